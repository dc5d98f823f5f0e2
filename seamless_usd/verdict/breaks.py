"""Line breaks: a texture judged on its own, by where a line breaks the texture's own continuation, read
against every parallel line of the same texture. With the classifier against the texture's own lines
(:mod:`.judge`), this is how a texture with no separate source is judged.

Measured by ``benchmarks/texture_verdict.py`` on textures judged on their own; its settings (:data:`RANK`,
:data:`MARGIN`) were chosen on the corpus's tuning part only.

With no separate source, a seam is a line unlike the texture's other lines. Across a line, every pair of rows
``tau`` apart that straddles it is compared (:func:`straddle`): inside a texture, such pairs differ as the
texture differs over ``tau`` (its structure function), whichever line they straddle; across a join of
unrelated places they differ as unrelated texels do, at every lag. So each line gets, for every lag, its
mean straddling difference in units of the same figure's spread over all the texture's parallel lines
(a robust z-score: the median and the median absolute deviation), and its break is the largest of these
over the lags. Short lags see a one-texel break, long lags a broad tone step (a lit photo's seam), and the
texture's own period, when it has one, a lattice that the join puts out of phase.

A texture's own lines (mortar joints, plank gaps, slab joints) recur: they lift many lines alike. A join is
one line (a wrap, a half-rolled window's centre) or two (a spliced strip). So the reference is the texture's
:data:`RANK`-th strongest line, and a seam is a line whose break stands :data:`MARGIN` above it.

A few large slabs or a grid whose joints differ in strength leave too few alike lines for the rank, so a line
that breaks is also read across: a joint is a groove (:func:`groove`), a narrow band darker or lighter than
*both* its sides all along the line, the sides alike; a join is a step or a jumble. A groove is the texture's
own line, never a seam.
"""
from __future__ import annotations

import numpy as np

from .lines import Seam
from .prepare import joint, map_weights, to_working

__all__ = ["WORK_SIDE", "RANK", "MARGIN", "line_breaks", "line_figures", "line_period", "groove", "straddle", "peaks", "working"]

#: Longest side (px) the maps are read at: fine enough that a join's texel step survives the area filter.
WORK_SIDE = 512
#: The reference is the texture's RANK-th strongest line (lines within :data:`SPACING` of a stronger one
#: left out).
RANK = 4
#: A line whose break is more than this above the reference is a seam (robust z units).
MARGIN = 6.0
#: A line that recurs one period on at least this share of its own strength is the texture's own line (a grid's
#: joints differ in strength from one to the next, far more than a robust z-score's units).
RECUR = 0.5
#: Lines closer than this (px at the working size), or than the lag read, to a stronger line are the same line.
SPACING = 3
#: The lines' own spacing (:func:`line_period`) counts when their profile's autocorrelation there reaches this.
LINE_PERIOD = 0.5


def _autocorrelation(n: int, profile: np.ndarray) -> np.ndarray:
    """(n,) the circular autocorrelation of ``profile`` ((n, m): rows, each less the mean row), summed over its
    columns, over its value at lag 0."""
    spec = np.fft.rfft(profile - profile.mean(axis=0), axis=0)
    auto = np.fft.irfft((spec * spec.conj()).real.sum(axis=1), n=n)
    return auto / max(auto[0], 1e-12)


def period(n: int, profile: np.ndarray) -> int | None:
    """The texture's own period along the axis: the lag of the strongest autocorrelation peak of ``profile``
    (rows of the maps flattened, on a torus) between a sixteenth and half of ``n``, if it reaches 0.3."""
    auto = _autocorrelation(n, profile)
    lo, hi = max(4, n // 16), n // 2
    if hi <= lo:
        return None
    peak = lo + int(np.argmax(auto[lo:hi + 1]))
    if auto[peak] > 0.3 and auto[peak] >= auto[peak - 1] and auto[peak] >= auto[min(peak + 1, n - 1)]:
        return peak
    return None


def _lags(n: int, own: int | None) -> list[int]:
    """Short lags doubling up to a quarter of ``n``, and the texture's own period when it has one."""
    lags = {1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128} & set(range(1, max(2, n // 4) + 1))
    return sorted(lags | ({own} if own else set()))


def straddle(img: np.ndarray, lag: int) -> np.ndarray:
    """(n,) for each line ``p`` (before row ``p``, on a torus): the mean difference of the row pairs ``lag``
    apart that straddle it."""
    n = img.shape[0]
    d = np.empty_like(img)  # rows y + lag less rows y, on the torus (no rolled copy)
    np.subtract(img[lag:], img[: n - lag], out=d[: n - lag])
    np.subtract(img[:lag], img[n - lag:], out=d[n - lag:])
    pair = np.sqrt(np.einsum("ywc,ywc->yw", d, d)).mean(axis=1)  # rows y and y + lag
    total = np.concatenate([[0.0], np.cumsum(np.concatenate([pair, pair]))])
    p = np.arange(n) + n
    return (total[p] - total[p - lag]) / lag  # pairs starting at rows p - lag .. p - 1


def lag_figures(img: np.ndarray, own: int | None = None) -> dict[int, np.ndarray]:
    """For every lag, (n,) each horizontal line's straddling difference of ``img`` (H, W, C) read as a torus,
    as a robust z-score over all the lines (see the module notes); ``own``: the texture's period along the
    axis, read as one more lag."""
    out = {}
    for lag in _lags(img.shape[0], own):
        e = straddle(img, lag)
        mid = np.median(e)
        spread = 1.4826 * np.median(np.abs(e - mid)) + 1e-3 * mid + 1e-6  # a flat map: no line stands out
        out[lag] = (e - mid) / spread
    return out


def peaks(f: np.ndarray, spacing: int) -> list[int]:
    """Lines strongest first, each more than ``spacing`` from every stronger one (on a torus): a join lifts
    the lines within a lag of it too, less the closer they are."""
    n = len(f)
    taken: list[int] = []
    for line in np.argsort(-f):
        if all(min(abs(line - t), n - abs(line - t)) > spacing for t in taken):
            taken.append(int(line))
        if len(taken) > RANK:
            break
    return taken


def line_period(z: dict[int, np.ndarray]) -> int | None:
    """The spacing at which a texture's strong lines recur, read from the lines themselves when its rows do not
    repeat (:func:`period` finds none: a wall of irregular stones in panels, whose joints recur but whose stones do
    not): the lag of the highest local peak, between a sixteenth and half of the side, of the circular
    autocorrelation of each line's strongest z-score over the lags (``z``: :func:`lag_figures`, below 0 read as
    0), if it reaches :data:`LINE_PERIOD`."""
    strongest = np.clip(np.max(np.stack(list(z.values())), axis=0), 0.0, None)
    n = len(strongest)
    auto = _autocorrelation(n, strongest[:, None])
    lo, hi = max(4, n // 16), n // 2
    if hi <= lo + 1:
        return None
    inner = np.arange(lo + 1, hi)  # a peak has a neighbour on each side inside the range
    local = inner[(auto[inner] >= auto[inner - 1]) & (auto[inner] >= auto[inner + 1])]
    if not len(local):
        return None
    peak = int(local[np.argmax(auto[local])])
    return peak if auto[peak] >= LINE_PERIOD else None


def line_figures(img: np.ndarray, own: int | None = None) -> np.ndarray:
    """(n,) how far each horizontal line of ``img`` stands above the texture's own lines, at the lag where it
    stands out most: at each lag, its z-score less the texture's :data:`RANK`-th strongest line at that lag
    (lines a lag apart) and less its own recurrences one period on, give or take a texel (``own``, else
    :func:`line_period`); -inf where it is no top line."""
    n = img.shape[0]
    out = np.full(n, -np.inf)
    z_by_lag = lag_figures(img, own)
    recur = own or line_period(z_by_lag)
    for lag, z in z_by_lag.items():
        strongest = peaks(z, max(SPACING, lag))
        reference = z[strongest[RANK]] if len(strongest) > RANK else 0.0
        for line in strongest[:RANK]:
            # a texture's own line recurs one period on: a line is read against its recurrences too
            again = max(z[(line + d * recur + k) % n] for d in (-1, 1) for k in (-1, 0, 1)) if recur else -np.inf
            if again >= RECUR * z[line]:
                again = np.inf  # it recurs, at most a little weaker: the texture's own line at this lag
            out[line] = max(out[line], float(z[line] - max(reference, again)))
    return out


#: A line is a groove when, on at least this share of its length, its most deviant row near it lies beyond
#: both sides in the same direction ...
GROOVE_SHARE = 0.8
#: ... and that row stands this many times further from the sides' mean than the sides stand apart.
GROOVE_RATIO = 1.5


def groove(img: np.ndarray, line: int) -> bool:
    """Whether horizontal ``line`` of ``img`` (H, W, C, on a torus; the line lies before row ``line``) is a
    groove. Of the rows ``line - 2 .. line + 1``, the one deviating most from its sides (rows 3-6 away on each
    side, averaged) is read column by column, each column weighted by how much happens there (its deviation
    and its sides' difference: a joint that runs along part of the line, as in a running bond, is read where
    it runs): it lies beyond both sides in the same direction on :data:`GROOVE_SHARE` of the weight, and stands
    :data:`GROOVE_RATIO` times further from the sides' mean than the sides stand apart."""
    n = img.shape[0]

    def rows(ks: range) -> np.ndarray:
        return img[[(line + k) % n for k in ks]]

    left, right = rows(range(-7, -3)).mean(axis=0), rows(range(3, 7)).mean(axis=0)  # (W, C)
    mid = (left + right) / 2
    inner = rows(range(-2, 2))
    centre = inner[int(np.argmax(np.linalg.norm(inner - mid, axis=-1).mean(axis=1)))]  # (W, C)
    rise = np.linalg.norm(centre - mid, axis=-1)
    step = np.linalg.norm(left - right, axis=-1)
    weight = rise + step + 1e-9
    beyond = (((centre - left) * (centre - right)).sum(axis=-1) > 0)
    share = float((weight * beyond).sum() / weight.sum())
    return share >= GROOVE_SHARE and float((weight * rise).sum()) >= GROOVE_RATIO * float((weight * step).sum())


def working(prepared: list[np.ndarray]) -> tuple[list[np.ndarray], list[float]]:
    """``prepared`` (the maps in the verdict's form) at the working size (longest side at most :data:`WORK_SIDE`,
    read as the torus they tile), and each map's weight in the joint image (:func:`.prepare.map_weights`)."""
    factor = min(1.0, WORK_SIDE / max(prepared[0].shape[:2]))
    work = to_working(prepared, factor, periodic=True)
    return work, map_weights(work)


def line_breaks(prepared: list[np.ndarray], names: list[str], units: float = 1.0,
                work: tuple[list[np.ndarray], list[float]] | None = None) -> tuple[list[Seam], float]:
    """Seams of a texture judged on its own (``prepared``: its maps in the verdict's form, see
    :func:`.prepare.prepare_maps`; the maps together, then each map), strongest first, and the strongest line's
    break over the reference. Figures are scaled so that ``units`` is the margin: a line above ``units`` is a
    seam (the verdict reports them on its own margin's scale). ``work``: :func:`working` of ``prepared`` when it
    is made already."""
    size = prepared[0].shape[:2]
    work, weights = work or working(prepared)
    parts = [("stack", joint(work, weights))] + ([(n, m * w) for n, m, w in zip(names, work, weights)]
                                                 if len(work) > 1 else [])
    seams: list[Seam] = []
    strongest = -np.inf
    for name, img in parts:
        for axis, rotated in (("y", img), ("x", np.ascontiguousarray(img.transpose(1, 0, 2)))):
            n = rotated.shape[0]
            own = period(n, rotated.reshape(n, -1))
            f = line_figures(rotated, own)
            across = size[0 if axis == "y" else 1]
            along = size[1 if axis == "y" else 0]
            for line in np.flatnonzero(np.isfinite(f)):
                if f[line] > MARGIN and own is None and groove(rotated, int(line)):
                    continue  # the texture's own joint, in a texture with too few to recur
                figure = float(f[line]) * units / MARGIN
                strongest = max(strongest, figure)
                if f[line] > MARGIN:
                    seams.append(Seam(axis, int(round(line * across / n)) % across, 0, along - 1, figure, name))
    seams.sort(key=lambda s: -s.figure)
    return seams, float(strongest)
