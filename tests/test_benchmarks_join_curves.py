"""Copy runs read along a cut (benchmarks/join_curves.py): a meandering quilt join of stone cells reads stronger
along the cut than along straight lines; a straight join reads the same either way."""
from __future__ import annotations

import numpy as np

from benchscripts import load_benchmark


def test_runs_along_the_cut_read_a_quilts_joins_stronger_than_straight_runs():
    curves = load_benchmark("join_curves")
    synthetic = load_benchmark("synthetic")
    from seamless_usd.synthesis.lattice.quilt import best_quilt

    stack = synthetic.cells(160, 40, seed=8)
    maps, normals = [v[0] for v in stack.values()], [v[1] for v in stack.values()]
    field, _ = best_quilt(maps, (160, 160), (2, 2), 3)
    figures = curves.curve_figures([m[field[..., 0], field[..., 1]] for m in maps], maps, normals, 32)
    assert figures is not None and figures[4] > 1.5 * figures[0] and figures[4] > 1.2, figures
    roll = [np.roll(m, (37, 51), (0, 1)) for m in maps]  # one join per axis, straight: read the same either way
    straight = curves.curve_figures(roll, maps, normals, 32)
    assert straight[4] < 1.5 * straight[0] + 0.1, straight
