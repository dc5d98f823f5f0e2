"""Authoring on the bundled sample scenes, with the maps discovery finds in them.

The tileable files are stand-ins (copies of the sources): authoring only places them.
"""
from __future__ import annotations

import hashlib
from dataclasses import replace
from pathlib import Path

import MaterialX as mx
import pytest
from pxr import Usd, UsdShade
from standins import stand_ins

from seamless_usd.authoring import (
    MapResult,
    Provenance,
    Schema,
    StackResult,
    WriteMode,
    author_mtlx,
    author_usd,
    scale2d,
    uv_affine,
)
from seamless_usd.textures import Origin

SCALE = (2.0, 3.0)
STDLIB = mx.createDocument()
mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), STDLIB)
USD_SCENES = ["brick/scene.usda", "orm/scene.usda", "interface/scene.usda", "transform2d/scene.usda",
              "referenced/scene.usda", "usd_mtlx/scene.usda"]
MTLX_DOCS = ["mtlx/tiled.mtlx", "mtlx/prefixed.mtlx"]


def stand_in_results(path: Path) -> list[StackResult]:
    results = stand_ins(path, SCALE, lambda stack: Provenance(stack.maps[0].asset, (64, 64), SCALE, True, 0.5,
                                                              (0.6, 0.7), "hash", "0.1.0"))
    assert results, f"discovery found no stack in {path}"
    return results


def digest(folder: Path) -> dict[str, str]:
    return {str(p): hashlib.sha256(p.read_bytes()).hexdigest() for p in folder.rglob("*") if p.is_file()}


@pytest.mark.parametrize("scene", USD_SCENES)
def test_sample_scene_new_layer(samples_copy: Path, scene: str):
    path = samples_copy / scene
    results = stand_in_results(path)
    before = digest(samples_copy)
    result = author_usd(path, results)
    assert result.layers_written == [result.output] and not result.findings
    after = digest(samples_copy)
    assert {k: after[k] for k in before} == before  # no source layer or texture changed
    old, new = Usd.Stage.Open(str(path)), Usd.Stage.Open(str(result.output))
    for stack in results:
        for map_result in stack.maps:
            node = map_result.map.node.strip("<>")
            prim = new.GetPrimAtPath(node)
            assert prim.HasAPI(Schema.TILE_API)
            attr = UsdShade.Shader(prim).GetInput("file").GetValueProducingAttributes()[0]
            assert Path(attr.Get().resolvedPath) == map_result.output_path.resolve()
            assert uv_affine(new, node).close_to(uv_affine(old, node).then(scale2d(SCALE)), 1e-6)
    again = author_usd(result.output, results)  # a second run on the output: no-op
    assert again.layers_written == [] and again.plan == []


def test_sample_referenced_library_in_place(samples_copy: Path):
    path = samples_copy / "referenced/scene.usda"
    library = samples_copy / "library/materials/wood.usda"
    original = library.read_bytes()
    result = author_usd(path, stand_in_results(path), mode=WriteMode.IN_PLACE)
    assert result.layers_written == [library]  # the layer holding the opinions, through the reference
    assert Path(str(library) + ".bak").read_bytes() == original


@pytest.mark.parametrize("document", MTLX_DOCS)
def test_sample_document(samples_copy: Path, document: str):
    path = samples_copy / document
    results = [r for r in stand_in_results(path) if r.maps[0].map.origin is Origin.MTLX]
    before = path.read_bytes()
    result = author_mtlx(path, results)
    assert path.read_bytes() == before and result.layers_written == [result.output]
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(result.output))
    doc.importLibrary(STDLIB)
    valid, message = doc.validate()
    assert valid, message
    for stack in results:
        for map_result in stack.maps:
            node = doc.getDescendant(map_result.map.node)
            assert node.getAttribute("seamless_uvscale") == "2.0, 3.0"
    # a second run on the new document, with the same (source) maps: nothing to change
    moved = [replace(r, maps=[MapResult(replace(m.map, document=str(result.output),
                                                file_at=replace(m.map.file_at, layer=str(result.output))),
                                        m.output_path) for m in r.maps]) for r in results]
    again = author_mtlx(result.output, moved, output_path=result.output.with_name("again.mtlx"))
    assert again.plan == [] and again.layers_written == []


def test_sample_stage_referencing_a_materialx_document(samples_copy: Path):
    from pxr import Sdf

    path = samples_copy / "mtlx/scene.usda"
    document = samples_copy / "mtlx/tiled.mtlx"
    results = stand_in_results(path)
    assert all(m.map.origin is Origin.MTLX for r in results for m in r.maps)
    before = digest(samples_copy)
    result = author_usd(path, results)
    new_document = samples_copy / "mtlx/tiled.seamless.mtlx"
    assert result.layers_written == [result.output, new_document]
    after = digest(samples_copy)
    assert {k: after[k] for k in before} == before
    # the new layer points the stage's reference at the new document, keeping its prim path
    layer = Sdf.Layer.FindOrOpen(str(result.output))
    (spec,) = [s for s in [layer.GetPrimAtPath("/World/Looks/Wood")] if s]
    (deleted,), (prepended,) = spec.referenceList.deletedItems, spec.referenceList.prependedItems
    assert Path(layer.ComputeAbsolutePath(deleted.assetPath)) == document
    assert Path(layer.ComputeAbsolutePath(prepended.assetPath)) == new_document
    assert prepended.primPath == deleted.primPath
    # in place: the document itself is edited (with a backup); no layer needs a change
    in_place = author_usd(path, results, mode=WriteMode.IN_PLACE)
    assert in_place.layers_written == [document] and in_place.backups == [Path(f"{document}.bak")]
