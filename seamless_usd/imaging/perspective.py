"""Structure that converges with perspective (``process --straighten``): find where a picture's near-vertical
lines meet, and resample it so that they run parallel and its rows are evenly spaced.

A wall or pavement shot at a slant has lines that meet at a vanishing point: a brick pavement's long joints lean
one way on the left of the photo and the other way on the right, and its courses come closer towards the far
side. No cut of whole periods fits such a photo, and turning it by one angle (:mod:`.straighten`) cannot help.

1. **The vanishing point** of the lines within 30 degrees of the picture's vertical (:func:`find_keystone`). Each
   map's grey (light broader than 6 px taken away, at most 512 px) is read in an 8 x 8 grid of cells; each cell's
   structure tensor (of the gradients within 30 degrees of the horizontal: a grid's other lines left out) gives
   its lines' lean and its coherence. A line through the vanishing point ``(vx, vy)`` passes a cell centre
   ``(x, y)`` with ``tan(a) = (vx - x) / (y - vy)``, fitted by coherence-weighted least squares in
   ``u = 1 / (y0 - vy)`` and ``u vx`` (``y0`` the centre row), so that lines that barely converge (``u`` near 0)
   are as well posed as lines that meet close by. A picture is rectified only where its leans spread by at least
   :data:`MIN_SPREAD` degrees across it (the 10th to 90th percentile), the fitted point makes them spread so
   (a spread of noisy leans around parallel lines fits a point far away), and it explains most of them
   (:data:`MIN_EXPLAINED`: leans that spread at random, as a bowl of beans', fit no point). The point is read
   again on the picture rectified by it, up to :data:`PASSES` times (short lines read nearer the vertical than
   they lean).
2. **The one-point homography** that sends it to infinity (:func:`rectify_maps`): with ``X = x - vx`` and
   ``Y = y - vy``, ``x' = X Yr / Y`` and ``y' = Yr - Yr^2 / Y``. Lines through the vanishing point become vertical,
   and rows evenly spaced on the plane (a camera pitched about the horizontal axis) come out evenly spaced.
   ``Yr`` is the far row, so no texel is magnified: nearer rows are shrunk, each through a Gaussian prefilter as
   wide as its own shrink (from a few levels of blur; the far row is not blurred), and the picture is cut to
   the largest rectangle of source texels. The far row keeps its proportions: a surface seen at a slant is
   foreshortened there too, and its true aspect is not known from its vanishing point alone, so a rectified
   brick may be shorter than it is. A point below the
   picture is handled upside down. Normal maps' vectors turn with the picture, texel by texel (each line
   through the point is turned upright where it passes), and are renormalised.

The experiment this came from, with its figures: ``benchmarks/experiments/keystone.py`` (``docs/decisions.md``,
"Rectifying perspective").
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["Keystone", "find_keystone", "rectify_maps", "MIN_SPREAD"]

CELLS = 8
LEAN_MAX = np.radians(30.0)  # lines leaning further from the vertical are not read
LIGHT = 6.0  # px: broader changes are light, taken away first
SIGMAS = (0.0, 0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 16.0)  # the prefilter's levels of blur (px)
SIDE = 512  # the grey picture is read at most this many px on its longer side
#: Leans spread by fewer degrees (10th to 90th percentile) are parallel lines: the 512 px photos of a tiled floor,
#: a corrugated panel and a concrete-tile facade read 0.8-1.5, the brick pavement shot at a slant 17.
MIN_SPREAD = 3.0
#: ... and the point must explain this share of the cells' leans (weighted R^2): on the 33 photos at 512 px the
#: slanted pavement's read 0.99; photos of beans, sausages, leaves and rock whose leans spread at random (by 10-24
#: degrees) 0.28 at most.
MIN_EXPLAINED = 0.7


@dataclass(frozen=True)
class Keystone:
    """Where a picture's near-vertical lines meet, as shares of its width and height (``vy`` < 0: above it), and
    how far their leans spread (degrees)."""

    vx: float
    vy: float
    spread: float

    def as_dict(self) -> dict:
        return {"vanishing": [round(self.vx, 5), round(self.vy, 5)], "spread": round(self.spread, 2)}


def _grey(values: np.ndarray) -> np.ndarray:
    from scipy import ndimage

    a = np.asarray(values, dtype=np.float64)
    g = a.reshape(a.shape[0], a.shape[1], -1).mean(axis=2)
    step = max(1, int(np.ceil(max(g.shape) / SIDE)))
    hh, ww = g.shape[0] // step * step, g.shape[1] // step * step
    g = g[:hh, :ww].reshape(hh // step, step, ww // step, step).mean(axis=(1, 3))
    return g - ndimage.gaussian_filter(g, LIGHT)


def _cell_leans(g: np.ndarray) -> list[tuple[float, float, float, float]]:
    """(x, y, tan(lean), coherence) of each cell whose dominant lines lean at most LEAN_MAX from the vertical: the
    structure tensor's gradient direction is the lines' normal, so for near-vertical lines it is their lean."""
    gy, gx = np.gradient(g)
    steep = np.abs(gy) > np.tan(LEAN_MAX) * np.abs(gx)  # gradients of lines leaning further (a grid's other lines)
    gx, gy = np.where(steep, 0.0, gx), np.where(steep, 0.0, gy)
    h, w = g.shape
    out = []
    for i in range(CELLS):
        for j in range(CELLS):
            x0, x1, y0, y1 = i * w // CELLS, (i + 1) * w // CELLS, j * h // CELLS, (j + 1) * h // CELLS
            sx, sy = gx[y0:y1, x0:x1], gy[y0:y1, x0:x1]
            jxx, jyy, jxy = float((sx * sx).sum()), float((sy * sy).sum()), float((sx * sy).sum())
            if jxx + jyy <= 0:
                continue
            phi = 0.5 * np.arctan2(2 * jxy, jxx - jyy)
            if abs(phi) > LEAN_MAX:
                continue
            coherence = float(np.hypot(jxx - jyy, 2 * jxy) / (jxx + jyy))
            out.append(((x0 + x1) / 2, (y0 + y1) / 2, float(np.tan(phi)), coherence))
    return out


def _fit(g: np.ndarray) -> tuple[float, float, float, float, float, float] | None:
    """(vx, vy, spread, implied spread, weight, explained) of one grey picture's near-vertical lines: their
    vanishing point (px), the spread of the cells' leans and the spread the point implies across the picture
    (degrees), the cells' total coherence, and the share of the leans' variance the point explains (weighted
    R^2); None with too few cells or lines that do not converge at all."""
    from scipy.optimize import least_squares

    leans = _cell_leans(g)
    if len(leans) < 4:
        return None
    x, y, t, c = (np.array(v) for v in zip(*leans))
    if c.sum() <= 0:
        return None
    y0 = float(np.average(y, weights=c))
    slope, icept = np.polyfit(x, t, 1, w=c)  # near y0: t = p - u x
    fit = least_squares(lambda q: c * (t - (q[1] - q[0] * x) / (1.0 + q[0] * (y - y0))), [-slope, icept])
    u, p = fit.x
    if abs(u) < 1e-12:
        return None
    order = np.argsort(t)
    cum = np.cumsum(c[order]) / c.sum()
    lo, hi = t[order][np.searchsorted(cum, 0.1)], t[order][min(len(t) - 1, np.searchsorted(cum, 0.9))]
    vx, vy = float(p / u), float(y0 - 1.0 / u)
    w = g.shape[1]
    implied = float(np.degrees(abs(np.arctan(vx / (y0 - vy)) - np.arctan((vx - w) / (y0 - vy)))))
    total = float(np.average((t - np.average(t, weights=c)) ** 2, weights=c))
    left = float(np.average((t - (vx - x) / (y - vy)) ** 2, weights=c))
    explained = 1.0 - left / total if total > 0 else 0.0
    return vx, vy, float(np.degrees(np.arctan(hi) - np.arctan(lo))), implied, float(c.sum()), explained


def _converges(fit, h: int) -> bool:
    """Whether a fit's lines converge enough to rectify (module notes), their point outside the picture's rows."""
    return (fit is not None and fit[2] >= MIN_SPREAD and fit[3] >= MIN_SPREAD and fit[5] >= MIN_EXPLAINED
            and not 0.0 <= fit[1] <= h)


def _frame(h: int, w: int, vx: float, vy: float) -> tuple[float, float, int, int]:
    """(Yr, left, out_w, out_h) of an ``h`` x ``w`` picture's rectification by (vx, vy) (px, above it): the far row
    (it keeps its texel size; nearer rows shrink, none is magnified), the first column kept, and the size of the
    largest rectangle of source texels."""
    yr, y_bottom = -vy, h - 1 - vy
    left = max(-vx, -vx * yr / y_bottom)
    right = min(w - 1 - vx, (w - 1 - vx) * yr / y_bottom)
    return yr, left, int(right - left), int(yr - yr * yr / y_bottom)


def _source(vx: float, vy: float, yr: float, left: float, xp, yp):
    """The picture's (x, y) of the rectified picture's (xp, yp) (the module notes' homography, inverted)."""
    big_y = yr * yr / (yr - yp)
    return (xp + left) * big_y / yr + vx, big_y + vy


def _back(vx: float, vy: float, point: tuple[float, float], hw: tuple[int, int]) -> tuple[float, float]:
    """The picture's (x, y) of the rectified picture's ``point`` (px), rectified by (vx, vy) (px, above it)."""
    yr, left, _, _ = _frame(*hw, vx, vy)
    return _source(vx, vy, yr, left, *point)


#: Times the vanishing point is read again on the picture rectified by it: the structure tensors of short, noisy
#: lines read them nearer the vertical than they lean, so a first point lies too far off (a brick wall pitched
#: with its point 1.8 heights above it: read at 3.2), fine ones further (bars with their point 1.5 heights above: read
#: at 1.2, after which they diverge the other way); each reading takes away most of what is left.
PASSES = 3
#: A rectification that keeps less than this share of either side of the picture (a point very close above it)
#: is not made: the stack is left as it is.
KEEP = 0.4


def find_keystone(values: Sequence[np.ndarray]) -> Keystone | None:
    """Where the near-vertical lines of the maps ``values`` (``(H, W, C)`` or ``(H, W)``, one texel grid) meet,
    read on the map whose lines are most coherent; None when they run parallel (module notes)."""
    greys = [_grey(v) for v in values if min(np.shape(v)[:2]) >= 64]
    fits = [(f, g) for f, g in ((_fit(g), g) for g in greys) if f is not None]
    if not fits:
        return None
    fit, g = max(fits, key=lambda fg: fg[0][4])
    h, w = g.shape
    if not _converges(fit, h):
        return None
    vx, vy, spread = fit[0], fit[1], fit[2]
    below = vy > h
    if below:  # read upside down, as it is rectified
        g, vy = g[::-1], h - 1 - vy
    for _ in range(PASSES - 1):
        try:
            r = _rectify(g[..., None], vx, vy)[..., 0]
        except ValueError:
            return None
        again = _fit(r)
        if again is None or again[3] < 0.5:  # parallel now
            break
        # the point of what is left, in the picture's own rows: closer where it was read too far (left above),
        # further where too close (the lines now diverge upwards: left below)
        nx, ny = _back(vx, vy, (again[0], again[1]), (h, w))
        if not ny < 0:
            break
        vx, vy = nx, ny
    _, _, out_w, out_h = _frame(h, w, vx, vy)  # what the rectification keeps: at least KEEP of each side
    if out_h < KEEP * h or out_w < KEEP * w:
        return None
    if below:
        vy = h - 1 - vy
    return Keystone(vx / w, vy / h, spread)


def _rectify(flat: np.ndarray, vx: float, vy: float) -> np.ndarray:
    """One map (H, W, C), its vanishing point above it (px, ``vy`` < 0), rectified (module notes)."""
    from scipy import ndimage

    h, w = flat.shape[:2]
    yr, left, out_w, out_h = _frame(h, w, vx, vy)
    if out_w < 16 or out_h < 16:
        raise ValueError(f"a {w} x {h} picture rectified keeps only {out_w} x {out_h} texels")
    yp, xp = np.mgrid[0:out_h, 0:out_w].astype(np.float64)
    sx, sy = _source(vx, vy, yr, left, xp, yp)
    # each output row is sampled from the picture blurred as much as that row shrinks (Y / Yr along x, its square
    # along y: their geometric mean), from a few levels of blur: the far rows, not shrunk, are not blurred
    shrink = ((sy[:, 0] - vy) / yr) ** 1.5
    want = 0.5 * np.maximum(0.0, shrink - 1.0)
    levels = [s for s in SIGMAS if s <= max(want.max(), 0.0) * 2 or s == 0.0]
    level = np.array([min(range(len(levels)), key=lambda i: abs(levels[i] - v)) for v in want])
    out = np.empty((out_h, out_w, flat.shape[2]))
    for i, sigma in enumerate(levels):
        rows = np.flatnonzero(level == i)
        if not rows.size:
            continue
        for k in range(flat.shape[2]):
            src = ndimage.gaussian_filter(flat[..., k], sigma) if sigma else flat[..., k]
            out[rows, :, k] = ndimage.map_coordinates(src, [sy[rows], sx[rows]], order=3, mode="nearest")
    return out


def _lean(h: int, w: int, vx: float, vy: float) -> np.ndarray:
    """(out_h, out_w) radians: how far the picture turns at each texel of its rectification by (vx, vy) (px, above
    it): the line through the point there is made vertical (its lean from the vertical, down and to the right
    positive)."""
    yr, left, out_w, out_h = _frame(h, w, vx, vy)
    yp, xp = np.mgrid[0:out_h, 0:out_w].astype(np.float64)
    sx, sy = _source(vx, vy, yr, left, xp, yp)
    return np.arctan2(sx - vx, sy - vy)


def rectify_maps(values: Sequence[np.ndarray], normals: Sequence[bool], keystone: Keystone) -> list[np.ndarray]:
    """Every map of ``values`` (decoded, (H, W, C), one texel grid) rectified by ``keystone`` (module notes): its
    lines through the vanishing point made vertical, its rows evenly spaced, at the far row's texel size, cut to
    source texels. Values are held to each channel's range in the source; normal maps' vectors (x right, y up)
    turn with the picture, texel by texel, and are renormalised."""
    from .straighten import renormalise

    out = []
    for v, is_normal in zip(values, normals):
        a = np.asarray(v, dtype=np.float64)
        h, w = a.shape[:2]
        flat = a.reshape(h, w, -1)
        vx, vy = keystone.vx * w, keystone.vy * h
        below = vy > h  # the lines meet below the picture: rectified upside down
        vector = is_normal and flat.shape[2] >= 3
        src = flat[::-1].copy() if below else flat
        if below and vector:  # upside down, a vector's y (up) points the other way
            src[..., 1] = -src[..., 1]
        py = (h - 1 - vy) if below else vy
        made = _rectify(src, vx, py)
        lo, hi = flat.min(axis=(0, 1)), flat.max(axis=(0, 1))
        if vector:  # the vectors turn with the picture, texel by texel: each line through the point made vertical
            turn = -_lean(h, w, vx, py)  # turned back against the lean
            x, y = made[..., 0].copy(), made[..., 1].copy()
            made[..., 0] = x * np.cos(turn) - y * np.sin(turn)
            made[..., 1] = x * np.sin(turn) + y * np.cos(turn)
            if below:
                made[..., 1] = -made[..., 1]
            lo, hi = lo.copy(), hi.copy()
            lo[:2], hi[:2] = -1.0, 1.0
        made = made[::-1] if below else made
        made = np.clip(made, lo, hi).astype(np.float32)
        if vector:
            made = np.concatenate([renormalise(made[..., :3]), made[..., 3:]], axis=2)
        out.append(np.ascontiguousarray(made.reshape(made.shape[:2] + np.shape(v)[2:])))
    return out
