"""A lattice that drifts: tiles, bricks or boards whose rows wander a few texels from an even spacing across a
photo (a lens's bend, a wall not quite flat, a floor shot a little off square), and the maps evened so they
repeat evenly.

A cut of whole periods (:mod:`.cut`) joins the photo to itself one tile on. Where the lattice drifts, the copy
one tile on sits a texel or two off, and every joint crossing the wrap jogs: on a 512 px window of a white
tiled floor the joints' phase wanders 3 px over the photo, and the cut's wrap reads as a seam that shows at 3x.

The drift is read by demodulation, one axis at a time: the maps' first principal channel, with light broader
than a period taken away, is multiplied by a wave of the lattice's period along that axis and blurred by a
Gaussian of :data:`DRIFT_SIGMA` periods. The angle of what is left is the lattice's local phase; its difference
from the mean phase, in texels, is how far the rows (or columns) sit from an even lattice there. Each map is
then resampled by that displacement (cubic B-spline, values held to each channel's range in the source, normal
vectors renormalised), all maps through one field, so they stay aligned. Texels move by a texel or two, never
more than :data:`DRIFT_MAX` of a period: a phase that wanders further is not a drift this reading can be trusted
with (a weak period, or a texture that only repeats in places).

The result is a function of the maps alone: ``check`` evens the recorded source the same way.

>>> y, x = np.mgrid[0:256, 0:256].astype(np.float64)
>>> bent = 2.0 * np.sin(np.pi * x / 256)  # rows bowed by up to 2 texels across the picture
>>> rows = np.cos(2 * np.pi * (y - bent) / 16)[..., None].astype(np.float32)
>>> def bow(a):  # how far the rows' phase wanders from column to column (texels; the outer period left out)
...     phase = np.angle((a[..., 0] * np.exp(-2j * np.pi * y / 16)).sum(0)) * 16 / (2 * np.pi)
...     return round(float(np.ptp(phase[16:-16])), 1)
>>> (even,), facts = even_lattice([rows], [False], period=(16.0, None))
>>> bow(rows), bow(even), facts["moved"] < 0.125 * 16
(1.6, 0.2, True)
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from seamless_usd.imaging.resample import grown_linear

from ..scale import box_downsample
from .lines import principal_tone

__all__ = ["DRIFT_SIGMA", "DRIFT_MIN", "DRIFT_MAX", "lattice_drift", "even_lattice"]

#: The demodulation's Gaussian, in periods: narrower reads the phase of too few rows to be steady.
DRIFT_SIGMA = 1.5
#: A lattice whose rows sit less than this (texels) from an even spacing everywhere is left as it is.
DRIFT_MIN = 0.5
#: The most a texel is moved, as a share of the period along its axis; a drift read larger is refused.
DRIFT_MAX = 0.125
#: The phase is read on the maps box-halved to at most this many px a side (each period kept at least
#: _MIN_PERIOD px there).
_SIDE = 512
_MIN_PERIOD = 8.0
_STRIP = 256  # rows resampled at a time: a 4K map never holds its coordinates whole


def _blur(a: np.ndarray, sigma: float) -> np.ndarray:
    from scipy import ndimage

    return ndimage.gaussian_filter(a, sigma, mode="reflect")


def lattice_drift(values: Sequence[np.ndarray], period: tuple[float | None, float | None]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(dy, dx), each (H, W) float32: how far (texels) the lattice of ``period`` (px along y and x; None where
    an axis does not repeat, its field then 0) sits from an even lattice at every texel of ``values``."""
    H, W = values[0].shape[:2]
    shortest = min(p for p in period if p is not None)
    halvings = 0
    while max(H, W) / 2 ** halvings > _SIDE and shortest / 2 ** (halvings + 1) >= _MIN_PERIOD:
        halvings += 1
    small = [box_downsample(np.asarray(v, dtype=np.float32).reshape(H, W, -1), max(H, W) // 2 ** halvings)[0]
             for v in values] if halvings else [np.asarray(v, dtype=np.float32) for v in values]
    factor = H / small[0].shape[0]
    tone = principal_tone(small).astype(np.float64)
    fields = []
    for axis, p in enumerate(period):
        if p is None:
            fields.append(np.zeros((H, W), np.float32))
            continue
        p_small = p / factor
        wave = tone - _blur(tone, p_small)  # light broader than a period is not the lattice
        n = wave.shape[axis]
        carrier = np.exp(-2j * np.pi * np.arange(n) / p_small)
        z = wave * (carrier[:, None] if axis == 0 else carrier[None, :])
        z = _blur(z.real, DRIFT_SIGMA * p_small) + 1j * _blur(z.imag, DRIFT_SIGMA * p_small)
        mean = z.mean()
        phase = np.angle(z * np.conj(mean) / max(abs(mean), 1e-12))
        field = (phase * p / (2 * np.pi)).astype(np.float32)
        fields.append(field if field.shape == (H, W) else grown_linear(field, (H, W)))
    return fields[0], fields[1]


def _resampled(channel: np.ndarray, dy: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """``channel`` (H, W) read at (y - dy, x - dx): cubic B-spline, a strip of rows at a time."""
    from scipy import ndimage

    coeffs = ndimage.spline_filter(channel.astype(np.float64), order=3, mode="nearest")
    H, W = channel.shape
    out = np.empty((H, W), np.float32)
    xs = np.arange(W, dtype=np.float64)[None, :]
    for y0 in range(0, H, _STRIP):
        ys = np.arange(y0, min(H, y0 + _STRIP), dtype=np.float64)[:, None]
        rows = slice(y0, y0 + ys.shape[0])
        out[rows] = ndimage.map_coordinates(coeffs, [ys - dy[rows], xs - dx[rows]], order=3, mode="nearest",
                                            prefilter=False)
    return out


def even_lattice(values: Sequence[np.ndarray], normals: Sequence[bool], lattice=None,
                 period: tuple[float | None, float | None] | None = None) -> tuple[list[np.ndarray], dict]:
    """(maps, facts): ``values`` (network domain) resampled so that their lattice repeats evenly (see the module
    notes), and what was done: ``moved``, the most a texel moved (texels), ``moved_mean``, its mean, ``periods``
    and ``sigma``. The lattice is ``lattice`` (a :class:`.cut.Lattice`), or found here, or given as ``period``.
    Maps are given back as they are (``moved`` 0) when nothing repeats, when the drift is under
    :data:`DRIFT_MIN` everywhere, or when it is over :data:`DRIFT_MAX` of a period somewhere (``refused``)."""
    from seamless_usd.imaging.normals import renormalise

    if period is None:
        if lattice is None:
            from .cut import find_lattice

            lattice = find_lattice([np.asarray(v) for v in values])
        period = lattice.period
    same = [np.asarray(v, dtype=np.float32) for v in values]
    facts = {"moved": 0.0, "moved_mean": 0.0, "periods": [None if p is None else round(float(p), 2) for p in period],
             "sigma": DRIFT_SIGMA}
    if all(p is None for p in period):
        return same, facts
    dy, dx = lattice_drift(same, period)
    worst = max((float(np.abs(d).max()) / p for d, p in zip((dy, dx), period) if p is not None))
    moved = np.hypot(dy, dx)
    if worst > DRIFT_MAX:
        return same, {**facts, "refused": round(worst, 3)}
    if float(moved.max()) < DRIFT_MIN:
        return same, facts
    out = []
    for v, normal in zip(same, normals):
        lo, hi = v.min(axis=(0, 1)), v.max(axis=(0, 1))
        warped = np.stack([_resampled(v[..., c], dy, dx) for c in range(v.shape[-1])], -1)
        warped = np.clip(warped, lo, hi)
        out.append(renormalise(warped) if normal and v.shape[-1] == 3 else warped.astype(np.float32))
    return out, {**facts, "moved": round(float(moved.max()), 3), "moved_mean": round(float(moved.mean()), 3)}
