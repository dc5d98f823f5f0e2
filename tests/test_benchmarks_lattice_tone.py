"""The tone lever's benchmark on the bundled brick sample: levelled, its texels are no longer copies the
verdict can place, which is why the lever is not kept."""
from __future__ import annotations

import json

from benchscripts import load_benchmark


def test_levelling_the_tone_leaves_the_verdict_few_copies_to_place(tmp_path):
    tone = load_benchmark("lattice_tone")
    assert tone.main(["--items", "brick", "--out", str(tmp_path)]) == 0
    row = json.loads((tmp_path / "lattice_tone.json").read_text())["rows"][0]
    assert row["cut"] == "lattice" and row["plain"]["passed"]
    assert row["plain"]["changed"] == 0 and row["plain"]["placed"] > 0.99
    assert row["matched"]["changed"] > 0.9 and row["matched"]["placed"] < 0.5
    assert (tmp_path / "lattice_tone" / "brick.jpg").stat().st_size > 1000
    assert "| brick | lattice |" in (tmp_path / "lattice_tone.md").read_text()


def test_levelling_removes_the_light_step_where_a_cut_joins_copies_a_tile_apart():
    """A pattern of period 10 lit by a ramp: the first 4 columns taken one tile on are 0.4 brighter than their
    neighbours; levelled, the step across the cut is the pattern's own to within 0.1."""
    import numpy as np

    tone = load_benchmark("lattice_tone")
    _, x = np.mgrid[0:60, 0:60].astype(np.float32)
    wall = (np.sin(2 * np.pi * x / 10) + 0.01 * x)[..., None]
    field = np.stack(np.mgrid[0:40, 0:40], -1) + 5
    field[:, :4, 1] += 40
    plain = wall[field[..., 0], field[..., 1]]
    matched = tone.tone_matched([wall], [False], field, (5, 5), (40, 40), (8, 8))[0]
    step = lambda t: float(np.abs(t[:, 4] - t[:, 3] - (wall[0, 9] - wall[0, 8])).max())  # noqa: E731
    assert round(step(plain), 2) == 0.4 and step(matched) < 0.1
