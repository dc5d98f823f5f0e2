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


def moving_mean(a: np.ndarray, length: int, periodic: bool, step: int = 1) -> np.ndarray:
    """Moving mean of ``a`` (along, ...) over ``length`` rows, from cumulative sums: periodic wraps (one
    mean per row, starting there), else only whole windows; every ``step``-th window."""
    rows = a.shape[0]
    if step > 1 and length % step == 0 and (rows % step == 0 or not periodic) and rows >= length:
        # every window is whole groups of ``step`` rows: sum the groups first, a ``step`` times shorter cumsum
        whole = rows - rows % step
        groups = np.array(a[0:whole:step], dtype=np.float64)  # the rows of each group added one by one
        for k in range(1, step):
            groups += a[k:whole:step]
        return moving_mean(groups, length // step, periodic) * (1 / step)
    if periodic:
        a = np.concatenate([a, a[: length - 1]], axis=0)
    c = np.empty((a.shape[0] + 1,) + a.shape[1:])
    c[0] = 0
    np.cumsum(a, axis=0, dtype=np.float64, out=c[1:])
    return (c[length::step] - c[: c.shape[0] - length: step]) / length


def _square_norm(a: np.ndarray) -> np.ndarray:
    """Sum of squares over the last axis, channel by channel (a few channels: three times faster than
    ``einsum`` or ``(a ** 2).sum(-1)``)."""
    out = np.square(a[..., 0])
    for k in range(1, a.shape[-1]):
        out += np.square(a[..., k])
    return out


def _columns(a: np.ndarray, start: int, count: int) -> np.ndarray:
    """``count`` columns of ``a`` from ``start``, as a view."""
    return a[:, start: start + count]


def _column_sums(a: np.ndarray) -> np.ndarray:
    """Cumulative sums along the columns with a leading zero: ``sum(a[:, i: j])`` is ``c[:, j] - c[:, i]``."""
    c = np.zeros((a.shape[0], a.shape[1] + 1))
    np.cumsum(a, axis=1, out=c[:, 1:])
    return c


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
        first, count = REACH, w
    else:
        ext = u
        first, count = REACH, w - 2 * REACH + 1

    feats, within_all = [], []
    for d in DISTANCES:
        # pairs (c - j, c - j + d), j = 1..d, cross the line at c; (c - j - d, c - j) lie on its left and
        # (c + j - 1, c + j - 1 + d) on its right: three windows of d pair positions, read from the columns
        # c - 2d .. c + 2d only (a narrow image, such as the classifier's stacked joins, is mostly outside them)
        near = ext[:, first - 2 * d: first + count + 2 * d]
        sq = moving_mean(_square_norm(near[:, d:] - near[:, :-d]), length, periodic, step)  # pair (x, x + d)
        cs = _column_sums(sq)  # its column 2d is the first line's
        straddle = (_columns(cs, 2 * d, count) - _columns(cs, d, count)) / d
        within = 0.5 * ((_columns(cs, d, count) - _columns(cs, 0, count))
                        + (_columns(cs, 3 * d, count) - _columns(cs, 2 * d, count))) / d
        log_within = np.log(within + _EPS)
        feats.append(np.log(straddle + _EPS) - log_within)
        within_all.append((within, log_within))
    for within, log_within in within_all:  # local contrast against the image's own
        feats.append(log_within - np.log(np.median(within) + _EPS))
    step1 = _columns(ext, first, count) - _columns(ext, first - 1, count)  # (H, lines, C)
    mean_step = moving_mean(step1.reshape(h, -1), length, periodic, step).reshape(-1, count, channels)
    energy = moving_mean(_square_norm(step1), length, periodic, step)
    feats.append(_square_norm(mean_step) / (energy + _EPS))  # 1: one coherent step along the stretch
    return np.stack(feats, axis=-1)
