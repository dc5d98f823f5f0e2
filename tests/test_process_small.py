"""Textures under SeamlessGAN's 100 px minimum crop (icons, 64 px game textures) get a tile cut from the source
instead of a skip: no GAN is trained, the cut is written, judged and reported as any other."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import OpenImageIO as oiio

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def test_a_64_px_brick_stack_gets_its_lattice_cut_without_training(tmp_path, capsys):
    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    (tmp_path / "textures").mkdir()
    for name in ("brick_albedo", "brick_normal", "brick_roughness"):  # the sample's maps at 64 px
        src = oiio.ImageBuf(str(SAMPLES / "textures" / f"{name}.png"))
        small = oiio.ImageBufAlgo.resize(src, roi=oiio.ROI(0, 64, 0, 64, 0, 1, 0, src.nchannels))
        assert small.write(str(tmp_path / "textures" / f"{name}.png"))
    code = main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--cache-dir",
                 str(tmp_path / "cache"), "--json"])
    report = json.loads(capsys.readouterr().out)
    [stack] = report["stacks"]
    gan = stack["resampled"]["gan"]
    assert stack["status"] in ("passed", "not-passed") and code == report["exit_code"]
    assert gan["layout"] in ("lattice", "window", "quilt") and "below 100 px" in gan["lattice"]["gan"]
    assert stack["q"] == {} and stack["model_hash"] == "" and "train" not in stack["timings"]
    for m in stack["maps"]:  # written at the cut's size, beside the scene
        spec = oiio.ImageInput.open(m["output"]).spec()
        assert (spec.height, spec.width) == tuple(stack["tile_size"]) and max(stack["tile_size"]) <= 64
    assert stack["verdict"]["size"] == list(stack["tile_size"])


def test_too_small_or_too_thin_stacks_fail_saying_why(tmp_path, capsys):
    """A 24 px stack, a 2048 x 32 strip (its short side would be 16 px where candidates are weighed) and a 512 x 128
    stack that --max-size 100 reduces to 100 x 25 px each fail with the reason and what to do, not an internal
    error; nothing is written for them."""
    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    (tmp_path / "textures").mkdir()
    cases = {"24": ((24, 24), []), "strip": ((2048, 32), []), "reduced": ((512, 128), ["--max-size", "100"])}
    for name, ((w, h), extra) in cases.items():
        for m in ("brick_albedo", "brick_normal", "brick_roughness"):
            src = oiio.ImageBuf(str(SAMPLES / "textures" / f"{m}.png"))
            small = oiio.ImageBufAlgo.resize(src, roi=oiio.ROI(0, w, 0, h, 0, 1, 0, src.nchannels))
            assert small.write(str(tmp_path / "textures" / f"{m}.png"))
        code = main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--force", "--cache-dir",
                     str(tmp_path / "cache"), "--json", *extra])
        [stack] = json.loads(capsys.readouterr().out)["stacks"]
        assert code == 1 and stack["status"] == "failed", (name, stack)
        assert stack["message"].startswith("too small to make a tile from") and "internal" not in stack["message"]
        assert {"24": "24 x 24 px", "strip": "long and thin", "reduced": "raise --max-size"}[name] in stack["message"]
        assert not (tmp_path / "brick" / "tileable").exists()
