"""The triage's pixel figures kept between runs (discover/triagememo.py): taken back for the same bytes,
measured again when a file changes or a kept figure is unreadable, and the decision is the same either way."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd.discover import open_stage, scan_stage

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _library(tmp_path: Path) -> Path:
    """The bundled already-tileable floor (a wood texture made to repeat, colour and roughness) in a copy."""
    shutil.copytree(SAMPLES / "tileable", tmp_path / "tileable")
    (tmp_path / "textures").mkdir()
    for name in ("wood_tileable.jpg", "wood_tileable_roughness.jpg"):
        shutil.copy(SAMPLES / "textures" / name, tmp_path / "textures" / name)
    return tmp_path / "tileable" / "floor.usda"


def _decision(scene: Path, memo: Path) -> tuple[str, str]:
    [stack] = scan_stage(open_stage(scene), memo).stacks
    return stack.intent, stack.intent_reason


def test_figures_are_kept_by_content_and_taken_back(tmp_path):
    scene, memo = _library(tmp_path), tmp_path / "triage"
    first = _decision(scene, memo)
    assert first[0] == "already-tileable", first
    kept = sorted(memo.rglob("*.json"))
    kinds = sorted(json.loads(p.read_text())["kind"] for p in kept)
    assert kinds == ["verdict"]  # the stack's maps judged together against themselves, as `check` judges them
    # a second scan reads it back: a kept verdict changed by hand is what it decides on
    [kept_verdict] = kept
    body = json.loads(kept_verdict.read_text())
    verdict = body["value"]["verdict"]
    planted = {"map": "stack", "axis": "x", "position": 17, "start": 0, "end": 99, "figure": 3.5}
    kept_verdict.write_text(json.dumps({**body, "value": {"verdict": {
        **verdict, "seamless": False, "passed": False, "seams": [planted]}}}))
    intent, reason = _decision(scene, memo)
    assert intent == "tiling" and "(+3.50)" in reason, reason
    # an unreadable figure is measured again, and the decision is the first one
    kept_verdict.write_text("{not json")
    assert _decision(scene, memo) == first
    assert json.loads(kept_verdict.read_text())["value"] == body["value"]


def test_a_file_that_changes_is_measured_again(tmp_path):
    scene, memo = _library(tmp_path), tmp_path / "triage"
    assert _decision(scene, memo)[0] == "already-tileable"
    # the colour map edited in place (same name, same size): its right half turned upside down, so its wrap and
    # its middle join texels that were not neighbours
    path = tmp_path / "textures" / "wood_tileable.jpg"
    buf = oiio.ImageBuf(str(path))
    px = buf.get_pixels(oiio.UINT8)
    h, w = px.shape[:2]
    window = np.ascontiguousarray(np.concatenate([px[:, :w // 2], px[::-1, w // 2:]], axis=1))
    out = oiio.ImageBuf(buf.spec())
    out.set_pixels(oiio.ROI(0, w, 0, h, 0, 1, 0, px.shape[2]), window)
    assert out.write(str(path))
    intent, reason = _decision(scene, memo)
    assert intent == "tiling", reason
