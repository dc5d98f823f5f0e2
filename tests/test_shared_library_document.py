"""Two stages in their own folders referencing one MaterialX library document: each stage's new layer gets a
new document of its own, beside it, with the library's relative paths rebased; the second run rewrote the one
new document beside the library, and the first stage's layer then showed the second stage's tiles."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


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
