"""Discovery on the bundled sample scenes: roles, channels, authored locations, UV chains."""
from __future__ import annotations

from pathlib import Path

import pytest

from seamless_usd.discover import ColorSpace, Origin, scan_paths


def _maps(result):
    return {Path(m.resolved).name: m for s in result.stacks for m in s.maps}


def test_brick_albedo_normal_roughness(samples_dir):
    result = scan_paths([samples_dir / "brick" / "scene.usda"])
    assert result.materials == ["</World/Looks/Brick>"]
    assert len(result.stacks) == 1 and not result.findings
    stack = result.stacks[0]
    assert stack.uv.primvar == "st" and stack.uv.reader == "/World/Looks/Brick/StReader"
    maps = _maps(result)
    assert set(maps) == {"brick_albedo.png", "brick_normal.png", "brick_roughness.png"}
    albedo, normal, rough = maps["brick_albedo.png"], maps["brick_normal.png"], maps["brick_roughness.png"]
    assert [(r.role, r.channels) for r in albedo.roles] == [("diffuseColor", "rgb")]
    assert [(r.role, r.channels) for r in rough.roles] == [("roughness", "r")]
    assert normal.is_normal and normal.scale == (2.0, 2.0, 2.0, 1.0) and normal.bias == (-1.0, -1.0, -1.0, 0.0)
    assert not normal.normal_y_flip
    assert albedo.wrap_s == albedo.wrap_t == "repeat"
    assert albedo.origin is Origin.USD and albedo.node_type == "UsdUVTexture"
    assert albedo.asset == "../textures/brick_albedo.png"
    assert albedo.file_at.prim == "/World/Looks/Brick/Albedo" and albedo.file_at.attribute == "inputs:file"
    assert Path(albedo.file_at.layer) == (samples_dir / "brick" / "scene.usda").resolve()
    # image header, no pixels
    assert (albedo.image.width, albedo.image.height, albedo.image.channels, albedo.image.dtype) == (256, 256, 3, "uint8")
    assert albedo.image.file_format == "png" and rough.image.channels == 1
    assert albedo.color_space is ColorSpace.SRGB and albedo.color_space_reason.startswith("auto: file header")
    assert rough.color_space is ColorSpace.RAW and "sourceColorSpace" in rough.color_space_reason


def test_packed_orm_is_one_map_with_three_roles(samples_dir):
    maps = _maps(scan_paths([samples_dir / "orm" / "scene.usda"]))
    orm = maps["brick_orm.png"]
    assert {r.role: r.channels for r in orm.roles} == {"occlusion": "r", "roughness": "g", "metallic": "b"}
    assert orm.channels_used == "rgb" and orm.color_space is ColorSpace.RAW


def test_file_on_material_interface_input(samples_dir):
    result = scan_paths([samples_dir / "interface" / "scene.usda"])
    (cloth,) = [m for s in result.stacks for m in s.maps]
    assert cloth.node == "/World/Looks/Cloth/Color"
    assert cloth.file_at.prim == "/World/Looks/Cloth" and cloth.file_at.attribute == "inputs:colorMap"
    assert Path(cloth.resolved).name == "cloth.png"


def test_existing_transform2d_with_scale_on_interface_input(samples_dir):
    result = scan_paths([samples_dir / "transform2d" / "scene.usda"])
    (stack,) = result.stacks
    assert len(stack.maps) == 2
    assert stack.uv.primvar == "st"  # varname comes through inputs:frame:stPrimvarName
    (t,) = stack.uv.transforms
    assert t.kind == "UsdTransform2d" and t.node == "/World/Looks/Wood/Place"
    assert t.scale == (3.0, 3.0) and t.rotation == 90.0 and t.translation == (0.25, 0.0)
    authored = dict(t.authored)
    assert set(authored) == {"scale"}
    assert authored["scale"].prim == "/World/Looks/Wood" and authored["scale"].attribute == "inputs:tiling"


def test_material_in_referenced_layer_resolves_against_that_layer(samples_dir):
    result = scan_paths([samples_dir / "referenced" / "scene.usda"])
    assert result.materials == ["</World/Looks/Wood>"]
    maps = _maps(result)
    color = maps["wood_color.png"]
    assert color.asset == "../../textures/wood_color.png"
    assert Path(color.resolved) == (samples_dir / "textures" / "wood_color.png").resolve()
    assert Path(color.file_at.layer) == (samples_dir / "library" / "materials" / "wood.usda").resolve()
    assert color.file_at.prim == "/World/Looks/Wood/Color"  # the composed prim


def test_materialx_nodes_inside_usd(samples_dir):
    result = scan_paths([samples_dir / "usd_mtlx" / "scene.usda"])
    (stack,) = result.stacks
    maps = _maps(result)
    assert maps["brick_albedo.png"].node_type == "ND_image_color3"
    assert maps["brick_albedo.png"].color_space is ColorSpace.SRGB
    assert maps["brick_albedo.png"].color_space_reason.startswith("colorSpace metadata")
    orm = maps["brick_orm.png"]
    assert [(r.role, r.channels) for r in orm.roles] == [("specular_roughness", "g")]  # ND_extract index 1
    normal = maps["brick_normal.png"]
    assert normal.is_normal and normal.normal_y_flip and normal.color_space is ColorSpace.RAW
    assert stack.uv.primvar == "st" and stack.uv.reader == "/World/Looks/Brick/TexCoord"
    (place,) = stack.uv.transforms
    assert place.kind == "place2d" and place.scale == (2.0, 2.0)
    assert maps["brick_albedo.png"].wrap_s == "periodic"


@pytest.mark.parametrize("name", ["brick", "orm", "interface", "transform2d", "referenced", "usd_mtlx", "mtlx"])
def test_every_sample_scene_scans_clean(samples_dir, name):
    result = scan_paths([samples_dir / name / "scene.usda"])
    assert result.stacks and not [f for f in result.findings if f.severity.value != "warning"]
    for stack in result.stacks:
        for m in stack.maps:
            assert Path(m.resolved).is_file() and m.image is not None
