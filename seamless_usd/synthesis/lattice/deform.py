"""Feature matching and deformation at a quilt's joins (Wu and Yu 2004): a lever, measured and not kept.

Where two quilt blocks meet, the structure of one is often the other's shifted by a few texels: a brick
course a little higher, a stripe a little to the side. A cut cannot hide such a join; it steps the course or
kinks the stripe. This lever moves the new block's texels near each join so that they line up with the
texels already laid there, and eases the move to nothing over a ramp inside the block:

1. along each overlap band, windows of the band's width, a window every quarter of it, are matched against
   the laid texels over every integer shift within ``reach`` (the mean squared difference over the laid
   texels, plus a small cost that grows with the shift, so that a texture that agrees unshifted stays
   unshifted);
2. the shifts are smoothed along the band (a median of three, then a Gaussian of one window), interpolated
   to every texel along it, held over the band and eased linearly to nothing over a ramp as wide as the band
   beyond it; where two bands meet, their shifts are averaged by weight;
3. the block's source texel at each place is the one shifted by the rounded displacement. Every texel is
   still a source copy, through one field for every map; inside the ramp, neighbours may come from source
   texels one apart more or less than their distance, which stretches or squeezes the texture there by at
   most ``reach`` over the ramp.
"""
from __future__ import annotations

import numpy as np

__all__ = ["join_shifts"]

_SHIFT_COST = 0.05  # the cost of the longest shift, over the difference of two unrelated texels


def _best_shift(template: np.ndarray, mask: np.ndarray, region: np.ndarray, reach: tuple[int, int],
                unrelated: float) -> tuple[int, int]:
    """The (dy, dx) within ``reach`` (the region's margin around the window on each axis) whose shifted
    window of ``region`` agrees best with ``template`` over ``mask``."""
    h, w = template.shape[:2]
    m = mask[..., None].astype(np.float32)
    n = max(1.0, float(mask.sum()))
    best, best_cost = (0, 0), np.inf
    ry, rx = reach
    for dy in range(-ry, ry + 1):
        for dx in range(-rx, rx + 1):
            got = region[ry + dy: ry + dy + h, rx + dx: rx + dx + w]
            cost = float((m * (got - template) ** 2).sum()) / n
            cost += _SHIFT_COST * unrelated * (dy * dy + dx * dx) / max(1, ry * ry + rx * rx)
            if cost < best_cost:
                best, best_cost = (dy, dx), cost
    return best


def join_shifts(laid: np.ndarray, mask: np.ndarray, place: tuple[int, int], bands: list[tuple[str, int]],
                sample, source_hw: tuple[int, int], reach: int, unrelated: float) -> tuple[np.ndarray, np.ndarray]:
    """Integer (dy, dx) arrays of the block's shape: the displacement of each of its source texels (see the
    module notes). ``laid``: the joint features (bh, bw, C) of the texels already laid where the block
    goes, ``mask`` where they are; ``place``: the block's source (y, x); ``bands``: each side it shares with
    a laid block (``"left"``, ``"top"``, ``"right"``, ``"bottom"``) and the band's width; ``sample(y, x)``:
    the joint features of source texels; ``reach``: the longest shift (px)."""
    from scipy import ndimage

    bh, bw = mask.shape
    H, W = source_hw
    py, px = place
    num = np.zeros((bh, bw, 2), dtype=np.float64)
    den = np.zeros((bh, bw), dtype=np.float64)
    for side, width in bands:
        across_rows = side in ("top", "bottom")  # the band runs along the block's columns
        length = bw if across_rows else bh
        step = max(2, width // 4)
        centres = np.arange(step // 2, length, step)
        shifts = []
        for c in centres:
            a0, a1 = max(0, c - width // 2), min(length, c + width // 2 + 1)
            b0, b1 = (0, width) if side in ("left", "top") else ((bh if across_rows else bw) - width,
                                                               bh if across_rows else bw)
            rows, cols = ((b0, b1), (a0, a1)) if across_rows else ((a0, a1), (b0, b1))
            win_mask = mask[rows[0]: rows[1], cols[0]: cols[1]]
            if win_mask.sum() < win_mask.size / 4:
                shifts.append((0.0, 0.0))
                continue
            # the shifts the source allows on each axis, the same both ways
            ry = max(0, min(reach, py + rows[0], H - (py + rows[1])))
            rx = max(0, min(reach, px + cols[0], W - (px + cols[1])))
            yy, xx = np.mgrid[py + rows[0] - ry: py + rows[1] + ry, px + cols[0] - rx: px + cols[1] + rx]
            region = sample(yy, xx)
            shifts.append(_best_shift(laid[rows[0]: rows[1], cols[0]: cols[1]], win_mask, region, (ry, rx),
                                      unrelated))
        u = np.asarray(shifts, dtype=np.float64).reshape(-1, 2)
        if len(u) >= 3:
            u = ndimage.median_filter(u, size=(3, 1), mode="nearest")
            u = ndimage.gaussian_filter1d(u, 1.0, axis=0, mode="nearest")
        along = np.stack([np.interp(np.arange(length), centres, u[:, k]) for k in range(2)], -1)  # (length, 2)
        depth = np.arange(bh if across_rows else bw, dtype=np.float64)
        if side in ("right", "bottom"):
            depth = depth[::-1]
        weight = np.clip(1.0 - (depth - width) / width, 0.0, 1.0)  # 1 over the band, to 0 over a ramp as wide
        if across_rows:
            w2 = weight[:, None] * np.ones((1, bw))
            num += w2[..., None] * along[None, :, :]
        else:
            w2 = weight[None, :] * np.ones((bh, 1))
            num += w2[..., None] * along[:, None, :]
        den += w2
    d = num / np.maximum(den, 1.0)[..., None]
    return np.rint(d[..., 0]).astype(np.int64), np.rint(d[..., 1]).astype(np.int64)
