"""End to end on sample types and alpha that PNG cannot hold: a signed 16-bit height map (values below zero), a
32-bit unsigned roughness, and a colour map whose TIFF stores colour multiplied by alpha. Each tile keeps its
source's sample type, its sign, its alpha as stored, and no colour label its source did not have."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Usd

from seamless_usd.imaging.io import read_info
from seamless_usd_cli.main import main

SIZE = 128
SCENE = """#usda 1.0
def Scope "Looks"
{
    def Material "M"
    {
        token outputs:surface.connect = </Looks/M/Surface.outputs:surface>
        token outputs:displacement.connect = </Looks/M/Surface.outputs:displacement>
        def Shader "Surface"
        {
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Looks/M/Albedo.outputs:rgb>
            float inputs:opacity.connect = </Looks/M/Albedo.outputs:a>
            float inputs:roughness.connect = </Looks/M/Roughness.outputs:r>
            float inputs:displacement.connect = </Looks/M/Height.outputs:r>
            token outputs:surface
            token outputs:displacement
        }
        def Shader "St"
        {
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st"
            float2 outputs:result
        }
        def Shader "Albedo"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./albedo.tif@
            token inputs:sourceColorSpace = "sRGB"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float3 outputs:rgb
            float outputs:a
        }
        def Shader "Roughness"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./roughness.tif@
            token inputs:sourceColorSpace = "raw"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float outputs:r
        }
        def Shader "Height"
        {
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./height.tif@
            token inputs:sourceColorSpace = "raw"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float outputs:r
        }
    }
}
"""


def _write(path: Path, values: np.ndarray, kind, associated: bool = False) -> None:
    """``values`` (H, W, C) as the reader gives them ([-1, 1] signed, [0, 1] unsigned), stored as ``kind``."""
    spec = oiio.ImageSpec(values.shape[1], values.shape[0], values.shape[2], kind)
    if values.shape[2] == 4:
        spec.alpha_channel = 3
        if not associated:
            spec.attribute("oiio:UnassociatedAlpha", 1)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(np.ascontiguousarray(values, dtype=np.float32)), out.geterror()
    out.close()


def _stored(path: Path) -> tuple[np.ndarray, oiio.ImageSpec]:
    """The values as stored (colour not divided by alpha), as floats, and the header."""
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)
    inp = oiio.ImageInput.open(str(path), config)
    spec = inp.spec()
    pixels = np.asarray(inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT))
    inp.close()
    return pixels.reshape(spec.height, spec.width, spec.nchannels), spec


def test_signed_32_bit_and_premultiplied_sources_keep_what_they_store(tmp_path, capsys):
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    rng = np.random.default_rng(3)
    bumps = np.sin(2 * np.pi * 3.3 * x + 1.0) * np.cos(2 * np.pi * 2.7 * y) + 0.2 * rng.normal(size=x.shape)
    height = np.clip(0.8 * bumps / np.abs(bumps).max(), -1, 1)[..., None]  # about half of it below zero
    rough = (0.3 + 0.4 * (bumps - bumps.min()) / np.ptp(bumps))[..., None]
    alpha = np.clip(0.5 + 0.5 * bumps, 0.05, 1.0)
    colour = np.stack([0.2 + 0.5 * alpha, 0.3 + 0.2 * x, 0.6 - 0.3 * alpha], axis=-1)
    _write(tmp_path / "height.tif", height, oiio.INT16)
    _write(tmp_path / "roughness.tif", rough, oiio.UINT32)
    _write(tmp_path / "albedo.tif", np.concatenate([colour * alpha[..., None], alpha[..., None]], -1), oiio.UINT8,
           associated=True)
    assert read_info(tmp_path / "albedo.tif").associated_alpha
    (tmp_path / "scene.usda").write_text(SCENE)

    code = main(["process", str(tmp_path / "scene.usda"), "--preset", "tiny", "--seeds", "1", "--json",
                 "--cache-dir", str(tmp_path / "cache")])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] in ("passed", "not-passed"), stack["message"]
    assert code == (0 if stack["status"] == "passed" else 1)
    tiles = {Path(m["asset"]).stem: Path(m["output"]) for m in stack["maps"]}
    stage = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    for node, name in (("Albedo", "albedo"), ("Roughness", "roughness"), ("Height", "height")):
        authored = stage.GetPrimAtPath(f"/Looks/M/{node}").GetAttribute("inputs:file").Get().resolvedPath
        assert Path(authored).resolve() == tiles[name].resolve() and tiles[name].suffix == ".tif", (name, authored)

    values, spec = _stored(tiles["height"])
    assert str(spec.format) == "int16" and spec.get_string_attribute("oiio:ColorSpace") == ""
    assert values.min() < -0.3 and (values < 0).mean() > 0.2  # the sign kept, not clipped to zero
    assert values.min() >= height.min() - 1e-3 and values.max() <= height.max() + 1e-3

    values, spec = _stored(tiles["roughness"])
    assert str(spec.format) == "uint" and abs(values.mean() - rough.mean()) < 0.05

    values, spec = _stored(tiles["albedo"])
    assert str(spec.format) == "uint8" and read_info(tiles["albedo"]).associated_alpha
    # colour stored multiplied by alpha, as in the source: never above its texel's alpha
    assert (values[..., :3] <= values[..., 3:] + 2 / 255).all()
    source, _ = _stored(tmp_path / "albedo.tif")
    assert abs(values[..., 0].mean() - source[..., 0].mean()) < 0.05


def test_a_multi_part_openexr_says_its_other_parts_are_not_in_the_tile(tmp_path, capsys):
    """An OpenEXR of two parts (the colour, and a mask part): the tile held the first only, and nothing said so."""
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    colour = np.stack([0.3 + 0.2 * np.sin(9 * x), 0.4 + 0.1 * np.cos(7 * y), 0.2 + 0.1 * x * y], -1)
    specs = [oiio.ImageSpec(SIZE, SIZE, 3, oiio.HALF), oiio.ImageSpec(SIZE, SIZE, 1, oiio.HALF)]
    specs[1].attribute("oiio:subimagename", "mask")
    path = tmp_path / "albedo.exr"
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), specs)
    assert out.write_image(colour.astype(np.float32))
    assert out.open(str(path), specs[1], "AppendSubimage") and out.write_image(np.ones((SIZE, SIZE, 1), np.float32))
    out.close()
    assert read_info(path).parts == 2
    scene = SCENE.replace("@./albedo.tif@", "@./albedo.exr@").replace('"sRGB"', '"raw"')
    scene = scene[:scene.index('        def Shader "Roughness"')] + "    }\n}\n"
    scene = scene.replace("            float inputs:opacity.connect = </Looks/M/Albedo.outputs:a>\n", "")
    scene = scene.replace("            float inputs:roughness.connect = </Looks/M/Roughness.outputs:r>\n", "")
    scene = scene.replace("            float inputs:displacement.connect = </Looks/M/Height.outputs:r>\n", "")
    (tmp_path / "scene.usda").write_text(scene)
    main(["process", str(tmp_path / "scene.usda"), "--preset", "tiny", "--seeds", "1", "--json", "--cache-dir",
          str(tmp_path / "cache")])
    payload = json.loads(capsys.readouterr().out)
    [said] = [f for f in payload["findings"] if f["code"] == "parts-not-kept"]
    assert "2 parts" in said["message"] and "albedo.exr" in said["where"]
