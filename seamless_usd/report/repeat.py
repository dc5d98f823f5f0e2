"""Same-texel-scale repeats: the source and the tile shown over one UV window.

The source covers the UV unit square; the tile covers ``1 / uv_scale`` of it (its authored UV
scale). Shown side by side at the same on-screen size, a 2x2 of each would put them at different
texel scales, and magnification would be hidden. Here both are sampled over the *same* UV window
(by default 3 repeats of whichever of the two covers more UV), so one on-screen pixel is the same
UV distance in both pictures.

Sampling is wrap-around throughout (a periodic Gaussian pre-filter when shrinking, then bilinear
interpolation with wrap), so the borders look exactly as a renderer repeating the texture shows
them: a clamped filter would smear or hide the seams the pictures are there to show.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["VIEW_MAX", "REPEATS", "ViewGeometry", "view_geometry", "repeat_view", "through_uv"]

VIEW_MAX = 576  # longest side of a same-scale picture, px (3 repeats of 192 px)
REPEATS = 3  # repeats of the larger of source and tile across the window


@dataclass(frozen=True)
class ViewGeometry:
    """One UV window and how the source and the tile repeat inside it.

    ``window`` is the UV size ``(u, v)`` shown, ``tile_extent`` the UV size of one tile
    (``1 / uv_scale``; the source's is ``(1, 1)``), ``size`` the picture's ``(W, H)`` in pixels.
    """

    window: tuple[float, float]
    tile_extent: tuple[float, float]
    size: tuple[int, int]

    @property
    def source_repeats(self) -> tuple[float, float]:
        return self.window[0], self.window[1]

    @property
    def tile_repeats(self) -> tuple[float, float]:
        return self.window[0] / self.tile_extent[0], self.window[1] / self.tile_extent[1]

    def lines(self, extent: tuple[float, float], offset: float = 0.0) -> tuple[list[float], list[float]]:
        """Pixel positions ``(xs, ys)`` of the lines at ``(k + offset) * extent`` inside the picture.

        ``offset=0`` gives the repeat borders, ``offset=0.5`` the centre lines of each repeat.
        """
        out = []
        for axis in (0, 1):
            n = self.window[axis] / extent[axis]
            px = self.size[axis] / n
            out.append([(k + offset) * px for k in range(int(np.ceil(n)) + 1) if 0 < (k + offset) * px < self.size[axis]])
        return out[0], out[1]

    def to_dict(self) -> dict:
        return {"window": list(self.window), "tile_extent": list(self.tile_extent), "size": list(self.size)}


def view_geometry(source_size: tuple[int, int], uv_scale: tuple[float, float] | None,
                  repeats: int = REPEATS, max_px: int = VIEW_MAX) -> ViewGeometry:
    """The shared UV window for a source of ``source_size = (W, H)`` px and a tile at ``uv_scale``.

    Texels stay square on screen (the UV unit square is shown ``W : H``).

    Examples
    --------
    >>> g = view_geometry((512, 512), (0.5, 0.5))  # a tile covering 2x2 UV units
    >>> g.window, g.tile_repeats, g.size
    ((6.0, 6.0), (3.0, 3.0), (576, 576))
    """
    su, sv = uv_scale or (1.0, 1.0)
    if not (su > 0 and sv > 0 and np.isfinite(su) and np.isfinite(sv)):
        raise ValueError(f"uv_scale must be positive and finite, got {uv_scale}")
    extent = (1.0 / su, 1.0 / sv)
    # The same number of repeats along both axes (of the larger cover), so the picture keeps the aspect.
    cover = max(1.0, extent[0], extent[1])
    window = (repeats * cover, repeats * cover)
    w, h = source_size
    span_x, span_y = window[0] * w, window[1] * h  # native texels across the window
    f = max_px / max(span_x, span_y)
    return ViewGeometry(window=window, tile_extent=extent,
                        size=(max(1, int(round(span_x * f))), max(1, int(round(span_y * f)))))


def _periodic_blur(img: np.ndarray, sigma: tuple[float, float]) -> np.ndarray:
    """Gaussian blur with wrap-around (FFT), ``sigma = (x, y)`` in pixels; ``(H, W, C)``."""
    if max(sigma) <= 0.3:
        return img
    h, w = img.shape[:2]
    fy = np.fft.fftfreq(h)[:, None]
    fx = np.fft.rfftfreq(w)[None, :]
    gain = np.exp(-2.0 * np.pi ** 2 * ((sigma[1] * fy) ** 2 + (sigma[0] * fx) ** 2))
    spectrum = np.fft.rfft2(img, axes=(0, 1)) * gain[..., None]
    return np.fft.irfft2(spectrum, s=(h, w), axes=(0, 1))


def _block_factor(n: int, step: float) -> int:
    """The largest divisor of ``n`` at most ``step / 2``: blocks that tile the image exactly."""
    limit = int(step // 2)
    return next((k for k in range(limit, 1, -1) if n % k == 0), 1)


def _reduce(img: np.ndarray, kx: int, ky: int) -> np.ndarray:
    """Block means over ``ky x kx`` blocks (they tile the image, so periodicity is kept)."""
    h, w, c = img.shape
    return img.reshape(h // ky, ky, w // kx, kx, c).mean(axis=(1, 3))


def _sample_axis(img: np.ndarray, coords: np.ndarray, axis: int) -> np.ndarray:
    """Linear interpolation with wrap-around at texel coordinates ``coords`` along ``axis``."""
    n = img.shape[axis]
    i0 = np.floor(coords).astype(np.int64)
    t = (coords - i0).astype(img.dtype)
    i0 %= n
    i1 = (i0 + 1) % n
    a, b = np.take(img, i0, axis=axis), np.take(img, i1, axis=axis)
    shape = [1] * img.ndim
    shape[axis] = -1
    t = t.reshape(shape)
    return a * (1 - t) + b * t


def repeat_view(img: np.ndarray, extent: tuple[float, float], geometry: ViewGeometry) -> np.ndarray:
    """``img`` (covering ``extent`` of UV) repeated over the window, ``(H, W, C)`` float.

    Parameters
    ----------
    img : ``(H, W)`` or ``(H, W, C)`` float values (any domain; filtering is linear).
    extent : UV size ``(u, v)`` one copy of ``img`` covers: ``(1, 1)`` for the source,
        ``geometry.tile_extent`` for the tile.
    geometry : the shared window from :func:`view_geometry`.

    Examples
    --------
    >>> g = ViewGeometry(window=(2.0, 2.0), tile_extent=(1.0, 1.0), size=(4, 4))
    >>> repeat_view(np.array([[0.0, 1.0], [2.0, 3.0]]), (1.0, 1.0), g)[..., 0].tolist()
    [[0.0, 1.0, 0.0, 1.0], [2.0, 3.0, 2.0, 3.0], [0.0, 1.0, 0.0, 1.0], [2.0, 3.0, 2.0, 3.0]]
    """
    a = np.asarray(img, dtype=np.float32)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3:
        raise ValueError(f"expected (H, W) or (H, W, C), got {np.shape(img)}")
    out_w, out_h = geometry.size
    # Texels of img per output pixel, per axis: > 1 means shrinking, so pre-filter.
    step_x = geometry.window[0] / extent[0] * a.shape[1] / out_w
    step_y = geometry.window[1] / extent[1] * a.shape[0] / out_h
    kx, ky = _block_factor(a.shape[1], step_x), _block_factor(a.shape[0], step_y)
    if kx > 1 or ky > 1:  # large maps: exact block means first (cheap), the Gaussian does the rest
        a = _reduce(a, kx, ky)
        step_x, step_y = step_x / kx, step_y / ky
    a = _periodic_blur(a, (0.5 * step_x if step_x > 1 else 0.0, 0.5 * step_y if step_y > 1 else 0.0))
    xs = (np.arange(out_w) + 0.5) * step_x - 0.5
    ys = (np.arange(out_h) + 0.5) * step_y - 0.5
    return _sample_axis(_sample_axis(a, ys, 0), xs, 1)


def through_uv(img: np.ndarray, affine, geometry: ViewGeometry) -> np.ndarray:
    """``img`` (one tile, repeating) as the asset shows it over the window when its texture coordinates go through
    ``affine`` (asset UV -> the tile's UV, one tile a UV unit; :class:`.authoring.uvmath.Affine2`), ``(H, W, C)``
    float: the picture turned and scaled as the authored UV nodes turn and scale it. v runs up, rows down."""
    a = np.asarray(img, dtype=np.float32)
    a = a[..., None] if a.ndim == 2 else a
    h, w = a.shape[:2]
    out_w, out_h = geometry.size
    u = (np.arange(out_w) + 0.5) / out_w * geometry.window[0]
    v = geometry.window[1] - (np.arange(out_h) + 0.5) / out_h * geometry.window[1]
    u, v = np.meshgrid(u, v)
    tu, tv = affine.a * u + affine.b * v + affine.tx, affine.c * u + affine.d * v + affine.ty
    step = max(abs(affine.a), abs(affine.b), abs(affine.c), abs(affine.d)) * geometry.window[0] / out_w * max(h, w)
    a = _periodic_blur(a, (0.5 * step, 0.5 * step)) if step > 1 else a
    x, y = tu * w - 0.5, (1.0 - tv) * h - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[..., None].astype(np.float32), (y - y0)[..., None].astype(np.float32)
    at = lambda yy, xx: a[yy % h, xx % w]  # noqa: E731
    return ((at(y0, x0) * (1 - fx) + at(y0, x0 + 1) * fx) * (1 - fy)
            + (at(y0 + 1, x0) * (1 - fx) + at(y0 + 1, x0 + 1) * fx) * fy)
