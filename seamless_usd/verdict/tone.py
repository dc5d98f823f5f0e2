"""Broad tone steps: a line where the tile's tone changes by more than the source's tone ever changes.

Copies of a photo lit unevenly meet where its light differs: a dark copy beside a bright one. At 1x that is
how a seam looks, a long straight edge of tone, even where every texel along it continues its neighbour as
well as the texture's own texels do (gravel, grass: the copy and classifier rules judge texel against
texel, and a step of a tenth of the texture's contrast is lost in it). This rule reads tone, not texels:

- the *strip step* of a line over a run: the mean of the :data:`STRIP` texels on one side of the line minus
  the mean on the other side, each averaged over :data:`RUN_LENGTH` texels along the line (all maps
  together, at the verdict's working resolution), as a vector's length;
- the source's own strongest strip step, over every line and run of it (not wrapping: its own border is
  not a line of it), is the reference; a texture's own joints and plank gaps are in it;
- a tile's line whose strip step exceeds the reference by more than :data:`TONE_MARGIN` (a share of it)
  is a seam, reported with its figure (the share above the reference, less the margin).

The tile is read as it repeats, so a step at its wrap counts like one inside. A tile that is the source
rolled, or made of its copies with joins that hide, reads about 1: its strongest strip is the source's.
"""
from __future__ import annotations

import numpy as np

from .lines import Seam

__all__ = ["STRIP", "RUN_LENGTH", "TONE_MARGIN", "strip_steps", "tone_reference", "tone_steps"]

#: Texels (working resolution) on each side of a line whose means are compared.
STRIP = 8
#: Texels (working resolution) along the line over which the strips are averaged.
RUN_LENGTH = 64
#: A line whose strip step exceeds the source's strongest by more than this share of it is a seam.
TONE_MARGIN = 0.15


def strip_steps(img: np.ndarray, periodic: bool, strip: int = STRIP, length: int = RUN_LENGTH) -> np.ndarray:
    """(runs, lines): the strip step (see the module notes) across each vertical line of ``img`` (H, W, C), over
    each run of ``length`` rows. Periodic: every line and run, wrapping (line x lies before column x); otherwise
    only those whose strips and run lie inside."""
    H, W, C = img.shape
    strip, length = min(strip, max(1, W // 4)), min(length, H)
    ext = np.concatenate([img[:, -strip:], img, img[:, :strip]], 1) if periodic else img
    sums = np.concatenate([np.zeros((H, 1, C)), np.cumsum(ext, axis=1, dtype=np.float64)], axis=1)
    xs = np.arange(W) + strip if periodic else np.arange(strip, W - strip + 1)
    step = (sums[:, xs + strip] - 2 * sums[:, xs] + sums[:, xs - strip]) / strip  # right mean - left mean
    if periodic:
        step = np.concatenate([step, step[: length - 1]], axis=0)
    along = np.concatenate([np.zeros((1,) + step.shape[1:]), np.cumsum(step, axis=0)], axis=0)
    n = H if periodic else H - length + 1
    return np.linalg.norm((along[length: length + n] - along[:n]) / length, axis=-1)


def tone_reference(source: np.ndarray) -> dict[str, float]:
    """The source's strongest strip step (working resolution, not wrapping) across vertical (``"x"``) and
    horizontal (``"y"``) lines."""
    return {"x": float(strip_steps(source, periodic=False).max()) + 1e-9,
            "y": float(strip_steps(source.transpose(1, 0, 2), periodic=False).max()) + 1e-9}


def tone_steps(tile: np.ndarray, reference: dict[str, float], factor: float, size: tuple[int, int],
               name: str = "stack", limit: int = 4) -> list[Seam]:
    """Seams of broad tone steps in ``tile`` (working resolution, periodic) against the source's strongest strip
    steps (:func:`tone_reference`), in texels of the tile at full resolution (``factor`` = working / full,
    ``size`` its (h, w)), strongest first."""
    h, w = size
    found: list[Seam] = []
    for axis in ("x", "y"):
        t = tile if axis == "x" else tile.transpose(1, 0, 2)
        ratio = strip_steps(t, periodic=True) / reference[axis]  # (runs, lines)
        peak = ratio.max(axis=0)
        taken: list[int] = []
        for line in np.argsort(-peak):
            if peak[line] - 1.0 <= TONE_MARGIN or len(taken) >= limit:
                break
            if any(min(abs(line - k), len(peak) - abs(line - k)) <= STRIP for k in taken):
                continue
            taken.append(int(line))
            above = np.nonzero(ratio[:, line] - 1.0 > TONE_MARGIN)[0]
            along, across = (h, w) if axis == "x" else (w, h)
            run = min(RUN_LENGTH, t.shape[0])
            lo = int(above.min() / factor)
            hi = min(along - 1, int((above.max() + run) / factor))
            found.append(Seam(axis, int(round(line / factor)) % across, lo, hi,
                              float(peak[line] - 1.0 - TONE_MARGIN), name, "tone"))
    found.sort(key=lambda x: -x.figure)
    return found
