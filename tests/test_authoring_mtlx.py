"""Authoring into MaterialX documents written by the tests: files, address modes, uvtiling, place2d."""
from __future__ import annotations

import hashlib
from pathlib import Path

import MaterialX as mx
import pytest

from seamless_usd.authoring import (
    Affine2,
    MapResult,
    Provenance,
    StackResult,
    WriteMode,
    author_mtlx,
    place2d,
    read_mtlx_provenance,
    scale2d,
    uv_scale_for,
)
from seamless_usd.textures import AuthoredAt, ColorSpace, Origin, RoleUse, TextureMap, TextureStack, UVChain

SCALE = uv_scale_for((512, 768), (64, 128))  # (4, 3)

DOC = """<?xml version="1.0"?>
<materialx version="1.39" fileprefix="textures/">
  <nodegraph name="NG_brick">
    <input name="albedo_file" type="filename" value="brick albedo é.png" />
    <texcoord name="uv" type="vector2" />
    <place2d name="place" type="vector2">
      <input name="texcoord" type="vector2" nodename="uv" />
      <input name="scale" type="vector2" value="0.5, 2" />
      <input name="rotate" type="float" value="30" />
      <input name="offset" type="vector2" value="0.1, 0.2" />
      <input name="pivot" type="vector2" value="0.5, 0.5" />
    </place2d>
    <image name="image_color" type="color3">
      <input name="file" type="filename" interfacename="albedo_file" />
      <input name="texcoord" type="vector2" nodename="place" />
      <input name="uaddressmode" type="string" value="clamp" />
    </image>
    <tiledimage name="tiled_rough" type="float">
      <input name="file" type="filename" value="rough.png" />
      <input name="uvtiling" type="vector2" value="2, 3" />
      <input name="uvoffset" type="vector2" value="0.5, 0.25" />
    </tiledimage>
    <output name="out_color" type="color3" nodename="image_color" />
    <output name="out_rough" type="float" nodename="tiled_rough" />
  </nodegraph>
  <standard_surface name="SR_brick" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG_brick" output="out_color" />
    <input name="specular_roughness" type="float" nodegraph="NG_brick" output="out_rough" />
  </standard_surface>
  <surfacematerial name="M_brick" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_brick" />
  </surfacematerial>
</materialx>
"""


@pytest.fixture()
def document(tmp_path: Path) -> Path:
    path = tmp_path / "brick.mtlx"
    path.write_text(DOC, encoding="utf-8")
    (tmp_path / "textures").mkdir()
    for name in ("brick albedo é.png", "rough.png"):
        (tmp_path / "textures" / name).write_bytes(b"source")
    (tmp_path / "tileable").mkdir()
    for name in ("albedo.M_brick-0123456789.tile.png", "rough.M_brick-0123456789.tile.png"):
        (tmp_path / "tileable" / name).write_bytes(b"tile")
    return path


def mtlx_map(doc: Path, node: str, source: str, file_at: AuthoredAt) -> TextureMap:
    return TextureMap(
        material="M_brick", node=node, node_type="ND_image_color3", origin=Origin.MTLX,
        asset=source, resolved=str(doc.parent / "textures" / source), file_at=file_at,
        roles=(RoleUse("base_color", "rgb", "SR_brick.base_color"),), color_space=ColorSpace.SRGB,
        color_space_reason="test", uv=UVChain("UV0", None), document=str(doc),
    )


def results(doc: Path) -> list[StackResult]:
    albedo = mtlx_map(doc, "NG_brick/image_color", "brick albedo é.png",
                      AuthoredAt("NG_brick", "albedo_file", str(doc)))
    rough = mtlx_map(doc, "NG_brick/tiled_rough", "rough.png",
                     AuthoredAt("NG_brick/tiled_rough", "file", str(doc)))
    prov = Provenance("textures/brick albedo é.png", (64, 128), SCALE, False, 0.3, (0.1, 0.2), "h", "0.1.0")
    out = doc.parent / "tileable"
    return [
        StackResult(TextureStack("M_brick", albedo.uv, (albedo,)),
                    [MapResult(albedo, out / "albedo.M_brick-0123456789.tile.png")], SCALE, prov),
        StackResult(TextureStack("M_brick", rough.uv, (rough,)),
                    [MapResult(rough, out / "rough.M_brick-0123456789.tile.png")], SCALE, prov),
    ]


def read(path: Path) -> mx.Document:
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    return doc


def chain(doc: mx.Document, node_path: str) -> Affine2:
    """The affine map from UV0 to the UVs the node samples with (place2d chain, tiledimage)."""
    node = doc.getDescendant(node_path)
    total = Affine2()
    if node.getCategory() == "tiledimage":
        t, o = node.getInputValue("uvtiling"), node.getInputValue("uvoffset")
        total = Affine2(a=t[0], d=t[1], tx=-o[0], ty=-o[1])
    steps = []
    upstream = node.getInput("texcoord").getConnectedNode() if node.getInput("texcoord") else None
    while upstream is not None and upstream.getCategory() == "place2d":
        def val(name, default):
            v = upstream.getInputValue(name)
            return default if v is None else (tuple(v) if not isinstance(v, (int, float)) else v)
        steps.append(place2d(val("pivot", (0.0, 0.0)), val("scale", (1.0, 1.0)), val("rotate", 0.0),
                             val("offset", (0.0, 0.0)), val("operationorder", 0)))
        inp = upstream.getInput("texcoord")
        upstream = inp.getConnectedNode() if inp is not None else None
    out = Affine2()
    for step in reversed(steps):
        out = out.then(step)
    return out.then(total)


def test_new_document_with_paths_address_modes_and_uv(document: Path):
    before = hashlib.sha256(document.read_bytes()).hexdigest()
    result = author_mtlx(document, results(document))
    assert result.output == document.with_name("brick.seamless.mtlx")
    assert result.layers_written == [result.output]
    assert hashlib.sha256(document.read_bytes()).hexdigest() == before
    old, new = read(document), read(result.output)
    valid, message = new.validate()
    assert valid, message
    # files resolve (through fileprefix) to the tiles, relative to the new document
    albedo_file = new.getDescendant("NG_brick/albedo_file")
    assert (result.output.parent / albedo_file.getResolvedValueString()).resolve() == \
        (document.parent / "tileable" / "albedo.M_brick-0123456789.tile.png").resolve()
    rough_file = new.getDescendant("NG_brick/tiled_rough").getInput("file")
    assert (result.output.parent / rough_file.getResolvedValueString()).resolve() == \
        (document.parent / "tileable" / "rough.M_brick-0123456789.tile.png").resolve()
    image = new.getDescendant("NG_brick/image_color")
    assert image.getInputValue("uaddressmode") == "periodic"
    assert image.getInputValue("vaddressmode") == "periodic"
    # tiledimage: uvtiling and uvoffset scaled; image: a place2d after the existing one
    tiled = new.getDescendant("NG_brick/tiled_rough")
    assert tuple(tiled.getInputValue("uvtiling")) == pytest.approx((8.0, 9.0))
    assert tuple(tiled.getInputValue("uvoffset")) == pytest.approx((2.0, 0.75))
    for node in ("NG_brick/image_color", "NG_brick/tiled_rough"):
        # MaterialX holds vector2 values in float32 (1/3 is not exact): compare at float precision
        assert chain(new, node).close_to(chain(old, node).then(scale2d(SCALE)), tol=1e-6)
    added = image.getInput("texcoord").getConnectedNode()
    assert added.getName() == "seamless_uv" and added.getCategory() == "place2d"
    assert added.getInput("texcoord").getNodeName() == "place"
    recorded = read_mtlx_provenance(image)
    assert recorded.uv_scale == pytest.approx(SCALE) and recorded.crop_size == (64, 128)
    assert not recorded.q_passed


def test_rerun_on_new_document_is_a_no_op(document: Path):
    first = author_mtlx(document, results(document))
    text = first.output.read_text(encoding="utf-8")
    again = author_mtlx(first.output, [_retarget(r, first.output) for r in results(document)],
                        output_path=first.output.with_name("again.mtlx"))
    assert again.layers_written == [] and again.plan == []
    assert first.output.read_text(encoding="utf-8") == text
    new = read(first.output)
    assert len([n for n in new.getDescendant("NG_brick").getNodes() if n.getCategory() == "place2d"]) == 2


def _retarget(result: StackResult, doc: Path) -> StackResult:
    from dataclasses import replace

    maps = [MapResult(replace(m.map, document=str(doc),
                              file_at=replace(m.map.file_at, layer=str(doc))), m.output_path)
            for m in result.maps]
    return replace(result, maps=maps)


def test_in_place_keeps_backup_and_dry_run_writes_nothing(document: Path):
    original = document.read_bytes()
    dry = author_mtlx(document, results(document), mode=WriteMode.DRY_RUN)
    assert dry.dry_run and dry.plan and dry.layers_written == []
    # the provenance is one line per node, not values a dry run has not measured yet
    assert not [line for line in dry.plan if ".seamless_" in line]
    assert any(line.startswith("record the tile's provenance") for line in dry.plan)
    assert sorted(p.name for p in document.parent.iterdir()) == ["brick.mtlx", "textures", "tileable"]
    result = author_mtlx(document, results(document), mode=WriteMode.IN_PLACE)
    assert result.layers_written == [document]
    assert result.backups == [document.with_name("brick.mtlx.bak")]
    assert result.backups[0].read_bytes() == original
    in_place = read(document)
    tiled = in_place.getDescendant("NG_brick/tiled_rough")
    assert tuple(tiled.getInputValue("uvtiling")) == pytest.approx((8.0, 9.0))


def test_new_document_in_another_folder_rebases_paths(document: Path):
    out = document.parent / "out" / "brick.mtlx"
    result = author_mtlx(document, results(document), output_path=out)
    new = read(out)
    image_file = new.getDescendant("NG_brick/albedo_file").getResolvedValueString()
    assert (out.parent / image_file).resolve() == (document.parent / "tileable" / "albedo.M_brick-0123456789.tile.png").resolve()
    assert result.layers_written == [out]


def test_rerun_on_processed_tiles_composes_without_a_second_place2d(document: Path):
    first = author_mtlx(document, results(document))
    tiles = {"NG_brick/image_color": "albedo.M_brick-0123456789.tile.png", "NG_brick/tiled_rough": "rough.M_brick-0123456789.tile.png"}
    from dataclasses import replace

    # the pipeline processed the tiles themselves this time, with a UV scale of (2, 1)
    again_results = []
    for r in results(document):
        maps = [MapResult(replace(m.map, document=str(first.output),
                                  resolved=str(document.parent / "tileable" / tiles[m.map.node]),
                                  file_at=replace(m.map.file_at, layer=str(first.output))),
                          m.output_path) for m in r.maps]
        again_results.append(replace(r, maps=maps, uv_scale=(2.0, 1.0)))
    second = author_mtlx(first.output, again_results, output_path=document.with_name("second.mtlx"))
    old, new = read(document), read(second.layers_written[0])
    for node in tiles:
        total = (SCALE[0] * 2.0, SCALE[1] * 1.0)
        assert chain(new, node).close_to(chain(old, node).then(scale2d(total)), tol=1e-6)
        assert read_mtlx_provenance(new.getDescendant(node)).uv_scale == pytest.approx(total)
        assert read_mtlx_provenance(new.getDescendant(node)).source_asset.endswith(
            "brick albedo é.png" if "image" in node else "rough.png")
    place2ds = [n for n in new.getDescendant("NG_brick").getNodes() if n.getCategory() == "place2d"]
    assert len(place2ds) == 2  # the original and one seamless_uv


def test_address_modes_through_interface_inputs_and_missing_tile(document: Path):
    text = document.read_text(encoding="utf-8").replace(
        '<input name="uaddressmode" type="string" value="clamp" />',
        '<input name="uaddressmode" type="string" interfacename="wrap" />').replace(
        '<input name="albedo_file" type="filename" value="brick albedo é.png" />',
        '<input name="albedo_file" type="filename" value="brick albedo é.png" />\n'
        '    <input name="wrap" type="string" value="clamp" />')
    document.write_text(text, encoding="utf-8")
    (document.parent / "tileable" / "rough.M_brick-0123456789.tile.png").unlink()
    result = author_mtlx(document, results(document))
    assert [f.code for f in result.findings] == ["missing-output"]
    new = read(result.output)
    assert new.getDescendant("NG_brick/wrap").getValueString() == "periodic"
    assert new.getDescendant("NG_brick/image_color").getInput("uaddressmode").getInterfaceName() == "wrap"


def _file_values(path: Path) -> dict[str, str]:
    doc = read(path)
    return {e.getParent().getNamePath(): e.getValueString() for e in doc.traverseTree()
            if isinstance(e, mx.Input) and e.getType() == "filename"}


def test_a_second_run_for_other_materials_keeps_the_first_runs_edits(document: Path):
    """Two stages that use the same document, each processing one of its maps: the new document holds both edits
    (it was written whole from the source by each, and the last one undid the first's); once the source changes,
    it is made again from it, and the edits lost are named."""
    albedo, rough = results(document)
    first = author_mtlx(document, [albedo])
    assert "tileable/albedo.M_brick-0123456789.tile.png" in _file_values(first.output).values()
    second = author_mtlx(document, [rough])
    values = _file_values(second.output)
    assert "tileable/albedo.M_brick-0123456789.tile.png" in values.values() and "tileable/rough.M_brick-0123456789.tile.png" in values.values()
    assert not [f for f in second.findings if f.code == "mtlx-edits-replaced"]
    again = author_mtlx(document, [albedo, rough])  # nothing new: nothing written
    assert not again.layers_written
    document.write_text(document.read_text(encoding="utf-8").replace("<materialx", "<!-- edited -->\n<materialx", 1),
                        encoding="utf-8")
    third = author_mtlx(document, [rough])
    values = _file_values(third.output)
    assert "tileable/albedo.M_brick-0123456789.tile.png" not in values.values() and "tileable/rough.M_brick-0123456789.tile.png" in values.values()
    [lost] = [f for f in third.findings if f.code == "mtlx-edits-replaced"]
    assert "NG_brick/image_color" in lost.message and "tiled_rough" not in lost.message


CONNECTED_TILING = """<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="NG">
    <constant name="k" type="vector2">
      <input name="value" type="vector2" value="2.0, 2.0" />
    </constant>
    <tiledimage name="brick_color" type="color3">
      <input name="file" type="filename" value="textures/brick_albedo.png" colorspace="srgb_texture" />
      <input name="uvtiling" type="vector2" nodename="k" />
    </tiledimage>
    <output name="out" type="color3" nodename="brick_color" />
  </nodegraph>
  <standard_surface name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG" output="out" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>
</materialx>
"""


def test_a_uvtiling_fed_by_another_node_is_scaled_by_a_multiply_after_it(tmp_path, capsys):
    """A tiledimage whose uvtiling comes from a constant node: the UV scale multiplies that connection through a node
    of its own (a value beside the connection was a second binding: an invalid document, and no scale applied); a
    run on the new document updates that node instead of adding another."""
    import json
    import shutil

    from seamless_usd_cli.main import main

    shutil.copytree(Path(__file__).resolve().parents[1] / "sample_assets" / "textures", tmp_path / "textures")
    (tmp_path / "doc.mtlx").write_text(CONNECTED_TILING)
    args = ["--force", "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--cache-dir", str(tmp_path / "cache"),
            "--json"]
    main(["process", str(tmp_path / "doc.mtlx"), *args])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(tmp_path / "doc.seamless.mtlx"))
    library = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), library)
    doc.importLibrary(library)
    assert doc.validate()[0], doc.validate()[1]
    tiling = doc.getDescendant("NG/brick_color").getInput("uvtiling")
    product = tiling.getConnectedNode()
    assert product.getCategory() == "multiply" and product.getInput("in1").getNodeName() == "k"
    factor = [float(v) for v in product.getInput("in2").getValueString().split(",")]
    assert factor == pytest.approx(stack["uv_scale"], rel=1e-6) and not tiling.getValueString()
    main(["process", str(tmp_path / "doc.seamless.mtlx"), "--in-place", *args])
    capsys.readouterr()
    assert (tmp_path / "doc.seamless.mtlx").read_text().count("<multiply") == 1


def test_the_users_comments_are_kept_in_the_document_edited_in_place_and_the_new_one(tmp_path, capsys):
    """A document's comments (a header before its root, a note inside it) survive an in-place edit and the new
    document a run writes beside it; MaterialX drops them unless asked to read them."""
    import shutil

    from seamless_usd_cli.main import main

    shutil.copytree(Path(__file__).resolve().parents[1] / "sample_assets" / "textures", tmp_path / "textures")
    text = CONNECTED_TILING.replace('<?xml version="1.0"?>\n', '<?xml version="1.0"?>\n<!-- asset brick v3 -->\n')
    text = text.replace('  <nodegraph name="NG">', '  <!-- approved by lookdev: keep the roughness -->\n  <nodegraph name="NG">')
    args = ["--force", "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--cache-dir", str(tmp_path / "cache")]
    for name, extra in (("new.mtlx", ()), ("edited.mtlx", ("--in-place",))):
        (tmp_path / name).write_text(text)
        main(["process", str(tmp_path / name), *args, *extra])
        capsys.readouterr()
        written = tmp_path / (name if extra else name.replace(".mtlx", ".seamless.mtlx"))
        out = written.read_text()
        assert "<!-- asset brick v3 -->" in out and "<!-- approved by lookdev: keep the roughness -->" in out, out
        assert out.index("<!-- asset brick v3 -->") < out.index("<materialx")


def test_a_dry_run_names_the_tiledimage_uvtiling_edit(tmp_path, capsys):
    import json
    import shutil

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("mtlx", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    assert main(["process", str(tmp_path / "mtlx" / "tiled.mtlx"), "--dry-run", "--preset", "tiny", "--cache-dir",
                 str(tmp_path / "cache"), "--json"]) == 0
    plan = json.loads(capsys.readouterr().out)["plan"]
    assert any("uvtiling> = 2.0, 2.0 x the tile's UV scale" in line for line in plan), plan
