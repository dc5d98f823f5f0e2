"""A seam classifier fitted per stack on the source's own juxtapositions.

*True* juxtapositions are the source's own lines: every stretch of every line inside it, mortar joints
and plank edges included. *False* ones are joins the texture never makes: two places of the source
put side by side with a hard cut (at an arbitrary place, or on the same rows, as the wrap of a window
meets itself) or blended over a band (as a crossfade ghosts). A Fisher discriminant on the line
features (:mod:`.features`) separates the two; its score is given in units of the true lines' own
spread (a z-score), so 0 is an ordinary line of the texture and large values are joins.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .features import REACH, line_features as _features

__all__ = ["SeamClassifier", "fit"]

#: Synthetic joins per orientation used to fit the classifier.
JOINS = 72
_MAX_TRUE = 6000


def _blur_along(a: np.ndarray, periodic: bool) -> np.ndarray:
    """[1 2 1] / 4 along axis 0 (rows), twice: structures 2-4 px across. The ends wrap round (``periodic``)
    or repeat the end row; written with slices into one buffer (no rolled copies: it runs on every stretch
    of every synthetic join the classifier is fitted on)."""
    if a.shape[0] < 2:
        return np.asarray(a, dtype=np.result_type(a, np.float32)).copy()
    for _ in range(2):
        out = 0.5 * a
        out[1:] += 0.25 * a[:-1]
        out[:-1] += 0.25 * a[1:]
        out[0] += 0.25 * (a[-1] if periodic else a[0])
        out[-1] += 0.25 * (a[0] if periodic else a[-1])
        a = out
    return a


def line_features(u: np.ndarray, length: int, periodic: bool, step: int) -> np.ndarray:
    """Line features of ``u`` and of its derivative along the line, fine and blurred: the derivative sees
    the structures that cross the line (grain, joints) and whether they carry on across it."""
    diff = (lambda a: a - np.roll(a, 1, 0)) if periodic else (lambda a: np.concatenate([a[:1] * 0, np.diff(a, axis=0)], 0))
    d1 = diff(u)
    d2 = diff(_blur_along(u, periodic))
    return np.concatenate([_features(x, length, periodic, step) for x in (u, d1, d2)], axis=-1)


@dataclass
class SeamClassifier:
    """Per orientation (``"x"`` vertical lines, ``"y"`` horizontal), the discriminant and its scale."""

    weights: dict[str, np.ndarray]
    offset: dict[str, float]
    scale: dict[str, float]
    length: int
    step: int
    separation: dict[str, float]  # (mean false - mean true) in true-line units, on the fitting data

    def scores(self, u: np.ndarray, axis: str, periodic: bool = True) -> np.ndarray:
        """z-scores ``(stretches, lines)`` of every line stretch of ``u`` (see :func:`.features.line_features`)."""
        a = u if axis == "x" else u.transpose(1, 0, 2)
        f = line_features(a, self.length, periodic, self.step)
        return (f @ self.weights[axis] - self.offset[axis]) / self.scale[axis]


def _join(a: np.ndarray, b: np.ndarray, blend: int) -> np.ndarray:
    """``a`` then ``b`` side by side (each ``(h, 2 REACH, C)``): a hard cut, or a linear blend over ``blend`` px."""
    if blend <= 0:
        return np.concatenate([a, b], axis=1)
    w = a.shape[1]
    ramp = ((np.arange(2 * w) - (w - blend / 2) + 0.5) / blend).clip(0, 1)[None, :, None]
    wide_a = np.concatenate([a, a[:, ::-1]], axis=1)  # only the blend band reads past a's end
    wide_b = np.concatenate([b[:, ::-1], b], axis=1)
    return (1 - ramp) * wide_a + ramp * wide_b


def _false_features(src: np.ndarray, length: int, step: int, rng: np.random.Generator) -> np.ndarray:
    """Features of :data:`JOINS` synthetic joins of ``src``, read in one pass: the joins are stacked
    along the line into one image, cut to the :data:`REACH` columns each side of the join (the only line
    read; four times faster than reading every line of the blocks and keeping one), and only the stretches
    inside one join are kept. Its local contrast is thus against the joins' own sides, not against lines
    whose pairs reach across the join."""
    h, w, _ = src.shape
    side = 2 * REACH
    rows = min(h, 4 * length)
    blocks = []
    for n in range(JOINS):
        y1, y2 = rng.integers(0, h - rows + 1, 2)
        x1, x2 = rng.integers(0, w - side + 1, 2)
        if n % 3 == 1:
            y2 = y1  # the same rows from elsewhere: a window's wrap meeting itself
        while abs(int(x2) - int(x1)) < side // 2 and w > 2 * side:
            x2 = rng.integers(0, w - side + 1)
        blend = int(rng.integers(4, 2 * REACH)) if n % 3 == 2 else 0
        joined = _join(src[y1:y1 + rows, x1:x1 + side], src[y2:y2 + rows, x2:x2 + side], blend)
        blocks.append(joined[:, side - REACH: side + REACH])  # the join's line is the one line read
    f = line_features(np.concatenate(blocks, axis=0), length, periodic=False, step=step)
    starts = np.arange(f.shape[0]) * step
    inside = (starts % rows) + length <= rows
    return f[inside, 0]


def fit(source: np.ndarray, length: int, step: int, seed: int = 0) -> SeamClassifier:
    """Fit the classifier on ``source`` (H, W, C), for stretches of ``length`` px read every ``step`` px."""
    rng = np.random.default_rng(seed)
    weights, offset, scale, separation = {}, {}, {}, {}
    for axis in ("x", "y"):
        src = source if axis == "x" else source.transpose(1, 0, 2)
        true = line_features(src, length, periodic=False, step=step)
        true = true.reshape(-1, true.shape[-1])
        if len(true) > _MAX_TRUE:
            true = true[rng.choice(len(true), _MAX_TRUE, replace=False)]
        false = _false_features(src, length, step, rng)
        mt, mf = true.mean(0), false.mean(0)
        cov = 0.5 * (np.cov(true, rowvar=False) + np.cov(false, rowvar=False))
        n = cov.shape[0]
        cov += np.eye(n) * (1e-3 * np.trace(cov) / n + 1e-9)
        wv = np.linalg.solve(cov, mf - mt)
        t_proj = true @ wv
        weights[axis] = wv
        offset[axis] = float(np.median(t_proj))
        scale[axis] = float(max(np.percentile(t_proj, 84) - np.percentile(t_proj, 16), 1e-9) / 2)
        separation[axis] = float((np.median(false @ wv) - offset[axis]) / scale[axis])
    return SeamClassifier(weights, offset, scale, length, step, separation)
