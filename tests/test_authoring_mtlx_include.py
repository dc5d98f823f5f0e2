"""A MaterialX document whose texture nodes come from a document it includes (``xi:include``): the scan finds
their files beside the included document from any working folder, and the new document holds the edited
elements, so what was reported is what is written."""
from __future__ import annotations

import os
import shutil
from pathlib import Path

import MaterialX as mx

from standins import stand_ins

from seamless_usd.authoring import WriteMode, author_mtlx
from seamless_usd.discover import scan_paths

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
GRAPHS = """<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="NG_brick">
    <image name="albedo" type="color3">
      <input name="file" type="filename" value="brick_albedo.png" colorspace="srgb_texture" />
    </image>
    <image name="rough" type="float">
      <input name="file" type="filename" value="brick_roughness.png" />
    </image>
    <image name="spare" type="float">
      <input name="file" type="filename" value="maps/spare.png" />
    </image>
    <output name="base_color_out" type="color3" nodename="albedo" />
    <output name="rough_out" type="float" nodename="rough" />
  </nodegraph>
  <nodegraph name="NG_other">
    <constant name="c" type="float"><input name="value" type="float" value="0.5" /></constant>
    <output name="out" type="float" nodename="c" />
  </nodegraph>
</materialx>
"""
LOOK = """<?xml version="1.0"?>
<materialx version="1.39" xmlns:xi="http://www.w3.org/2001/XInclude">
  <xi:include href="lib/graphs.mtlx" />
  <standard_surface name="SR_brick" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG_brick" output="base_color_out" />
    <input name="specular_roughness" type="float" nodegraph="NG_brick" output="rough_out" />
  </standard_surface>
  <surfacematerial name="M_brick" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_brick" />
  </surfacematerial>
</materialx>
"""


def _library(root: Path) -> Path:
    (root / "lib" / "maps").mkdir(parents=True)
    (root / "lib" / "graphs.mtlx").write_text(GRAPHS)
    for name in ("brick_albedo.png", "brick_roughness.png"):
        shutil.copyfile(TEXTURES / name, root / "lib" / name)
    shutil.copyfile(TEXTURES / "brick_roughness.png", root / "lib" / "maps" / "spare.png")
    (root / "look.mtlx").write_text(LOOK)
    return root / "look.mtlx"


def _files(path: Path) -> dict[str, Path]:
    """Each image node's file as the written document resolves it (relative to its own folder)."""
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(path))
    return {n.getNamePath(): path.parent / n.getInput("file").getResolvedValueString()
            for n in doc.traverseTree() if isinstance(n, mx.Node) and n.getCategory() == "image"}


def test_the_included_texture_nodes_are_found_from_any_folder(tmp_path, monkeypatch):
    look = _library(tmp_path)
    monkeypatch.chdir(os.path.abspath(os.sep))
    [stack] = scan_paths([look]).stacks
    assert [Path(m.resolved).name for m in stack.maps] == ["brick_albedo.png", "brick_roughness.png"]
    assert {m.file_at.layer for m in stack.maps} == {str(tmp_path / "lib" / "graphs.mtlx")}


def test_the_edited_included_nodes_are_written_into_the_new_document(tmp_path):
    look = _library(tmp_path)
    included = (tmp_path / "lib" / "graphs.mtlx").read_bytes()
    result = author_mtlx(look, stand_ins(look))
    assert result.layers_written == [tmp_path / "look.seamless.mtlx"]
    assert any(f.code == "mtlx-include-inlined" and "NG_brick" in f.where for f in result.findings)
    files = _files(result.output)
    assert files["NG_brick/albedo"].resolve() == (tmp_path / "tileable" / "brick_albedo_tile.png").resolve()
    assert files["NG_brick/rough"].resolve() == (tmp_path / "tileable" / "brick_roughness_tile.png").resolve()
    assert files["NG_brick/spare"].resolve() == (tmp_path / "lib" / "maps" / "spare.png").resolve()  # rebased
    written = mx.createDocument()
    mx.readFromXmlFile(written, str(result.output))
    assert written.getChild("NG_other") is not None and not written.getChild("NG_other").getSourceUri()
    assert "xi:include" not in result.output.read_text()  # the included elements are written in its place
    assert written.getDescendant("NG_brick/albedo").getAttribute("seamless_passed") == "true"
    assert (tmp_path / "lib" / "graphs.mtlx").read_bytes() == included  # left as it is
    again = author_mtlx(look, stand_ins(look))  # a second run: nothing to change
    assert again.layers_written == [] and again.plan == []


def test_in_place_the_edited_nodes_go_into_the_document_itself(tmp_path):
    look = _library(tmp_path)
    result = author_mtlx(look, stand_ins(look), mode=WriteMode.IN_PLACE)
    assert result.layers_written == [look] and result.backups
    assert _files(look)["NG_brick/albedo"].resolve() == (tmp_path / "tileable" / "brick_albedo_tile.png").resolve()
