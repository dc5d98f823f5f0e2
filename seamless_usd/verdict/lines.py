"""Seams as the verdict reports them: where a run of line stretches scores like a join.

A line's stretches are scored by the stack's classifier (:mod:`.classifier`); a *run* is the mean
score over :data:`RUN` consecutive stretches (64 px at the working resolution), so one odd stretch is
not a seam, while a join as short as a copied block's edge is. The tile is read as it repeats, so its
wrap lines, centre lines and every interior line are judged alike.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .features import moving_mean

__all__ = ["RUN", "Seam", "figure_text", "runs", "seams_from_scores"]

#: Stretches averaged into a run (each stretch starts ``step`` px after the last).
RUN = 16


def figure_text(figure: float) -> str:
    """A seam's figure, signed, to two decimals unless that would read zero (then to its first digit).

    >>> figure_text(0.4567), figure_text(0.002), figure_text(0.0)
    ('+0.46', '+0.002', '+0.00')
    """
    return f"{figure:+.2f}" if abs(figure) >= 0.005 or figure == 0 else f"{figure:+.1g}"


@dataclass(frozen=True)
class Seam:
    """A seam found in a tile, in texels of the tile at full resolution.

    ``axis`` ``"x"``: a vertical line at column ``position`` (between ``position - 1`` and ``position``,
    0 being the wrap), over rows ``start`` to ``end``; ``"y"``: a horizontal line at row ``position``
    over columns ``start`` to ``end``. ``figure`` is how far the run scores above the strongest run of
    the reference's own lines (classifier units; above the verdict's margin is a seam). ``kind``
    ``"ghost"``: not a line but a band centred there, where the tile's detail fades against its source's
    (:mod:`.ghosts`: a crossfade); ``"tone"``: a broad step of tone along the line, larger than any in the source
    (:mod:`.tone`; its figure is the share above the source's strongest, less the margin)."""

    axis: str
    position: int
    start: int
    end: int
    figure: float
    map: str = "stack"  # the map it was found in, or "stack" for the maps together
    kind: str = "line"  # "line"; "ghost": a ghosted band centred on the line; "tone": a broad step of tone

    def where(self, size: tuple[int, int]) -> str:
        """Words for the report: ``"vertical line at x=256 (the centre), rows 0-511"``."""
        h, w = size
        n = w if self.axis == "x" else h
        line = "vertical line at x" if self.axis == "x" else "horizontal line at y"
        if self.kind == "ghost":
            line = "ghosted band (detail fading) around " + line
        elif self.kind == "tone":
            line = "step of tone along " + line
        place = " (the wrap)" if self.position in (0, n) else " (the centre)" if abs(self.position - n / 2) <= 2 else ""
        span = "rows" if self.axis == "x" else "columns"
        return f"{line}={self.position}{place}, {span} {self.start}-{self.end}"

    @property
    def above(self) -> str:
        """The figure in words: how far above the margin, never "+0.00" (a seam just over it reads "+0.002")."""
        return figure_text(self.figure)

    def as_dict(self) -> dict:
        out = {"map": self.map, "axis": self.axis, "position": self.position, "start": self.start,
               "end": self.end, "figure": round(float(self.figure), 3)}
        return out if self.kind == "line" else {**out, "kind": self.kind}


def runs(z: np.ndarray, run: int = RUN, periodic: bool = True) -> np.ndarray:
    """Mean of ``run`` consecutive stretches of every line: ``(stretches, lines)`` scores in, the same shape
    out (periodic: wrapping; otherwise only whole runs). Fewer stretches than ``run``: the whole line."""
    return moving_mean(z, min(run, z.shape[0]), periodic)


def seams_from_scores(scores: dict[str, np.ndarray], reference: float, margin: float, *, factor: float,
                      tile_shape: tuple[int, int], length: int, step: int, map_name: str = "stack",
                      limit: int = 6) -> tuple[list[Seam], float]:
    """Seams where a line's run exceeds ``reference + margin``, and the tile's strongest run minus ``reference``.

    ``scores[axis]`` are a tile's stretch scores ``(stretches, lines)`` at the working resolution
    (``factor`` = working / full size). A line yields its strongest run, extended over the stretches
    above the threshold; lines within 4 px of a stronger seam are the same seam. At most ``limit`` per
    axis, strongest first.
    """
    h, w = tile_shape
    found: list[Seam] = []
    strongest = -np.inf
    for axis, z in scores.items():
        r = runs(z)
        peak = r.max(axis=0)
        strongest = max(strongest, float(peak.max()) - reference)
        n_lines = z.shape[1]
        taken: list[int] = []
        for line in np.argsort(-peak):
            if peak[line] - reference <= margin or len(taken) >= limit:
                break
            if any(min(abs(line - t), n_lines - abs(line - t)) <= 4 for t in taken):
                continue
            taken.append(int(line))
            above = r[:, line] - reference > margin
            first, last = _span(above, int(np.argmax(r[:, line])))
            along = h if axis == "x" else w
            across = w if axis == "x" else h
            lo = int(first * step / factor)
            hi = min(along - 1, int((last * step + (RUN - 1) * step + length) / factor))
            pos = int(round(line / factor)) % across
            found.append(Seam(axis, pos, lo, hi, float(peak[line] - reference), map_name))
    found.sort(key=lambda s: -s.figure)
    return found, float(strongest)


def _span(above: np.ndarray, top: int) -> tuple[int, int]:
    """First and last run index of the stretch of ``above`` holding ``top`` (the whole line when it wraps)."""
    n = len(above)
    if above.all():
        return 0, n - 1
    first = top
    while first > 0 and above[first - 1]:
        first -= 1
    last = top
    while last < n - 1 and above[last + 1]:
        last += 1
    return first, last
