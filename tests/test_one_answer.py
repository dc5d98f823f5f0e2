"""One answer everywhere: ``check`` on a picture, ``check`` on a stage that uses it and the scan's
``already-tileable`` give the same answer on every picture of the labelled corpus (benchmarks/texture_corpus.py),
seamless and seamed, colour, scalar and normal maps."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from imagefiles import write_raw_image
from pxr import Sdf, Usd, UsdShade

from benchscripts import load_benchmark
from seamless_usd.discover import scan_paths
from seamless_usd.pipeline.check import check_paths

SHARED = Path(__file__).resolve().parents[2] / "shared" / "textures"


def _write_png16(path: Path, picture: np.ndarray) -> None:
    """A corpus picture (network domain) as the 16-bit PNG a library would hold: ``(v + 1) / 2``; a normal map
    thus encoded the usual way, a scalar map as one channel."""
    v = np.clip((picture + 1.0) / 2.0, 0.0, 1.0)
    write_raw_image(path, np.round(v * 65535.0).astype(np.uint16))


def _library(root: Path, items) -> Path:
    """One library material per picture (no geometry: meant to tile), each reading it the way its role does:
    colour to diffuseColor, a scalar to roughness, a normal map to normal with scale 2 and bias -1."""
    stage = Usd.Stage.CreateNew(str(root / "library.usda"))
    for k, item in enumerate(items):
        mat = UsdShade.Material.Define(stage, f"/Library/M{k}")
        surface = UsdShade.Shader.Define(stage, f"/Library/M{k}/Surface")
        surface.CreateIdAttr("UsdPreviewSurface")
        mat.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
        tex = UsdShade.Shader.Define(stage, f"/Library/M{k}/Tex")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(f"./{item.name}.png")
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("raw")
        reader = UsdShade.Shader.Define(stage, f"/Library/M{k}/St")
        reader.CreateIdAttr("UsdPrimvarReader_float2")
        reader.CreateInput("varname", Sdf.ValueTypeNames.Token).Set("st")
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
            reader.CreateOutput("result", Sdf.ValueTypeNames.Float2))
        channels = item.picture.shape[2]
        if item.is_normal:
            tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set((2, 2, 2, 1))
            tex.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set((-1, -1, -1, 0))
            out = tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
            surface.CreateInput("normal", Sdf.ValueTypeNames.Normal3f).ConnectToSource(out)
        elif channels == 1:
            out = tex.CreateOutput("r", Sdf.ValueTypeNames.Float)
            surface.CreateInput("roughness", Sdf.ValueTypeNames.Float).ConnectToSource(out)
        else:
            out = tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
            surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(out)
    stage.GetRootLayer().Save()
    return root / "library.usda"


@pytest.mark.skipif(not (SHARED / "wood_color.jpg").is_file(), reason="needs ../shared/textures")
def test_check_and_scan_agree_on_every_corpus_picture(tmp_path):
    items = load_benchmark("texture_corpus").build((128,))
    assert {i.seamless for i in items} == {True, False} and any(i.is_normal for i in items)
    assert any(i.picture.shape[2] == 1 for i in items)
    for item in items:
        _write_png16(tmp_path / f"{item.name}.png", item.picture)
    scene = _library(tmp_path, items)

    pictures = {Path(i.name).name: i for i in check_paths([tmp_path / f"{k.name}.png" for k in items]).items}
    scanned = {Path(s.maps[0].resolved).stem: s for s in scan_paths([scene]).stacks}
    on_stage = {Path(i.maps[0]).stem: i for i in check_paths([scene]).items}
    assert len(pictures) == len(scanned) == len(on_stage) == len(items)

    disagree = []
    for item in items:
        picture, stack = pictures[f"{item.name}.png"], scanned[item.name]
        assert not picture.error and stack.intent in ("tiling", "already-tileable"), (item.name, stack.intent_reason)
        left_alone = stack.intent == "already-tileable"
        judged = on_stage[item.name]
        if not (picture.passed == left_alone == judged.passed):
            disagree.append((item.name, picture.passed, stack.intent, judged.passed, stack.intent_reason))
    assert not disagree, disagree
    # the answers are not all one way: the corpus has pictures each side, and the verdict finds both
    assert {p.passed for p in pictures.values()} == {True, False}


def test_a_processed_stage_gets_one_answer_from_process_scan_and_check(tmp_path, capsys):
    """The stage a run wrote: the scan's triage reads the verdict recorded with each tile (against its source, as
    ``check`` judges it again), not the texture judged on its own; the names it reads are the authoring's."""
    import json
    import shutil

    from seamless_usd.authoring.mtlxinputs import MtlxNames
    from seamless_usd.authoring.schema import Schema
    from seamless_usd.discover.tokens import Recorded
    from seamless_usd_cli.main import main

    assert (Recorded.USD_SOURCE, Recorded.USD_PASSED) == (Schema.SOURCE_ASSET, Schema.PASSED)
    assert (Recorded.MTLX_SOURCE, Recorded.MTLX_PASSED) == (MtlxNames.SOURCE_ASSET, MtlxNames.PASSED)
    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    code = main(["process", str(tmp_path / "brick" / "scene.usda"), "--preset", "tiny", "--cache-dir",
                 str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    written = tmp_path / "brick" / "scene.seamless.usda"
    [scanned] = scan_paths([written]).stacks
    [checked] = check_paths([written]).items
    assert checked.verdict["reference"] == "source"
    assert (stack["status"] == "passed") == (scanned.intent == "already-tileable") == checked.passed == (code == 0)
    # the folder checked after the run: the stage as the run left it (its new layer), not the photo it was made from
    [in_folder] = check_paths([tmp_path / "brick"]).items
    assert Path(in_folder.source) == written and in_folder.verdict == checked.verdict
    assert "seamless:passed" in scanned.intent_reason
    # cut from its source with no network trained: said so, and no Q figures or model hash recorded
    assert stack["origin"] == "cut" and not stack["model_hash"]
    opened = Usd.Stage.Open(str(written))
    albedo = opened.GetPrimAtPath("/World/Looks/Brick/Albedo")
    assert albedo.GetAttribute("seamless:passed").Get() == (stack["status"] == "passed")
    for name in ("seamless:qPassed", "seamless:qTau", "seamless:qBandMin", "seamless:modelHash"):
        assert not albedo.GetAttribute(name).HasAuthoredValue(), name


def _process(tmp_path: Path, capsys, scene: str, names: tuple[str, ...]) -> tuple[Path, dict, int]:
    import json
    import shutil

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in names:
        shutil.copytree(samples / name, tmp_path / name)
    code = main(["process", str(tmp_path / scene), "--preset", "tiny", "--seeds", "1", "--max-size", "128",
                 "--cache-dir", str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    return tmp_path / scene, stack, code


def test_the_tiles_named_alone_are_judged_against_their_sources_with_their_stack(tmp_path, capsys):
    """A tile's file records its source and its stack's other tiles: ``check`` on the tiles alone (a folder of them,
    or one named) gives the answer ``check`` gives on the stage, judged together against the sources; a tile whose
    source has changed since is judged against itself, and says why."""
    scene, stack, code = _process(tmp_path, capsys, "brick/scene.usda", ("brick", "textures"))
    tiles = sorted(Path(m["output"]).resolve() for m in stack["maps"])
    assert len(tiles) == 3
    [on_stage] = check_paths([scene.with_name("scene.seamless.usda")]).items
    [folder] = check_paths([tiles[0].parent]).items  # the three tiles: one stack, judged once
    [named] = check_paths([tiles[1]]).items
    for item in (folder, named):
        assert item.verdict["reference"] == "source" and not item.error and not item.note
        assert sorted(Path(p).resolve() for p in item.maps) == tiles
        assert item.passed == on_stage.passed == (stack["status"] == "passed") == (code == 0)
        assert item.verdict["seams"] == on_stage.verdict["seams"]
        assert item.verdict["failing"] == on_stage.verdict["failing"]
    assert named.name == str(tiles[1]) and "other tile(s) of its stack" in named.words()

    (tmp_path / "textures" / "brick_roughness.png").write_bytes((tmp_path / "textures" / "brick_albedo.png")
                                                               .read_bytes())  # the source changed since
    roughness = next(t for t in tiles if t.name.startswith("brick_roughness"))
    [changed] = check_paths([roughness]).items
    assert changed.verdict["reference"] == "itself" and changed.maps == [str(roughness)]
    assert "has changed since the tile was made" in changed.note and changed.note in changed.words()
    # the folder: the other two still against their sources (saying which tile they were judged without), the
    # changed one against itself; the stage says the same
    by_reference = {i.verdict["reference"]: i for i in check_paths([tiles[0].parent]).items}
    assert sorted(by_reference) == ["itself", "source"] and len(by_reference["source"].maps) == 2
    assert roughness.name in by_reference["source"].note and by_reference["itself"].name == str(roughness)
    [layer] = check_paths([scene.with_name("scene.seamless.usda")]).items
    assert layer.verdict["reference"] == "itself" and "has changed since the tile was made" in layer.note
    (tmp_path / "textures" / "brick_roughness.png").unlink()  # gone: said so on the stage too
    [layer] = check_paths([scene.with_name("scene.seamless.usda")]).items
    assert "is not there" in layer.note and layer.verdict["reference"] == "itself"


def test_output_layer_names_the_new_materialx_document_judged_against_its_recorded_sources(tmp_path, capsys):
    """-o for a .mtlx input writes the new document there (its paths made relative to it), not beside the source;
    a USD name for it, or one name for several inputs, is refused before any work. ``check`` on the new document
    judges its tiles against the sources its nodes record, as ``process`` did, not against themselves."""
    import json
    import shutil

    import MaterialX as mx

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("mtlx", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    source = tmp_path / "mtlx" / "tiled.mtlx"
    assert main(["process", str(source), "-o", str(tmp_path / "out" / "new.usda")]) == 2
    assert main(["process", str(source), str(tmp_path / "mtlx" / "prefixed.mtlx"), "-o", str(tmp_path / "n.mtlx")]) == 2
    capsys.readouterr()
    new = tmp_path / "out" / "new.mtlx"
    code = main(["process", str(source), "-o", str(new), "--preset", "tiny", "--seeds", "1", "--max-size", "128",
                 "--cache-dir", str(tmp_path / "cache"), "--json"])
    report = json.loads(capsys.readouterr().out)
    assert report["layers_written"] == [str(new)] and not source.with_name("tiled.seamless.mtlx").exists()
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(new))
    files = [n.getInput("file").getResolvedValueString() for n in doc.traverseTree()
             if isinstance(n, mx.Node) and n.getInput("file") is not None]
    assert files and all((new.parent / f).is_file() for f in files)
    [checked] = check_paths([new]).items
    assert checked.verdict["reference"] == "source" and not checked.error and not checked.note
    assert checked.passed == (report["stacks"][0]["status"] == "passed") == (code == 0)
    [original] = check_paths([source]).items  # the sources themselves: nothing recorded, judged against themselves
    assert original.verdict["reference"] == "itself"


def test_a_materialx_stack_written_across_nodegraph_scopes_is_read_back_as_one_stack(tmp_path, capsys):
    """The brick document's albedo sits at the document's top level, its ORM and normal images inside a nodegraph: the
    authoring inserts one UV place2d in each scope (a node inside a nodegraph cannot read one outside it). Scanned and
    checked again, the three maps are still one stack, judged together as ``process`` judged them."""
    import json
    import shutil

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("mtlx", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    source = tmp_path / "mtlx" / "prefixed.mtlx"
    code = main(["process", str(source), "--preset", "tiny", "--seeds", "1", "--max-size", "128", "--cache-dir",
                 str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    written = source.with_name("prefixed.seamless.mtlx")
    assert written.read_text().count('<place2d name="seamless_uv"') == 2  # one place2d per scope
    import MaterialX as mx

    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(written))
    places = [n for n in doc.traverseTree() if isinstance(n, mx.Node) and n.getCategory() == "place2d"]
    for place in places:  # each reads UV0, as the images did by default (a place2d's own default is (0, 0))
        reader = place.getInput("texcoord").getConnectedNode()
        assert reader is not None and reader.getCategory() == "texcoord", place.getNamePath()
        assert int(reader.getInput("index").getValueString()) == 0
    library = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), library)
    doc.importLibrary(library)
    assert doc.validate()[0], doc.validate()[1]
    [scanned] = scan_paths([written]).stacks
    assert len(scanned.maps) == len(stack["maps"]) == 3
    [checked] = check_paths([written]).items
    assert checked.passed == (stack["status"] == "passed") == (code == 0) and len(checked.maps) == 3
