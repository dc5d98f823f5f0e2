"""Two stages in their own folders referencing one MaterialX library document: each stage's new layer gets a
new document of its own, beside it, with the library's relative paths rebased; the second run rewrote the one
new document beside the library, and the first stage's layer then showed the second stage's tiles."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
#: A library document of two materials (image nodes, no UV nodes), in a folder below the stage that references it.
LIBRARY = """<?xml version="1.0"?>
<materialx version="1.39" colorspace="lin_rec709">
  <image name="b_base" type="color3">
    <input name="file" type="filename" value="../../textures/brick_albedo.png" colorspace="srgb_texture" />
  </image>
  <image name="b_rough" type="float">
    <input name="file" type="filename" value="../../textures/brick_roughness.png" />
  </image>
  <standard_surface name="SR_b" type="surfaceshader">
    <input name="base_color" type="color3" nodename="b_base" />
    <input name="specular_roughness" type="float" nodename="b_rough" />
  </standard_surface>
  <surfacematerial name="M_brick" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_b" />
  </surfacematerial>
  <image name="w_base" type="color3">
    <input name="file" type="filename" value="../../textures/wood_color.png" colorspace="srgb_texture" />
  </image>
  <standard_surface name="SR_w" type="surfaceshader">
    <input name="base_color" type="color3" nodename="w_base" />
  </standard_surface>
  <surfacematerial name="M_wood" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="SR_w" />
  </surfacematerial>
</materialx>
"""
STAGE = """#usda 1.0
def Xform "World"
{
    def Scope "Looks"
    {
        def Material "Brick" ( references = @./mtl/looks.mtlx@</MaterialX/Materials/M_brick> ) {}
        def Material "Wood" ( references = @./mtl/looks.mtlx@</MaterialX/Materials/M_wood> ) {}
    }
}
"""


def test_two_stages_referencing_one_library_document_get_a_document_each(tmp_path, capsys):
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "lib").mkdir()
    shutil.copy(SAMPLES / "mtlx" / "tiled.mtlx", tmp_path / "lib" / "looks.mtlx")
    scene = (SAMPLES / "mtlx" / "scene.usda").read_text().replace("@./tiled.mtlx@", "@../lib/looks.mtlx@")
    for name in ("shot1", "shot2"):
        (tmp_path / name).mkdir()
        (tmp_path / name / f"{name}.usda").write_text(scene)
    written = {}
    for name in ("shot1", "shot2"):
        code = main(["process", str(tmp_path / name / f"{name}.usda"), "--preset", "tiny", "--max-size", "128",
                     "--cache-dir", str(tmp_path / "cache"), "--json"])
        payload = json.loads(capsys.readouterr().out)
        assert code == payload["exit_code"] and payload["stacks"][0]["status"] in ("passed", "not-passed")
        document = tmp_path / name / f"looks.{name}.seamless.mtlx"
        assert document.is_file() and str(document) in payload["layers_written"]
        assert f"@./looks.{name}.seamless.mtlx@" in (tmp_path / name / f"{name}.seamless.usda").read_text()
        assert f"{name}/tileable/" not in document.read_text() and "tileable/" in document.read_text()
        written[name] = document.read_text()
    assert sorted(p.name for p in (tmp_path / "lib").iterdir()) == ["looks.mtlx"]  # the library as it was
    assert (tmp_path / "shot1" / "looks.shot1.seamless.mtlx").read_text() == written["shot1"]  # not rewritten
    # check reads each stage through its own document, against the library's sources
    for name in ("shot1", "shot2"):
        main(["check", "--json", str(tmp_path / name / f"{name}.seamless.usda")])
        [item] = json.loads(capsys.readouterr().out)["items"]
        assert not item["note"] and item["maps"][0].startswith("tileable/"), item


def test_a_stage_referencing_a_document_in_another_folder_run_again_keeps_its_uv_scale(tmp_path, capsys):
    """The new document beside the stage records each tile's source relative to itself; a run again read that path
    against the library's folder, took the tile for a tile of a tile, and multiplied the UV scale each time (1.2,
    1.44, 1.73: texel density lost, and check then disagreed with the run)."""
    import re

    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "shot" / "mtl").mkdir(parents=True)
    (tmp_path / "shot" / "mtl" / "looks.mtlx").write_text(LIBRARY)
    (tmp_path / "shot" / "shot.usda").write_text(STAGE)
    document = tmp_path / "shot" / "looks.shot.seamless.mtlx"
    run = ["process", str(tmp_path / "shot" / "shot.usda"), "--preset", "tiny", "--max-size", "128",
           "--cache-dir", str(tmp_path / "cache"), "--json"]
    texts = []
    for _ in range(3):
        code = main(run)
        payload = json.loads(capsys.readouterr().out)
        assert code == payload["exit_code"], payload
        texts.append(document.read_text())
    scales = re.findall(r'seamless_uvscale="([^"]+)"', texts[0])
    assert scales and texts[1] == texts[0] and texts[2] == texts[0], (scales, re.findall(
        r'seamless_uvscale="([^"]+)"', texts[2]))
    assert not payload["layers_written"]  # the run again is a no-op
    main(["check", "--json", str(tmp_path / "shot" / "shot.seamless.usda")])
    assert json.loads(capsys.readouterr().out)["exit_code"] == payload["exit_code"]
