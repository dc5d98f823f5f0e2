"""The line breaks (verdict/breaks.py) on real photos: a texture's own joints are not seams, a window's wrap is;
and the benchmark that measures the verdict on real photos judged on their own."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
from PIL import Image

from benchscripts import load_benchmark
from seamless_usd.verdict import judge
from seamless_usd.verdict.alone import FileMap, judge_alone, read_alone, reduce_bins
from seamless_usd.verdict.breaks import groove, lag_figures, line_breaks, line_period, period
from seamless_usd.verdict.prepare import joint, map_weights, prepare_maps, to_working

PHOTOS = Path(__file__).resolve().parents[1] / "benchmarks" / "photos"


def _reading(name: str, window: bool = False) -> np.ndarray:
    """The photo at 256 px as the verdict reads it (network domain); ``window``: its middle 75 %, not tileable."""
    a = np.asarray(Image.open(PHOTOS / name).convert("RGB"), dtype=np.float64) / 255.0
    if window:
        h, w = a.shape[:2]
        a = a[h // 10:h // 10 + 3 * h // 4, w // 10:w // 10 + 3 * w // 4]
    return 2.0 * reduce_bins(a, (256, 256)) - 1.0


def _rows(picture: np.ndarray) -> np.ndarray:
    work = to_working(prepare_maps([picture], [False]), 1.0, periodic=True)
    return joint(work, map_weights(work))


def test_large_slabs_joints_are_grooves_not_seams():
    """Stone slabs made to tile (Poly Haven marble_01): four courses, too few for their joints to recur as a
    grid's do, so the joints are read across: narrow bands beyond both sides, the sides alike in tone."""
    slabs = _reading("tiles_marble_slabs_1.jpg")
    rows = _rows(slabs)
    assert period(256, rows.reshape(256, -1)) is None
    profile = np.linalg.norm(rows - np.roll(rows, 1, axis=0), axis=-1).mean(axis=1)
    joint_line = int(np.argmax(profile))  # the strongest horizontal joint
    assert groove(rows, joint_line)
    seams, _ = line_breaks(prepare_maps([slabs], [False]), ["slabs"])
    assert not seams, seams
    # rolled by half, the same texture: no seam either (the joints moved, none was made)
    seams, _ = line_breaks(prepare_maps([np.roll(slabs, (128, 128), (0, 1))], [False]), ["slabs"])
    assert not seams, seams


def test_joints_that_recur_where_the_stones_do_not_are_the_textures_own():
    """A wall of irregular stones set in panels (Poly Haven, made to tile): its rows do not repeat, so the rows'
    autocorrelation finds no period, but the panels' joints recur every sixth of the height. Read from the lines
    themselves, that spacing makes each joint the texture's own; `check` called the wall seamed along one of them
    (+0.50 over the margin) before."""
    path = PHOTOS / "stones_wall_1.jpg"
    verdict, _ = judge_alone([FileMap(str(path))])
    assert verdict.seamless, verdict.reasons()
    picture = read_alone(FileMap(str(path)))[0]
    rows = _rows(picture)
    n = rows.shape[0]
    assert period(n, rows.reshape(n, -1)) is None
    spacing = line_period(lag_figures(rows))
    assert spacing is not None and abs(spacing - n / 6) <= 3, spacing
    # the same photo's window: its wrap is not at a joint's place, and is still a seam
    window = picture[n // 10: n // 10 + 3 * n // 4, n // 10: n // 10 + 3 * n // 4]
    assert not judge([window], None, [False], ["wall"], fidelity=False).seamless


def test_a_window_wrap_is_a_seam_and_not_a_groove():
    for name in ("tiles_marble_slabs_1.jpg", "fruit_berries_1.jpg", "stones_wall_1.jpg"):
        window = _reading(name, window=True)
        verdict = judge([window], None, [False], [name], fidelity=False)
        assert not verdict.seamless and verdict.strongest > verdict.margin, name
    berries = _rows(_reading("fruit_berries_1.jpg", window=True))
    assert not groove(berries, 0)  # the wrap joins unrelated berries: a jumble, not a band


def test_the_photo_benchmark_judges_each_variant_from_a_file(tmp_path):
    bench = load_benchmark("photo_verdict")
    photos = tmp_path / "photos"
    photos.mkdir()
    for name in ("sand_coast_1.jpg", "food_peas_1.jpg"):
        shutil.copy(PHOTOS / name, photos / name)
    shutil.copy(PHOTOS / "SOURCES.md", photos / "SOURCES.md")
    assert bench.main(["--photos", str(photos), "--out", str(tmp_path / "out")]) == 0
    data = json.loads((tmp_path / "out" / "photo_verdict.json").read_text())
    kinds = {(r["photo"], r["kind"]): r for r in data["items"]}
    assert set(kinds) == {("sand_coast_1.jpg", k) for k in ("whole", "rolled", "turned", "window", "half-roll")} | {
        ("food_peas_1.jpg", k) for k in ("whole", "window", "half-roll")}
    assert kinds[("sand_coast_1.jpg", "whole")]["seamless"] and not kinds[("food_peas_1.jpg", "whole")]["seamless"]
    # the peas do not tile: every variant's seam is found, and located
    for k in ("whole", "window", "half-roll"):
        seamed, _, _, where = kinds[("food_peas_1.jpg", k)]["rules"]["verdict"]
        assert seamed and "line at" in where, k
    assert "| sand_coast_1-whole |" in (tmp_path / "out" / "photo_verdict.md").read_text()
