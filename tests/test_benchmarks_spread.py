"""The spread benchmark on a small real stack: the seam figures of one torus tile over its origins."""
from __future__ import annotations

import json

import numpy as np
import pytest

from benchscripts import load_benchmark


def test_origin_spread_reads_every_origin_of_the_same_tile():
    s = load_benchmark("spread")
    rng = np.random.default_rng(0)
    tile = rng.uniform(size=(40, 48))
    tile[:, 10] += 3.0  # one strong vertical line, at column 10 | 11
    spread = s.origin_spread(tile, False)
    x, y = spread["x"], spread["y"]
    # the line is a border or centre line at 4 of the 48 origins (either side of it, twice), and far above the target there
    assert x["max"] > 3.0 and x["min"] < 1.2 and x["min"] <= x["at_origin"] <= x["max"]
    assert abs(x["inside"] - (48 - 4) / 48) < 0.05
    assert y["max"] < 1.6 and 0.0 <= y["inside"] <= 1.0


def test_the_figure_at_each_origin_is_the_seam_ratio_of_the_rolled_tile():
    from seamless_usd import metrics as M

    s = load_benchmark("spread")
    rng = np.random.default_rng(1)
    for tile, is_normal in ((rng.uniform(size=(30, 37, 3)), False), (rng.normal(size=(26, 33, 3)), True)):
        for axis, label in ((1, "x"), (0, "y")):
            worst = s._worst_lines(tile, is_normal, axis)
            for k in (0, 1, 7, tile.shape[axis] - 1):
                rolled = np.roll(tile, k, axis=axis)
                expected = max(M.seam_ratios(rolled, is_normal)[f"seam_ratio_{label}"],
                               M.centre_seam_ratios(rolled, is_normal)[f"centre_seam_{label}"])
                assert worst[k] == pytest.approx(expected, rel=1e-9), (axis, k)


def test_the_script_writes_its_tables_for_a_real_stack(tmp_path):
    s = load_benchmark("spread")
    assert s.main(["--stacks", "cloth", "--max-size", "96", "--out", str(tmp_path)]) == 0
    data = json.loads((tmp_path / "spread.json").read_text())
    cloth = data["stacks"]["cloth"]
    assert set(cloth["origins"]) == {"lattice-cut", "refine-random"}  # the weave repeats
    for per_map in cloth["origins"].values():
        v = per_map["color"]["x"]
        assert v["min"] <= v["median"] <= v["max"] and 0.0 <= v["inside"] <= 1.0
    assert set(cloth["scale"]["color"]) == {"top_vs_bottom", "left_vs_right", "quadrant_min", "quadrant_max"}
    md = (tmp_path / "spread.md").read_text()
    assert "| cloth | lattice-cut | color |" in md and "Q over" not in md
