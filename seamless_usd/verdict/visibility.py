"""Whether a seam can be seen at all: the step of value across its line, in the maps' own units.

The verdict's figures are relative: a line is read against the texture's other lines, in units of their
spread. On a map that is nearly flat (a roughness, metallic or opacity map of one value, with a patch or a row
one code value off) every line but a few reads exactly nothing, so those few read millions of units above the
rest though no eye can see them. A seam is kept only where the maps step across its line, over its run, by at
least :data:`VISIBLE`: at some width (:data:`WIDTHS`), the mean of the texels on one side against the mean on the
other, texel by texel along the run, so that a one-texel break, a jumble of unrelated texels and a broad step of
tone all count. The step is read as it is, not against the texture's other lines: on a textured map every line
steps by far more than that (a seam's step there is as large as any line's, and is told apart by the verdict's
own figures), so only lines of a nearly flat map are dropped. A ghosted band (a crossfade's fading detail) is
not a step and is kept as found.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .lines import Seam

__all__ = ["VISIBLE", "CODE_8BIT", "WIDTHS", "step_across", "visible", "floor"]

#: The least step (network units, where a map spans 2) a seam must show over a typical line: one and a half 8-bit
#: code values, under which a step of value is not seen on a flat surface.
VISIBLE = 2 * 1.5 / 255
#: One code value of an 8-bit file in network units: the step a map is taken to be stored in unless told otherwise.
CODE_8BIT = 2 / 255
#: Widths (texels at the reading's size) of the bands read on each side of a line.
WIDTHS = (1, 2, 4, 8, 16)


def step_across(m: np.ndarray, axis: str, line: int, start: int, end: int) -> float:
    """The step across ``line`` of map ``m`` (H, W, C; ``axis`` ``"x"``: a vertical line at column ``line`` over
    rows ``start`` to ``end``, on a torus), at the band width where it is largest: the mean over the run of the
    norm of (mean of the ``width`` lines after it) less (mean of the ``width`` lines before it)."""
    a = m if axis == "y" else m.transpose(1, 0, 2)
    n, length = a.shape[:2]
    run = np.arange(start, end + 1) % length
    best = -np.inf
    for width in WIDTHS:
        if width > n // 4:
            break
        after = a[(line + np.arange(width)) % n][:, run].mean(axis=0)
        before = a[(line - width + np.arange(width)) % n][:, run].mean(axis=0)
        best = max(best, float(np.sqrt(((after - before) ** 2).sum(axis=-1)).mean()))
    return best


def floor(m: np.ndarray, code: float) -> float:
    """The least step a seam must show in map ``m`` (network units) stored in steps of ``code`` (network units of
    one code value; 0 for half and float files).

    An 8-bit map's is :data:`VISIBLE`, one and a half of its codes: finer steps are rounding, not a picture. A map
    stored finer (16-bit, half, float) holds values whose size only the shader's scale gives meaning to (a
    displacement map spanning a centimetre in scene units, 0.01 of a float): its floor is the same share of its own
    span (largest less smallest value), never under one and a half of its codes and never over :data:`VISIBLE`.
    Read against 8-bit codes such a map is flat, and a plain seam across it read as nothing."""
    if code >= CODE_8BIT * (1 - 1e-6):  # 8 bits (or coarser), however the code value was computed
        return VISIBLE
    span = float(m.max() - m.min()) if m.size else 0.0
    return min(VISIBLE, max(VISIBLE * span / 2, 1.5 * code))


def visible(seams: Sequence[Seam], maps: Sequence[np.ndarray], names: Sequence[str], factor: float,
            codes: Sequence[float] | None = None) -> list[Seam]:
    """The ``seams`` (positions in texels of the full size) whose step can be seen in ``maps`` (the maps at
    ``factor`` times the full size, in network units: normal maps as unit vectors), in the named map or, for a
    seam of the maps together, in any of them, each against its :func:`floor` (``codes``: each map's code value,
    8-bit where not given); ghosted bands are kept as found."""
    floors = [floor(m, c) for m, c in zip(maps, codes or [CODE_8BIT] * len(maps))]
    kept = []
    for s in seams:
        if s.kind == "ghost":
            kept.append(s)
            continue
        chosen = [(m, f) for m, f, name in zip(maps, floors, names) if name == s.map] or list(zip(maps, floors))
        line, start, end = (int(round(v * factor)) for v in (s.position, s.start, s.end))
        if any(step_across(m, s.axis, line, start, max(start, end)) >= f for m, f in chosen):
            kept.append(s)
    return kept
