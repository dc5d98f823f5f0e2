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


SHARED_FILE = """<?xml version="1.0"?>
<materialx version="1.39">
  <nodegraph name="NG" fileprefix="../tex/">
    <input name="albedo_file" type="filename" value="brick_albedo.png" colorspace="srgb_texture" />
    <image name="tiled" type="color3"><input name="file" type="filename" interfacename="albedo_file" /></image>
    <image name="decal" type="color3"><input name="file" type="filename" interfacename="albedo_file" />
      <input name="uaddressmode" type="string" value="clamp" />
      <input name="vaddressmode" type="string" value="clamp" />
    </image>
    <image name="rough" type="float"><input name="file" type="filename" value="brick_roughness.png" /></image>
    <image name="other" type="color3"><input name="file" type="filename" interfacename="albedo_file" /></image>
    <output name="tiled_out" type="color3" nodename="tiled" /><output name="decal_out" type="color3" nodename="decal" />
    <output name="rough_out" type="float" nodename="rough" /><output name="other_out" type="color3" nodename="other" />
  </nodegraph>
  <standard_surface name="SR_tile" type="surfaceshader"><input name="base_color" type="color3" nodegraph="NG" output="tiled_out" />
    <input name="specular_roughness" type="float" nodegraph="NG" output="rough_out" /></standard_surface>
  <surfacematerial name="M_tile" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR_tile" /></surfacematerial>
  <standard_surface name="SR_decal" type="surfaceshader"><input name="base_color" type="color3" nodegraph="NG" output="decal_out" /></standard_surface>
  <surfacematerial name="M_decal" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR_decal" /></surfacematerial>
  <standard_surface name="SR_other" type="surfaceshader"><input name="base_color" type="color3" nodegraph="NG" output="other_out" /></standard_surface>
  <surfacematerial name="M_other" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR_other" /></surfacematerial>
</materialx>
"""


def _document(tmp_path: Path, name: str, text: str, textures: tuple[str, ...]) -> Path:
    """``docs/<name>`` holding ``text``, reading ``textures`` (sample textures) from ``../tex``."""
    (tmp_path / "tex").mkdir(exist_ok=True)
    for texture in textures:
        shutil.copyfile(TEXTURES / texture, tmp_path / "tex" / texture)
    (tmp_path / "docs").mkdir(exist_ok=True)
    source = tmp_path / "docs" / name
    source.write_text(text)
    return source


def test_an_interface_file_input_three_images_read_keeps_each_ones_file(tmp_path, model_cache, capsys):
    """A nodegraph's interface input read by a tiling image (with a roughness beside it), a clamped decal left alone,
    and another material's image (a stack of its own): the tile was written to the interface input, so the decal
    showed a crop of the tile, and the last stack's tile replaced the first's (its maps misaligned, both passed).
    Each tiling image now reads its own file input; the decal keeps reading the photo; a run again changes nothing."""
    import json

    from runchecks import PLUMBING

    from seamless_usd_cli.main import main

    source = _document(tmp_path, "shared.mtlx", SHARED_FILE, ("brick_albedo.png", "brick_roughness.png"))
    args = ["process", *PLUMBING, "--max-size", "112", "--json", "--cache-dir", str(model_cache), str(source)]
    main(args)
    rows = {s["material"]: s for s in json.loads(capsys.readouterr().out)["stacks"]}
    assert rows["<M_decal>"]["status"] == "left-alone"
    assert {rows[m]["status"] for m in ("<M_tile>", "<M_other>")} <= {"passed", "not-passed"}
    written = source.with_name("shared.seamless.mtlx")
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(written))
    assert doc.validate()[0]
    decal = doc.getDescendant("NG/decal/file")
    assert decal.getInterfaceName() == "albedo_file" and decal.getInterfaceInput().getResolvedValueString().endswith(
        "brick_albedo.png")  # the photo, through the fileprefix
    files = {n: doc.getDescendant(f"NG/{n}/file") for n in ("tiled", "other")}
    tiles = {n: (inp if not inp.getInterfaceName() else inp.getInterfaceInput()).getValueString()
             for n, inp in files.items()}
    assert all("tileable/" in t for t in tiles.values()) and tiles["tiled"] != tiles["other"]  # each its own tile
    assert doc.getDescendant("NG/tiled/file").getColorSpace() == "srgb_texture"  # kept from the interface input
    before = written.read_text()
    main(args)
    capsys.readouterr()
    assert written.read_text() == before


WRAP_SHARED = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <nodegraph name="NG">
    <input name="wrap" type="string" value="clamp" uniform="true" />
    <image name="a" type="color3">
      <input name="file" type="filename" value="../tex/brick_albedo.png" colorspace="srgb_texture" />
      <input name="uaddressmode" type="string" interfacename="wrap" />
      <input name="vaddressmode" type="string" interfacename="wrap" />
    </image>
    <image name="decal" type="color3">
      <input name="file" type="filename" value="../tex/wood_color.png" colorspace="srgb_texture" />
      <input name="uaddressmode" type="string" interfacename="wrap" />
      <input name="vaddressmode" type="string" interfacename="wrap" />
    </image>
    <output name="oa" type="color3" nodename="a" />
    <output name="od" type="color3" nodename="decal" />
  </nodegraph>
  <standard_surface name="SR1" type="surfaceshader"><input name="base_color" type="color3" nodegraph="NG" output="oa" /></standard_surface>
  <surfacematerial name="M1" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR1" /></surfacematerial>
  <standard_surface name="SR2" type="surfaceshader"><input name="base_color" type="color3" nodegraph="NG" output="od" /></standard_surface>
  <surfacematerial name="M2" type="material"><input name="surfaceshader" type="surfaceshader" nodename="SR2" /></surfacematerial>
</materialx>
"""


def test_address_modes_from_an_interface_input_a_decal_reads_too_stay_clamped_for_it(tmp_path, model_cache, capsys):
    """Two images read their address modes from one interface input (clamp); the first is tiled (forced), the
    second, a decal, is left alone. The interface input was set to periodic, so the decal repeated. The tiled image
    now gets periodic on its own inputs; the decal keeps reading clamp."""
    import json

    from runchecks import PLUMBING

    from seamless_usd_cli.main import main

    source = _document(tmp_path, "wrap.mtlx", WRAP_SHARED, ("brick_albedo.png", "wood_color.png"))
    main(["process", *PLUMBING, "--max-size", "112", "--force-materials", "M1", "--json", "--cache-dir",
          str(model_cache), str(source)])
    rows = {s["material"]: s for s in json.loads(capsys.readouterr().out)["stacks"]}
    assert rows["<M2>"]["status"] == "left-alone" and rows["<M1>"]["status"] in ("passed", "not-passed")
    doc = mx.createDocument()
    mx.readFromXmlFile(doc, str(source.with_name("wrap.seamless.mtlx")))
    assert doc.validate()[0]
    for mode in ("uaddressmode", "vaddressmode"):
        assert doc.getDescendant(f"NG/a/{mode}").getValueString() == "periodic"
        decal = doc.getDescendant(f"NG/decal/{mode}")
        assert decal.getInterfaceName() == "wrap" and decal.getInterfaceInput().getValueString() == "clamp"


def test_an_older_document_written_at_the_library_s_version_is_said(tmp_path, model_cache, capsys):
    """The MaterialX library upgrades a 1.38 document as it reads it, so the new document is a 1.39 one: a pipeline
    pinned to 1.38 readers was not told. A warning names both versions; a 1.39 document gets none."""
    import json

    from runchecks import PLUMBING

    from seamless_usd_cli.main import main

    for version in ("1.38", "1.39"):
        source = _document(tmp_path, f"v{version}.mtlx", WRAP_SHARED.replace('version="1.39"', f'version="{version}"'),
                           ("brick_albedo.png", "wood_color.png"))
        main(["process", *PLUMBING, "--max-size", "112", "--force", "--json", "--cache-dir", str(model_cache),
              str(source)])
        payload = json.loads(capsys.readouterr().out)
        said = [f["message"] for f in payload["findings"] if f["code"] == "mtlx-version-upgraded"]
        assert payload["layers_written"], payload
        assert len(said) == (1 if version == "1.38" else 0), said
        assert not said or ("1.38" in said[0] and "1.39" in said[0])
