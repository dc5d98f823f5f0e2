"""Line features: how the texels on the two sides of a line relate, compared with how texels on one side
relate at the same distance, per stretch of the line.

For a vertical line between columns ``c - 1`` and ``c`` and a stretch of rows, the *straddling*
variogram at distance ``d`` is the mean squared difference of texel pairs ``d`` apart that lie on
both sides of the line, the *within* variogram the same over pairs on one side. Across a texture's
own line (a mortar joint, a plank edge) both follow the texture's statistics; across a join of two
unrelated places the straddling pairs are as different as unrelated texels are, at every distance.
The features are the log ratios of the two at distances 1, 2, 4 and 8, the local contrast against the
whole image's, and how much of the step across the line is one coherent step (a straight edge).
Every figure is a moving mean along the line, from cumulative sums, so all lines and stretches of an
image cost a few array passes.
"""
from __future__ import annotations

import numpy as np

__all__ = ["DISTANCES", "FEATURES", "line_features", "moving_mean"]

DISTANCES = (1, 2, 4, 8)
FEATURES = 2 * len(DISTANCES) + 1
#: Columns a line needs on each side for every pair of the features.
REACH = 2 * max(DISTANCES)
_EPS = 1e-6


def moving_mean(a: np.ndarray, length: int, periodic: bool) -> np.ndarray:
    """Moving mean of ``a`` (along, ...) over ``length`` rows, from cumulative sums: periodic wraps (one
    mean per row, starting there), else only whole windows."""
    if periodic:
        a = np.concatenate([a, a[: length - 1]], axis=0)
    c = np.cumsum(a, axis=0, dtype=np.float64)
    c = np.concatenate([np.zeros((1,) + a.shape[1:]), c], axis=0)
    return (c[length:] - c[:-length]) / length


def line_features(u: np.ndarray, length: int, periodic: bool, step: int = 1) -> np.ndarray:
    """Features of every vertical line of ``u`` (H, W, C) over every stretch of ``length`` rows.

    Returns ``(stretches, lines, FEATURES)``: stretch ``s`` covers rows ``s * step`` to
    ``s * step + length - 1`` (periodic: wrapping); line ``j`` lies between columns ``j - 1`` and ``j``
    (periodic: every ``j`` in ``0 .. W - 1``, 0 being the wrap; otherwise the lines with :data:`REACH`
    columns on both sides, line index ``i`` being ``j = REACH + i``). Transpose ``u`` for horizontal lines.
    """
    h, w, channels = u.shape
    if periodic:
        ext = np.concatenate([u[:, w - REACH:], u, u[:, :REACH]], axis=1)
        lines = np.arange(w) + REACH
    else:
        ext = u
        lines = np.arange(REACH, w - REACH + 1)
    feats, within_all = [], []
    for d in DISTANCES:
        sq = moving_mean(((ext[:, d:] - ext[:, :-d]) ** 2).sum(-1), length, periodic)[::step]  # pair (x, x + d)
        straddle = np.zeros((sq.shape[0], len(lines)))
        within = np.zeros_like(straddle)
        for j in range(1, d + 1):
            straddle += sq[:, lines - j]  # pairs (c - j, c - j + d) cross the line at c
            within += 0.5 * (sq[:, lines - j - d] + sq[:, lines + j - 1])  # pairs on the left, on the right
        straddle /= d
        within /= d
        feats.append(np.log(straddle + _EPS) - np.log(within + _EPS))
        within_all.append(within)
    for within in within_all:  # local contrast against the image's own
        feats.append(np.log(within + _EPS) - np.log(np.median(within) + _EPS))
    step1 = ext[:, lines] - ext[:, lines - 1]  # (H, lines, C)
    mean_step = moving_mean(step1.reshape(h, -1), length, periodic)[::step].reshape(-1, len(lines), channels)
    energy = moving_mean((step1 ** 2).sum(-1), length, periodic)[::step]
    feats.append((mean_step ** 2).sum(-1) / (energy + _EPS))  # 1: one coherent step along the stretch
    return np.stack(feats, axis=-1)
