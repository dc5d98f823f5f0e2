"""A report is never written over a file of the user's: ``--report albedo.png`` writes ``albedo.html`` beside the
picture, a page or JSON file this tool did not write is refused before any work, and its own reports are
replaced."""
from __future__ import annotations

import hashlib
import json
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


def test_a_page_that_only_names_the_tool_and_a_json_that_only_has_its_key_are_the_users(tmp_path, capsys):
    """Only a page with the tool's own generator mark, or a JSON report with its keys, is replaced: a hand-written page
    about the tool, or a JSON file with one of its keys, is the user's."""
    picture = tmp_path / "albedo.png"
    shutil.copy(SAMPLES / "textures" / "brick_albedo.png", picture)
    notes = tmp_path / "notes.html"
    notes.write_text("<!DOCTYPE html>\n<html><head><title>Notes: seamless-usd rollout</title></head><body>mine</body>"
                     "</html>\n")
    assert main(["check", str(picture), "--report", str(notes)]) == 2
    assert "mine" in notes.read_text() and "not replaced" in capsys.readouterr().err
    data = tmp_path / "settings.json"
    data.write_text('{"tool_version": "mine"}')
    with pytest.raises(InputError, match="not replaced"):
        report_target(data, ".json")
    assert main(["check", str(picture), "--report", str(tmp_path / "sheet.html")]) in (0, 1)
    assert main(["check", str(picture), "--report", str(tmp_path / "sheet.html")]) in (0, 1)  # its own: replaced


def test_a_library_reports_pages_replace_only_its_own_and_leave_no_earlier_run_behind(tmp_path, capsys):
    """A file of the user's in the report's pages folder is refused before any work; a second run's report (one page,
    or fewer pages) removes the pages the earlier run wrote there that it no longer links."""
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    shutil.copytree(SAMPLES / "brick", tmp_path / "brick2")
    scenes = [str(tmp_path / "brick" / "scene.usda"), str(tmp_path / "brick2" / "scene.usda")]
    report = tmp_path / "out" / "report.html"
    pages = tmp_path / "out" / "report.files"
    pages.mkdir(parents=True)
    (pages / "0001-scene.html").write_text("<html>mine</html>")
    assert main(["process", *scenes, "--dry-run", "--report", str(report)]) == 2
    assert "0001-scene.html" in capsys.readouterr().err and (pages / "0001-scene.html").read_text() == "<html>mine</html>"
    assert not report.exists()
    (pages / "0001-scene.html").unlink()
    assert main(["process", *scenes, "--dry-run", "--report", str(report)]) == 0
    assert len(list(pages.glob("*.html"))) == 2
    assert main(["process", scenes[0], "--dry-run", "--report", str(report)]) == 0  # one source: one page
    assert report.is_file() and not pages.exists()


def test_an_empty_file_the_shell_made_for_stdout_is_no_users_file(tmp_path, capsys):
    """``process --report out/r.html --json > out/r.json``: the shell makes r.json empty before the run, and the run
    refused it as a file of the user's (exit 2). An empty file holds nothing to lose: the report's JSON goes there."""
    scene = tmp_path / "brick" / "scene.usda"
    shutil.copytree(SAMPLES / "brick", scene.parent)
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "run.json").write_text("")
    assert main(["process", str(scene), "--dry-run", "--report", str(tmp_path / "run.html")]) == 0
    capsys.readouterr()
    assert json.loads((tmp_path / "run.json").read_text())["stacks"] and (tmp_path / "run.html").exists()
