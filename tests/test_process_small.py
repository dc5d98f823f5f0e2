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


def test_a_smaller_map_of_a_stack_keeps_its_own_texel_density(tmp_path, capsys):
    """A 256 px colour map beside a 128 px roughness map: the roughness tile is written at half the colour tile's
    size (the same UV span at its own density, not upsampled), and check, reading it as it repeats, gives the
    verdict process gave."""
    from seamless_usd.pipeline.check import check_paths

    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    src = oiio.ImageBuf(str(SAMPLES / "textures" / "brick_roughness.png"))
    half = oiio.ImageBufAlgo.resize(src, roi=oiio.ROI(0, 128, 0, 128, 0, 1, 0, src.nchannels))
    assert half.write(str(tmp_path / "textures" / "brick_roughness.png"))
    code = main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--seeds", "1",
                 "--cache-dir", str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    sizes = {Path(m["asset"]).name: oiio.ImageInput.open(m["output"]).spec() for m in stack["maps"]}
    colour, rough = sizes["brick_albedo.png"], sizes["brick_roughness.png"]
    assert (colour.height, colour.width) == tuple(stack["tile_size"])
    assert abs(rough.width - colour.width / 2) <= 1 and abs(rough.height - colour.height / 2) <= 1
    [checked] = check_paths([tmp_path / "brick" / "scene.seamless.usda"]).items
    assert checked.passed == (stack["status"] == "passed") == (code == 0)
    assert checked.verdict["strongest"] == stack["verdict"]["strongest"]
    assert [s["position"] for s in checked.verdict["seams"]] == [s["position"] for s in stack["verdict"]["seams"]]
