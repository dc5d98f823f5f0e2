"""A MaterialX input that several texture nodes share through their nodegraph's interface (one ``uvtiling`` for a
stack's ``tiledimage`` nodes): scaled once a run, not once per node."""
from __future__ import annotations

import shutil
from pathlib import Path

import MaterialX as mx
from standins import stand_ins

from seamless_usd.authoring import author_mtlx

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
DOCUMENT = """<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="NG">
    <input name="tiling" type="vector2" value="2.0, 2.0" />
    <tiledimage name="alb" type="color3">
      <input name="file" type="filename" value="brick_albedo.png" colorspace="srgb_texture" />
      <input name="uvtiling" type="vector2" interfacename="tiling" />
    </tiledimage>
    <tiledimage name="rough" type="float">
      <input name="file" type="filename" value="brick_roughness.png" />
      <input name="uvtiling" type="vector2" interfacename="tiling" />
    </tiledimage>
    <output name="c" type="color3" nodename="alb" />
    <output name="r" type="float" nodename="rough" />
  </nodegraph>
  <standard_surface name="SR" type="surfaceshader">
    <input name="base_color" type="color3" nodegraph="NG" output="c" />
    <input name="specular_roughness" type="float" nodegraph="NG" output="r" />
  </standard_surface>
  <surfacematerial name="M" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR" />
  </surfacematerial>
</materialx>
"""


def test_a_shared_interface_uvtiling_is_scaled_once(tmp_path):
    for name in ("brick_albedo.png", "brick_roughness.png"):
        shutil.copyfile(TEXTURES / name, tmp_path / name)
    (tmp_path / "tiled.mtlx").write_text(DOCUMENT)
    [result] = stand_ins(tmp_path / "tiled.mtlx", (1.25, 1.5))
    assert len(result.maps) == 2
    written = author_mtlx(tmp_path / "tiled.mtlx", [result]).output
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(written))
    assert doc.getDescendant("NG/tiling").getValueString() == "2.5, 3.0"
    assert [f for f in author_mtlx(tmp_path / "tiled.mtlx", [result]).findings if f.code == "shared-texture-conflict"] == []
