"""A report is never written over a file of the user's: ``--report albedo.png`` writes ``albedo.html`` beside the
picture, a page or JSON file this tool did not write is refused before any work, and its own reports are
replaced."""
from __future__ import annotations

import hashlib
import shutil
from pathlib import Path

import pytest

from seamless_usd.errors import InputError
from seamless_usd.report.target import report_target
from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_check_with_the_picture_as_its_report_path_keeps_the_picture(tmp_path, capsys):
    picture = tmp_path / "albedo.png"
    shutil.copy(SAMPLES / "textures" / "brick_albedo.png", picture)
    before = _digest(picture)
    assert main(["check", str(picture), "--report", str(picture)]) in (0, 1)
    assert _digest(picture) == before
    sheet = tmp_path / "albedo.html"
    assert sheet.read_text().startswith("<!doctype html>") and "albedo.png" in sheet.read_text()
    # its own contact sheet is replaced on the next run
    assert main(["check", str(picture), "--report", str(sheet)]) in (0, 1)


def test_a_page_or_json_file_of_the_users_is_refused_before_any_work(tmp_path, capsys):
    picture = tmp_path / "albedo.png"
    shutil.copy(SAMPLES / "textures" / "brick_albedo.png", picture)
    page = tmp_path / "notes.html"
    page.write_text("<!doctype html><html><body>my notes</body></html>")
    assert main(["check", str(picture), "--report", str(page)]) == 2
    assert "notes.html" in capsys.readouterr().err and "my notes" in page.read_text()

    scene = tmp_path / "brick" / "scene.usda"
    shutil.copytree(SAMPLES / "brick", scene.parent)
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    data = tmp_path / "run.json"
    data.write_text('{"mine": true}')
    assert main(["process", str(scene), "--dry-run", "--report", str(tmp_path / "run.html")]) == 2
    err = capsys.readouterr().err
    assert "run.json" in err and "not replaced" in err
    assert data.read_text() == '{"mine": true}' and not (tmp_path / "run.html").exists()
    assert not list(scene.parent.glob("*.seamless.usda"))  # refused before any work


def test_report_target_names_the_file_and_refuses_folders(tmp_path):
    assert report_target(tmp_path / "r") == tmp_path / "r.html"
    assert report_target(tmp_path / "r.htm") == tmp_path / "r.htm"
    assert report_target(tmp_path / "r.html", ".json") == tmp_path / "r.json"
    (tmp_path / "out").mkdir()  # a folder named: the report goes inside it
    assert report_target(tmp_path / "out") == tmp_path / "out" / "report.html"
    assert report_target(f"{tmp_path / 'new'}/") == tmp_path / "new" / "report.html"
    (tmp_path / "d.html").mkdir()  # a folder where the page would go
    with pytest.raises(InputError, match="is a folder"):
        report_target(tmp_path / "d")
    stage = tmp_path / "s.usda"
    stage.write_text("#usda 1.0\n")
    assert report_target(stage) == tmp_path / "s.html"  # the stage itself is never the target
