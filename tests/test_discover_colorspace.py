"""Colour-space precedence (DESIGN.md) and the data-role-labelled-sRGB warning."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Sdf, Usd, UsdShade

from seamless_usd.discover import ColorSpace, scan_paths
from seamless_usd.discover.colorspace import Label, classify, resolve_color_space
from seamless_usd.discover.images import read_image_info
from seamless_usd.textures import ImageInfo

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def write_image(path: Path, channels: int = 3, dtype=oiio.UINT8, size: int = 128) -> str:
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(size, size, channels, dtype))
    out.write_image(np.full((size, size, channels), 0.25, np.float32))
    out.close()
    return str(path)


def scene(tmp_path: Path, file: str, role: str, *, source_cs: str | None = None, metadata: str | None = None,
          output: str = "rgb") -> Path:
    stage = Usd.Stage.CreateNew(str(tmp_path / "s.usda"))
    mat = UsdShade.Material.Define(stage, "/M")
    surf = UsdShade.Shader.Define(stage, "/M/S")
    surf.CreateIdAttr("UsdPreviewSurface")
    mat.CreateSurfaceOutput().ConnectToSource(surf.ConnectableAPI(), "surface")
    reader = UsdShade.Shader.Define(stage, "/M/St")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    tex = UsdShade.Shader.Define(stage, "/M/T")
    tex.CreateIdAttr("UsdUVTexture")
    file_in = tex.CreateInput("file", Sdf.ValueTypeNames.Asset)
    file_in.Set(file)
    if metadata:
        file_in.GetAttr().SetColorSpace(metadata)
    if source_cs:
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(source_cs)
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    surf.CreateInput(role, Sdf.ValueTypeNames.Float).ConnectToSource(tex.ConnectableAPI(), output)
    stage.Save()
    return tmp_path / "s.usda"


def _one(result):
    (stack,) = result.stacks
    (m,) = stack.maps
    return m


def test_source_color_space_beats_metadata_and_header(tmp_path):
    path = scene(tmp_path, str(TEXTURES / "brick_albedo.png"), "diffuseColor", source_cs="raw", metadata="srgb_texture")
    m = _one(scan_paths([path]))
    assert m.color_space is ColorSpace.RAW and m.color_space_reason.startswith("inputs:sourceColorSpace")


def test_metadata_used_when_source_color_space_is_auto(tmp_path):
    path = scene(tmp_path, str(TEXTURES / "brick_albedo.png"), "diffuseColor", source_cs="auto", metadata="lin_rec709")
    m = _one(scan_paths([path]))
    assert m.color_space is ColorSpace.RAW and m.color_space_reason.startswith("colorSpace metadata")


def test_auto_reads_the_png_header(tmp_path):
    m = _one(scan_paths([scene(tmp_path, str(TEXTURES / "brick_albedo.png"), "diffuseColor")]))
    assert m.color_space is ColorSpace.SRGB and m.color_space_reason == "auto: file header (srgb_rec709_scene)"


@pytest.mark.parametrize(
    "channels, dtype, expected",
    [(3, oiio.UINT8, ColorSpace.SRGB), (4, oiio.UINT8, ColorSpace.SRGB), (1, oiio.UINT8, ColorSpace.RAW),
     (3, oiio.UINT16, ColorSpace.RAW)],
)
def test_auto_without_header_srgb_only_for_8bit_rgb_or_rgba(tmp_path, channels, dtype, expected):
    # TIFF written by OpenImageIO states no colour space, so the 8-bit rule decides
    file = write_image(tmp_path / "t.tif", channels, dtype)
    assert read_image_info(file).color_space is None
    m = _one(scan_paths([scene(tmp_path, file, "diffuseColor", output="rgb" if channels > 1 else "r")]))
    assert m.color_space is expected and m.color_space_reason.startswith("auto: ")


def test_float_exr_is_raw(tmp_path):
    m = _one(scan_paths([scene(tmp_path, str(TEXTURES / "brick_albedo_linear.exr"), "diffuseColor")]))
    assert m.color_space is ColorSpace.RAW and m.image.dtype == "half"


def test_data_role_labelled_srgb_is_kept_and_warned(tmp_path):
    path = scene(tmp_path, str(TEXTURES / "brick_roughness.png"), "roughness", source_cs="sRGB", output="r")
    result = scan_paths([path])
    m = _one(result)
    assert m.color_space is ColorSpace.SRGB  # not silently changed
    (warning,) = result.findings
    assert warning.severity.value == "warning" and warning.code == "colorspace-mismatch"
    assert "roughness" in warning.message and "</M/T>" in warning.where


def test_data_role_labelled_srgb_by_file_header_is_warned(tmp_path):
    # a roughness PNG with an sRGB chunk: with auto that is what the renderer uses, so it is kept and warned
    import OpenImageIO as oiio

    tagged = tmp_path / "rough_srgb.png"
    buf = oiio.ImageBuf(str(TEXTURES / "brick_roughness.png"))
    buf.specmod().attribute("oiio:ColorSpace", "srgb_rec709_scene")
    assert buf.write(str(tagged))
    result = scan_paths([scene(tmp_path, str(tagged), "roughness", output="r")])
    assert _one(result).color_space is ColorSpace.SRGB
    assert [f.code for f in result.findings] == ["colorspace-mismatch"]


def test_sample_data_maps_carry_no_srgb_chunk_and_read_as_raw_under_auto(tmp_path):
    result = scan_paths([scene(tmp_path, str(TEXTURES / "brick_roughness.png"), "roughness", output="r")])
    assert _one(result).color_space is ColorSpace.RAW
    assert result.findings == []


def test_unknown_colour_space_name_is_passed_over_with_a_warning(tmp_path):
    path = scene(tmp_path, str(TEXTURES / "brick_albedo.png"), "diffuseColor", metadata="my_studio_space")
    result = scan_paths([path])
    assert _one(result).color_space_reason.startswith("auto")
    assert [f.code for f in result.findings] == ["unknown-colorspace"]


def test_a_source_colour_space_the_texture_node_does_not_take_is_named_and_read_as_auto(tmp_path):
    """UsdUVTexture's sourceColorSpace takes raw, sRGB or auto: "linear" is passed over as a renderer passes it over
    (the file decides), with a warning naming it, not silently."""
    path = scene(tmp_path, str(TEXTURES / "brick_roughness.png"), "roughness", source_cs="linear", output="r")
    result = scan_paths([path])
    assert _one(result).color_space_reason.startswith("auto")
    [finding] = result.findings
    assert finding.code == "unknown-colorspace" and "'linear'" in finding.message


def test_classify_names():
    assert classify("sRGB") is ColorSpace.SRGB and classify("srgb_texture") is ColorSpace.SRGB
    assert classify("raw") is ColorSpace.RAW and classify("lin_rec709") is ColorSpace.RAW
    assert classify("ACEScg") is ColorSpace.RAW and classify("auto") is None and classify("") is None


def test_resolve_order_skips_auto_labels():
    info = ImageInfo(64, 64, 1, "uint8", "png", ("Y",), None)
    cs, reason, unknown = resolve_color_space(
        [Label("auto", "inputs:sourceColorSpace"), Label("srgb_texture", "MaterialX colorspace")], info
    )
    assert cs is ColorSpace.SRGB and reason.startswith("MaterialX colorspace") and unknown == []


def test_opacity_from_the_alpha_of_an_srgb_map_is_not_warned():
    """The sRGB curve applies to red, green and blue only: opacity read from alpha is linear either way."""
    from seamless_usd.discover.colorspace import mismatch_finding
    from seamless_usd.textures import RoleUse

    alpha = RoleUse("opacity", "a", "</M/S.inputs:opacity>")
    colour = RoleUse("diffuseColor", "rgb", "</M/S.inputs:diffuseColor>")
    assert mismatch_finding((colour, alpha), ColorSpace.SRGB, "inputs:sourceColorSpace", "</M/T>") is None
    red = RoleUse("opacity", "r", "</M/S.inputs:opacity>")
    assert mismatch_finding((red,), ColorSpace.SRGB, "inputs:sourceColorSpace", "</M/T>") is not None


def test_materialx_image_nodes_in_usd_follow_materialx_rules_as_in_a_document(tmp_path):
    """A float or vector image is never colour-transformed by MaterialX: authored in USD (ND_image_vector3 for a
    normal, ND_image_float for a roughness) its 8-bit RGB file read as sRGB by the USD 'auto' rule, with a warning
    the user could not act on (these nodes have no sourceColorSpace); the same network in a .mtlx read raw."""
    files = {name: write_image(tmp_path / f"{name}.png") for name in ("normal", "rough", "albedo")}
    stage = Usd.Stage.CreateNew(str(tmp_path / "mx.usda"))
    mat = UsdShade.Material.Define(stage, "/M")
    surface = UsdShade.Shader.Define(stage, "/M/SS")
    surface.CreateIdAttr("ND_standard_surface_surfaceshader")
    mat.CreateOutput("mtlx:surface", Sdf.ValueTypeNames.Token).ConnectToSource(
        surface.CreateOutput("out", Sdf.ValueTypeNames.Token))
    for node, sid, role, vtype in (("N", "ND_image_vector3", "normal", Sdf.ValueTypeNames.Float3),
                                   ("R", "ND_image_float", "specular_roughness", Sdf.ValueTypeNames.Float),
                                   ("A", "ND_image_color3", "base_color", Sdf.ValueTypeNames.Color3f)):
        image = UsdShade.Shader.Define(stage, f"/M/{node}")
        image.CreateIdAttr(sid)
        image.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(files[{"N": "normal", "R": "rough", "A": "albedo"}[node]])
        surface.CreateInput(role, vtype).ConnectToSource(image.CreateOutput("out", vtype))
    stage.Save()
    result = scan_paths([tmp_path / "mx.usda"])
    maps = {Path(m.asset).stem: m for s in result.stacks for m in s.maps}
    assert maps["normal"].color_space is ColorSpace.RAW and maps["rough"].color_space is ColorSpace.RAW
    assert "MaterialX vector3 image, never colour-transformed" in maps["normal"].color_space_reason
    assert maps["albedo"].color_space is ColorSpace.SRGB  # a colour image: the USD rule for an 8-bit RGB file
    assert not [f for f in result.findings if f.code == "colorspace-mismatch"]
