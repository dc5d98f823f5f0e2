"""End to end on real formats: a 16-bit PNG stack and a half-float EXR stack (linear, with a normal map)
go through ``seamless-usd process``.

Each written map keeps its source's sample type, channel count and colour-space metadata; every texel
of a refined or cut tile is exactly one of its source's texels (the tile is made through one coordinate
field into the source); decoded normals stay unit length.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from imagefiles import write_raw_image
from pxr import Usd, UsdShade

from seamless_usd_cli.main import main

SIZE = 128  # small (the minimum crop is 100 px): these tests are about formats, not quality

SCENE = """#usda 1.0
(
    defaultPrim = "Looks"
)
def Scope "Looks"
{{
    def Material "M"
    {{
        token outputs:surface.connect = </Looks/M/Surface.outputs:surface>
        def Shader "Surface"
        {{
            uniform token info:id = "UsdPreviewSurface"
            color3f inputs:diffuseColor.connect = </Looks/M/Albedo.outputs:rgb>
            normal3f inputs:normal.connect = </Looks/M/Normal.outputs:rgb>
            float inputs:roughness.connect = </Looks/M/Roughness.outputs:r>
            token outputs:surface
        }}
        def Shader "St"
        {{
            uniform token info:id = "UsdPrimvarReader_float2"
            string inputs:varname = "st"
            float2 outputs:result
        }}
        def Shader "Albedo"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./albedo.{ext}@
            token inputs:sourceColorSpace = "{albedo_space}"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float3 outputs:rgb
        }}
        def Shader "Normal"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./normal.{ext}@
            token inputs:sourceColorSpace = "raw"
            float4 inputs:scale = (2, 2, 2, 1)
            float4 inputs:bias = (-1, -1, -1, 0)
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float3 outputs:rgb
        }}
        def Shader "Roughness"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @./roughness.{ext}@
            token inputs:sourceColorSpace = "raw"
            float2 inputs:st.connect = </Looks/M/St.outputs:result>
            float outputs:r
        }}
    }}
}}
"""


def _source_maps(seed: int) -> dict[str, np.ndarray]:
    """Float maps in [0, 1] of a bumpy, non-tileable surface: albedo (3), normal (3, encoded), roughness (1)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    height = (np.sin(2 * np.pi * 3.3 * x + 1.0) * np.cos(2 * np.pi * 2.7 * y) + 0.6 * x  # not periodic
              + 0.3 * rng.normal(size=(SIZE, SIZE)))
    gy, gx = np.gradient(height)
    n = np.stack([-gx, -gy, np.full_like(gx, 0.5)], axis=-1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    h01 = (height - height.min()) / np.ptp(height)
    albedo = np.stack([0.2 + 0.6 * h01, 0.3 + 0.3 * h01, 0.5 - 0.3 * h01], axis=-1)
    rough = (0.25 + 0.5 * (1 - h01))[..., None]
    return {"albedo": albedo, "normal": n * 0.5 + 0.5, "roughness": rough}


def _icc_profile() -> bytes:
    """An RGB ICC profile as a photo editor embeds one (littleCMS's sRGB, through Pillow)."""
    from PIL import ImageCms

    return ImageCms.ImageCmsProfile(ImageCms.createProfile("sRGB")).tobytes()


ICC_PROFILE = _icc_profile()


def _write_stack(folder: Path, kind: str) -> None:
    folder.mkdir(parents=True)
    maps = _source_maps(seed=0 if kind == "png16" else 1)
    for name, values in maps.items():
        # the file's colour metadata agrees with the stage: sRGB for the PNG albedo, linear for the rest
        space = "srgb_rec709_scene" if (kind, name) == ("png16", "albedo") else "lin_rec709_scene"
        if kind == "png16":
            data = np.round(values * 65535).astype(np.uint16)
            write_raw_image(folder / f"{name}.png", data, color_space=space,
                            icc_profile=ICC_PROFILE if name == "albedo" else None)
        else:
            data = values.astype(np.float16)
            names = ("R", "G", "B") if data.shape[-1] == 3 else ("Y",)
            write_raw_image(folder / f"{name}.exr", data, names, color_space=space)
    ext, space = ("png", "sRGB") if kind == "png16" else ("exr", "raw")  # the EXR albedo is linear
    (folder / "scene.usda").write_text(SCENE.format(ext=ext, albedo_space=space))


def _read(path: Path) -> tuple[np.ndarray, oiio.ImageSpec]:
    inp = oiio.ImageInput.open(str(path))
    assert inp, oiio.geterror()
    spec = inp.spec()
    pixels = inp.read_image(spec.format)  # stored values, no conversion
    inp.close()
    return np.asarray(pixels).reshape(spec.height, spec.width, spec.nchannels), spec


@pytest.fixture(scope="module")
def processed(tmp_path_factory, model_cache):
    """Both stacks processed in one run (tiny preset, refinement on)."""
    root = tmp_path_factory.mktemp("formats")
    for kind in ("png16", "exr"):
        _write_stack(root / kind, kind)
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["process", str(root / "png16" / "scene.usda"), str(root / "exr" / "scene.usda"),
                     "--preset", "tiny", "--seeds", "1", "--cache-dir", str(model_cache), "--json"])
    payload = json.loads(out.getvalue())
    stacks = {Path(s["source"]).parent.name: s for s in payload["stacks"]}
    return root, code, payload, stacks


@pytest.mark.parametrize("kind", ["png16", "exr"])
def test_each_written_map_keeps_sample_type_channels_and_colour_space(processed, kind):
    root, code, payload, stacks = processed
    errors = [f for f in payload["findings"] if f["severity"] == "error"]
    assert not errors, errors
    stack = stacks[kind]
    assert stack["status"] in ("passed", "not-passed"), stack  # written either way
    assert len(stack["maps"]) == 3
    for m in stack["maps"]:
        name = Path(m["asset"]).stem
        source, src_spec = _read(root / kind / Path(m["asset"]).name)
        tile, spec = _read(Path(m["output"]))
        assert Path(m["output"]).suffix == Path(m["asset"]).suffix, m
        assert spec.format == src_spec.format, (name, str(spec.format), str(src_spec.format))
        assert spec.format == (oiio.UINT16 if kind == "png16" else oiio.HALF)
        assert spec.nchannels == src_spec.nchannels == source.shape[2], name
        assert tuple(spec.channelnames) == tuple(src_spec.channelnames), name
        expected_space = src_spec.get_string_attribute("oiio:ColorSpace")
        assert expected_space, f"{name}: the source file records a colour space"
        assert spec.get_string_attribute("oiio:ColorSpace") == expected_space, name
        # the embedded colour profile is kept where the format holds one (PNG, not OpenEXR)
        profile = spec.getattribute("ICCProfile")
        if (kind, name) == ("png16", "albedo"):
            assert profile is not None and bytes(np.asarray(profile, np.uint8)) == ICC_PROFILE, name
        else:
            assert profile is None, name
    # the stage points at the written files
    stage = Usd.Stage.Open(str(root / kind / "scene.seamless.usda"))
    for node in ("Albedo", "Normal", "Roughness"):
        value = UsdShade.Shader(stage.GetPrimAtPath(f"/Looks/M/{node}")).GetInput("file").Get()
        assert Path(value.resolvedPath).parent == root / kind / "tileable"


def _unit_normals_as_stored(codes: np.ndarray) -> np.ndarray:
    """Source normal texels made unit length and stored again (scale 2, bias -1), computed here in
    float64: the values a normal map's texels may take once written (the writer renormalises a vector
    further off unit than its stored codes allow; copies come back to the source's own codes)."""
    is_int = codes.dtype == np.uint16
    n = codes.astype(np.float64) / (65535.0 if is_int else 1.0) * 2.0 - 1.0
    n = n / np.linalg.norm(n, axis=-1, keepdims=True) * 0.5 + 0.5
    return np.round(n * 65535.0).astype(np.uint16) if is_int else n.astype(np.float16)


def _positions(source: np.ndarray, tile: np.ndarray) -> list[set[int]]:
    """For each tile texel, the flat source positions holding exactly that texel (empty: none)."""
    c = source.shape[2]
    where: dict[bytes, set[int]] = {}
    for i, texel in enumerate(np.ascontiguousarray(source).reshape(-1, c)):
        where.setdefault(texel.tobytes(), set()).add(i)
    return [where.get(texel.tobytes(), set()) for texel in np.ascontiguousarray(tile).reshape(-1, c)]


def _maps(root: Path, kind: str, stack: dict) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Map name -> (source texels, tile texels) as stored in the files."""
    return {Path(m["asset"]).stem: (_read(root / kind / Path(m["asset"]).name)[0], _read(Path(m["output"]))[0])
            for m in stack["maps"]}


@pytest.mark.parametrize("kind", ["png16", "exr"])
def test_every_texel_of_the_tile_is_a_source_texel(processed, kind):
    """Albedo and roughness exactly; the normal at the same source position up to one stored step (a copied
    normal is stored with the source's codes when it is unit to their precision, else made unit)."""
    root, _, _, stacks = processed
    gan = stacks[kind]["resampled"]["gan"]
    assert gan["refined"] or gan["layout"] == "lattice", gan  # refinement is on: texels come from the source
    maps = _maps(root, kind, stacks[kind])
    per_map = []
    for name in ("albedo", "roughness"):
        positions = _positions(*maps[name])
        missing = sum(not p for p in positions)
        assert missing == 0, f"{kind} {name}: {missing} of {len(positions)} tile texels are not source texels"
        per_map.append(positions)
    # the maps are copied through one coordinate field: each tile texel comes from one source position in all maps
    common = [a & b for a, b in zip(*per_map)]
    assert all(common), f"{sum(not c for c in common)} tile texels come from different source positions"
    source, tile = maps["normal"]
    expected = _unit_normals_as_stored(source).reshape(-1, 3).astype(np.float64)
    step = 1.0 if kind == "png16" else np.spacing(np.float16(1.0)).astype(np.float64)  # one stored step
    got = tile.reshape(-1, 3).astype(np.float64)
    off = [i for i, where in enumerate(common) if min(np.abs(expected[p] - got[i]).max() for p in where) > step]
    assert not off, f"{kind}: {len(off)} normal texels differ from the source's at the same position"


@pytest.mark.parametrize("kind", ["png16", "exr"])
def test_normal_texels_of_the_tile_are_exactly_source_texels(processed, kind):
    root, _, _, stacks = processed
    source, tile = _maps(root, kind, stacks[kind])["normal"]
    positions = _positions(source, tile)
    assert all(positions), f"{kind}: {sum(not p for p in positions)} of {len(positions)} normal texels are new"


@pytest.mark.parametrize("kind", ["png16", "exr"])
def test_normals_stay_unit_length(processed, kind):
    _, _, _, stacks = processed
    [m] = [m for m in stacks[kind]["maps"] if Path(m["asset"]).stem == "normal"]
    tile, spec = _read(Path(m["output"]))
    scale = 65535.0 if spec.format == oiio.UINT16 else 1.0
    n = tile.astype(np.float64) / scale * 2.0 - 1.0
    lengths = np.linalg.norm(n, axis=-1)
    tolerance = 1e-4 if kind == "png16" else 2e-3  # one code of quantisation: 16 bits, half
    assert np.abs(lengths - 1.0).max() < tolerance, (lengths.min(), lengths.max())
