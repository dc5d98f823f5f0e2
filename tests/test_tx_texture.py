"""A ``.tx`` source (a tiled, MIP-mapped TIFF, as maketx makes): its tile is a ``.tx`` texture too, with the same
sample type, colour space and MIP levels, so a renderer that reads only textures reads it."""
from __future__ import annotations

import json
from pathlib import Path

import OpenImageIO as oiio
from pxr import Usd

from seamless_usd.pipeline.check import check_paths
from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _levels(path: Path) -> int:
    inp = oiio.ImageInput.open(str(path))
    n = 0
    while inp.seek_subimage(0, n):
        n += 1
    inp.close()
    return n


def test_a_tx_source_gets_a_tx_tile(tmp_path, capsys):
    (tmp_path / "textures").mkdir()
    config = oiio.ImageSpec()
    source = oiio.ImageBuf(str(SAMPLES / "textures" / "brick_albedo.png"))
    assert oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, source, str(tmp_path / "textures" / "albedo.tx"), config)
    scene = (SAMPLES / "brick" / "scene.usda").read_text().replace("brick_albedo.png", "albedo.tx")
    (tmp_path / "brick").mkdir()
    (tmp_path / "brick" / "scene.usda").write_text(scene)
    for name in ("brick_normal.png", "brick_roughness.png"):
        (tmp_path / "textures" / name).write_bytes((SAMPLES / "textures" / name).read_bytes())
    code = main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--seeds", "1", "--cache-dir",
                 str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    tile = next(Path(m["output"]) for m in stack["maps"] if m["asset"].endswith("albedo.tx"))
    assert tile.suffix == ".tx"
    spec = oiio.ImageInput.open(str(tile)).spec()
    assert spec.tile_width > 0 and spec.getattribute("textureformat") and str(spec.format) == "uint8"
    assert spec.getattribute("oiio:ColorSpace").lower().startswith("srgb") and _levels(tile) > 3
    assert spec.get_string_attribute("wrapmodes") == "periodic,periodic"  # a tile: made to repeat (maketx: black)
    stage = Usd.Stage.Open(str(tmp_path / "brick" / "scene.seamless.usda"))
    authored = stage.GetPrimAtPath("/World/Looks/Brick/Albedo").GetAttribute("inputs:file").Get().resolvedPath
    assert Path(authored).resolve() == tile.resolve()
    [checked] = check_paths([tmp_path / "brick" / "scene.seamless.usda"]).items
    assert checked.passed == (stack["status"] == "passed") == (code == 0)
    [alone] = check_paths([tile]).items  # the record kept in the texture's description
    assert alone.verdict["reference"] == "source" and alone.passed == checked.passed
