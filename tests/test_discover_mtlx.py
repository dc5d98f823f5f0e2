"""Discovery of MaterialX documents: given directly, referenced from USD, fileprefix, tiling."""
from __future__ import annotations

from pathlib import Path

import pytest

from seamless_usd.discover import ColorSpace, Origin, scan_mtlx, scan_paths
from seamless_usd.errors import InputError

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def _maps(result):
    return {Path(m.resolved).name: m for s in result.stacks for m in s.maps}


def test_tiledimage_with_uvtiling_is_one_stack(samples_dir):
    result = scan_mtlx(samples_dir / "mtlx" / "tiled.mtlx")
    assert result.materials == ["<M_wood>"]
    (stack,) = result.stacks
    maps = _maps(result)
    color, rough = maps["wood_color.png"], maps["wood_roughness.png"]
    assert color.origin is Origin.MTLX and color.node_type == "ND_tiledimage_color3"
    assert color.document == str((samples_dir / "mtlx" / "tiled.mtlx").resolve())
    assert color.file_at.prim == "NG_wood/wood_color" and color.file_at.attribute == "file"
    assert color.uv.primvar == "UV0" and color.uv.reader == "NG_wood/uv0"
    (tiling,) = color.uv.transforms
    assert tiling.kind == "uvtiling" and tiling.scale == (2.0, 2.0) and tiling.node == "NG_wood/wood_color"
    assert color.wrap_s == "periodic"
    assert color.color_space is ColorSpace.SRGB and "srgb_texture" in color.color_space_reason
    # a float image: MaterialX transforms colour images only
    assert rough.color_space is ColorSpace.RAW and "never colour-transformed" in rough.color_space_reason
    assert [(r.role, r.channels) for r in rough.roles] == [("specular_roughness", "r")]


def test_fileprefix_on_document_and_nodegraph(samples_dir):
    result = scan_mtlx(samples_dir / "mtlx" / "prefixed.mtlx")
    maps = _maps(result)
    assert set(maps) == {"brick_albedo.png", "brick_orm.png", "brick_normal.png"}
    assert maps["brick_albedo.png"].asset == "brick_albedo.png"  # as authored; the prefix is the document's
    assert maps["brick_orm.png"].asset == "orm.png"  # nodegraph prefix "../textures/brick_" wins
    assert {r.role: r.channels for r in maps["brick_orm.png"].roles} == {"specular_roughness": "g", "metalness": "b"}
    assert maps["brick_normal.png"].is_normal and not maps["brick_normal.png"].normal_y_flip
    assert not result.findings


def test_mtlx_referenced_from_usd_is_attached_to_the_prim(samples_dir):
    result = scan_paths([samples_dir / "mtlx" / "scene.usda"])
    assert "</World/Looks/Wood>" in result.materials
    (stack,) = result.stacks
    assert stack.material == "</World/Looks/Wood>"
    assert all(m.origin is Origin.MTLX and m.document.endswith("tiled.mtlx") for m in stack.maps)
    assert str((samples_dir / "mtlx" / "tiled.mtlx").resolve()) in result.sources


def test_whole_document_reference_puts_materials_under_the_prim(tmp_path, samples_dir):
    (tmp_path / "scene.usda").write_text(
        "#usda 1.0\n"
        f'def Scope "Looks" (references = @{samples_dir / "mtlx" / "prefixed.mtlx"}@) {{}}\n'
    )
    result = scan_paths([tmp_path / "scene.usda"])
    assert result.materials == ["</Looks/Materials/M_brick>"]
    assert len(result.stacks) == 1


def _write(path: Path, body: str) -> Path:
    path.write_text(f'<?xml version="1.0"?>\n<materialx version="1.39">\n{body}\n</materialx>\n')
    return path


def test_file_on_nodegraph_interface_input_and_place2d(tmp_path):
    doc = _write(
        tmp_path / "iface.mtlx",
        f"""
  <nodegraph name="NG">
    <input name="albedo_file" type="filename" value="{TEXTURES / 'cloth.png'}" />
    <input name="tiling" type="vector2" value="4, 4" />
    <geompropvalue name="uvs" type="vector2"><input name="geomprop" type="string" value="st" /></geompropvalue>
    <place2d name="place" type="vector2">
      <input name="texcoord" type="vector2" nodename="uvs" />
      <input name="scale" type="vector2" interfacename="tiling" />
      <input name="rotate" type="float" value="30" />
    </place2d>
    <image name="img" type="color3">
      <input name="file" type="filename" interfacename="albedo_file" />
      <input name="texcoord" type="vector2" nodename="place" />
      <input name="uaddressmode" type="string" value="clamp" />
    </image>
    <output name="out" type="color3" nodename="img" />
  </nodegraph>
  <gltf_pbr name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG" output="out" />
  </gltf_pbr>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>""",
    )
    result = scan_mtlx(doc)
    (m,) = [m for s in result.stacks for m in s.maps]
    assert m.file_at.prim == "NG" and m.file_at.attribute == "albedo_file"
    assert m.uv.primvar == "st" and m.uv.reader == "NG/uvs"
    (place,) = m.uv.transforms
    assert place.kind == "place2d" and place.scale == (4.0, 4.0) and place.rotation == 30.0
    assert dict(place.authored)["scale"].prim == "NG"
    assert m.wrap_s == "clamp" and m.wrap_t == "periodic"
    # no colorspace anywhere: auto from the PNG header
    assert m.color_space_reason.startswith("auto")


def test_gltf_colorimage_and_separate4_alpha(tmp_path):
    doc = _write(
        tmp_path / "gltf.mtlx",
        f"""
  <gltf_colorimage name="base" type="multioutput">
    <input name="file" type="filename" value="{TEXTURES / 'brick_albedo.png'}" />
  </gltf_colorimage>
  <gltf_image name="orm" type="vector3">
    <input name="file" type="filename" value="{TEXTURES / 'brick_orm.png'}" />
  </gltf_image>
  <separate3 name="split" type="multioutput"><input name="in" type="vector3" nodename="orm" /></separate3>
  <gltf_pbr name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodename="base" output="outcolor" />
    <input name="alpha" type="float" nodename="base" output="outa" />
    <input name="occlusion" type="float" nodename="split" output="outx" />
    <input name="roughness" type="float" nodename="split" output="outy" />
  </gltf_pbr>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>""",
    )
    maps = _maps(scan_mtlx(doc))
    assert {r.role: r.channels for r in maps["brick_albedo.png"].roles} == {"base_color": "rgb", "alpha": "a"}
    assert {r.role: r.channels for r in maps["brick_orm.png"].roles} == {"occlusion": "r", "roughness": "g"}
    assert maps["brick_orm.png"].node_type == "ND_gltf_image_vector3_vector3_1_0"


def test_unreadable_document_raises_input_error_naming_it(tmp_path):
    bad = tmp_path / "bad.mtlx"
    bad.write_text("<materialx version='1.39'><image name='x' type='color3'>")
    with pytest.raises(InputError, match="bad.mtlx"):
        scan_mtlx(bad)
    with pytest.raises(InputError, match="absent.mtlx"):
        scan_paths([tmp_path / "absent.mtlx"])


def test_missing_referenced_document_is_skipped(tmp_path):
    (tmp_path / "scene.usda").write_text('#usda 1.0\ndef Material "M" (references = @./gone.mtlx@) {}\n')
    result = scan_paths([tmp_path / "scene.usda"])
    (f,) = result.findings
    assert f.code == "missing-file" and "</M>" in f.where and "@./gone.mtlx@" in f.where


def test_a_colour_space_stated_on_the_interface_input_that_holds_the_file(tmp_path):
    """The document says linear, the node graph's interface input holding the file name says sRGB: the map is
    sRGB (the inherited colour space does not hide the one stated where the value is)."""
    import shutil

    shutil.copyfile(TEXTURES / "brick_albedo.png", tmp_path / "brick_albedo.png")
    (tmp_path / "look.mtlx").write_text("""<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="NG">
    <input name="albedo_file" type="filename" value="brick_albedo.png" colorspace="srgb_texture" />
    <image name="albedo" type="color3">
      <input name="file" type="filename" interfacename="albedo_file" />
    </image>
    <output name="c" type="color3" nodename="albedo" />
  </nodegraph>
  <standard_surface name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG" output="c" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>
</materialx>
""")
    [stack] = scan_mtlx(tmp_path / "look.mtlx").stacks
    assert stack.maps[0].color_space is ColorSpace.SRGB and "srgb_texture" in stack.maps[0].color_space_reason


def test_a_node_of_the_documents_own_definition_that_takes_a_file_is_named_and_its_material_left_alone(tmp_path):
    """A studio's definition wrapping ``image`` (its nodegraph implements a nodedef the document declares): the
    material was listed without stacks and no finding, its roughness beside it would have been tiled alone."""
    doc = _write(tmp_path / "custom.mtlx", """
  <nodedef name="ND_mytex_color3" node="mytex"><input name="file" type="filename" value="" uniform="true" />
    <output name="out" type="color3" /></nodedef>
  <nodegraph name="NG_mytex_color3" nodedef="ND_mytex_color3">
    <image name="img" type="color3"><input name="file" type="filename" interfacename="file" /></image>
    <output name="out" type="color3" nodename="img" /></nodegraph>
  <mytex name="wood_tex" type="color3"><input name="file" type="filename" value="wood.png" /></mytex>
  <image name="rough" type="float"><input name="file" type="filename" value="rough.png" /></image>
  <standard_surface name="SR" type="surfaceshader"><input name="base_color" type="color3" nodename="wood_tex" />
    <input name="specular_roughness" type="float" nodename="rough" /></standard_surface>
  <surfacematerial name="M" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>""")
    import shutil

    shutil.copyfile(Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "brick_roughness.png",
                    tmp_path / "rough.png")
    result = scan_mtlx(doc)
    [found] = [f for f in result.findings if f.code == "file-node-not-read"]
    assert found.where == "<wood_tex> @wood.png@" and found.material == "<M>"
    assert "ND_mytex_color3" in found.message and "flattenSubgraphs" in found.message
    from seamless_usd.discover.select import set_aside_stacks

    [stack] = result.stacks  # the roughness: left alone, not tiled without the albedo
    assert set_aside_stacks(result, [stack], str(doc))


def test_vector_images_are_read_as_stored_whatever_the_file_header_says(tmp_path):
    """MaterialX applies a colour transform to color3 / color4 images only. A vector3 normal map and a packed
    vector3 ORM in a document with no colorspace, their PNGs carrying sRGB chunks, were decoded as sRGB (the rule
    for UsdUVTexture's auto): the normals tilted and the stack failed. They are read as stored; the colour map, a
    color3 with no colorspace, keeps what its file's header says."""
    import shutil

    from seamless_usd.discover import scan_paths

    textures = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
    for name in ("brick_albedo.png", "brick_normal.png", "brick_orm.png"):
        shutil.copy(textures / name, tmp_path / name)
    for name in ("brick_normal.png", "brick_orm.png"):  # saved by an editor that tags every PNG sRGB
        _tag_srgb(tmp_path / name)
    (tmp_path / "look.mtlx").write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <image name="albedo" type="color3"><input name="file" type="filename" value="brick_albedo.png" /></image>
  <image name="orm" type="vector3"><input name="file" type="filename" value="brick_orm.png" /></image>
  <separate3 name="orm_split" type="multioutput"><input name="in" type="vector3" nodename="orm" /></separate3>
  <image name="normal" type="vector3"><input name="file" type="filename" value="brick_normal.png" /></image>
  <normalmap name="nmap" type="vector3"><input name="in" type="vector3" nodename="normal" /></normalmap>
  <standard_surface name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodename="albedo" />
    <input name="specular_roughness" type="float" nodename="orm_split" output="outy" />
    <input name="normal" type="vector3" nodename="nmap" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>
</materialx>
""")
    result = scan_paths([tmp_path / "look.mtlx"])
    maps = {Path(m.resolved).name: m for s in result.stacks for m in s.maps}
    assert maps["brick_albedo.png"].color_space is ColorSpace.SRGB
    for name in ("brick_normal.png", "brick_orm.png"):
        assert maps[name].color_space is ColorSpace.RAW, (name, maps[name].color_space_reason)
        assert "vector3 image, never colour-transformed" in maps[name].color_space_reason
    assert not [f for f in result.findings if f.code == "colorspace-mismatch"], result.findings


def _tag_srgb(path: Path) -> None:
    """Rewrite the PNG at ``path`` with an sRGB chunk, as most image editors save one."""
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(str(path))
    buf.specmod().attribute("oiio:ColorSpace", "srgb_rec709_scene")
    assert buf.write(str(path) + ".tmp.png")
    Path(str(path) + ".tmp.png").replace(path)


def test_a_document_that_does_not_validate_is_said(tmp_path):
    """A shader input naming a node graph or node that is not there read as a material with no textures, and the
    scan said nothing (exit 0): MaterialX's own validation is now a warning naming what it found."""
    (tmp_path / "bad.mtlx").write_text("""<?xml version="1.0"?>
<materialx version="1.39">
  <standard_surface name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG_missing" output="out" />
    <input name="specular_roughness" type="float" nodename="nonode" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>
</materialx>
""")
    result = scan_mtlx(tmp_path / "bad.mtlx")
    [said] = [f for f in result.findings if f.code == "mtlx-invalid"]
    assert "NG_missing" in said.message and "nonode" in said.message
    samples = Path(__file__).resolve().parents[1] / "sample_assets" / "mtlx"
    assert not [f for f in scan_mtlx(samples / "tiled.mtlx").findings if f.code == "mtlx-invalid"]
