"""Lines across which a texture does not continue: a texture judged on its own, by how well the rows on either
side of each line predict each other, against the line that comes next.

Inside a texture, neighbouring rows are alike: the difference between two rows one texel apart is smaller than
between rows two or three apart (the texture's own correlation). Across a join of unrelated places (a plain
window's wrap, a half-rolled window's centre) the two rows that meet are no more alike than rows further apart
across it: the join's one-texel difference is as large as its two- and three-texel ones. So each line gets its
*continuation ratio*: the mean difference of the row pair that straddles it one texel apart, over the mean of
the pairs two and three texels apart that straddle it (the maps together, as the verdict weighs them, at the
line breaks' working size). The line with the highest ratio is a seam when its ratio stands more than
:data:`MARGIN` times above the next-highest line's (lines within :data:`SPACING` of it left out): a texture's own
edges (mortar, plank gaps) come many alike, so the next line is one of them; a lone wrap stands above them.

The line breaks (:mod:`.breaks`) read the same pairs as robust z-scores over every parallel line and miss a
lone join in a texture of soft detail (a forest floor, a lit brick window) whose spread over the lines is
wide; this ratio reads the join against the texture's own next line. Its margin was set on the tuning parts
of ``benchmarks/texture_verdict.py`` and ``benchmarks/photo_verdict.py`` (their seamless pictures read at most
1.23) and measured on the held-back parts (``docs/decisions.md``, "The continuation ratio").
"""
from __future__ import annotations

import numpy as np

from .breaks import peaks, straddle, working
from .lines import Seam
from .prepare import joint

__all__ = ["MARGIN", "SPACING", "continuation_ratios", "unrelated_lines"]

#: The strongest line's continuation ratio over the next line's above which it is a seam.
MARGIN = 1.25
#: Lines closer than this (px at the working size) to a stronger line are the same line.
SPACING = 4


def continuation_ratios(img: np.ndarray) -> np.ndarray:
    """(H,): for the line before each row of ``img`` (H, W, C; periodic), the mean difference of the straddling row
    pair one texel apart over the mean of the straddling pairs two and three texels apart (:func:`.breaks.straddle`)."""
    eps = 1e-12
    return (straddle(img, 1) + eps) / (0.5 * (straddle(img, 2) + straddle(img, 3)) + eps)


def unrelated_lines(prepared: list[np.ndarray], units: float = 1.0,
                    work: tuple[list[np.ndarray], list[float]] | None = None) -> tuple[list[Seam], float]:
    """Seams of a texture judged on its own (``prepared``: its maps in the verdict's form; read together, at the
    line breaks' working size), at most one per axis, strongest first, and the strongest line's figure. Figures
    are the strongest line's ratio over the next line's, scaled so that ``units`` is :data:`MARGIN` (the verdict
    reports them on its own margin's scale); a seam runs the whole line. ``work``: :func:`.breaks.working` of
    ``prepared`` when it is made already."""
    size = prepared[0].shape[:2]
    img = joint(*(work or working(prepared)))
    seams: list[Seam] = []
    strongest = -np.inf
    for axis, rotated in (("y", img), ("x", img.transpose(1, 0, 2))):
        n = rotated.shape[0]
        if n < 4 * SPACING:
            continue
        ratios = continuation_ratios(rotated)
        found = peaks(ratios, SPACING)  # the strongest line, then the next one more than SPACING from it
        top = found[0]
        figure = float(ratios[top]) / float(ratios[found[1] if len(found) > 1 else top]) * units / MARGIN
        strongest = max(strongest, figure)
        if figure > units:
            across, along = (size[0], size[1]) if axis == "y" else (size[1], size[0])
            seams.append(Seam(axis, int(round(top * across / n)) % across, 0, along - 1, figure, "stack"))
    seams.sort(key=lambda s: -s.figure)
    return seams, float(strongest)
