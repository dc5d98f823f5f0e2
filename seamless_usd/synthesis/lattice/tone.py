"""A cut's copies levelled in tone (a lever for walls lit unevenly, measured and not kept).

A lattice cut (or a window cut) joins the crop's own texels with their copies one tile on, which sit at
the same phase of the pattern: the cut runs where they agree, mortar beside mortar. But a photographed
wall is rarely lit evenly. One tile on, every brick is a little lighter or darker, and where the cut
crosses a brick its two halves differ in tone: a diagonal split, seen at 3x on the lattice cut at a ramp of
0.05, which the verdict passes (``benchmarks/results/verdict.md``, kind ``lattice-lit``).

:func:`tone_matched` takes the light's change over one tile as the median difference between the crop's
texels and their copies over each cut's band (one figure per channel and axis), and removes it as a linear
ramp over the source places the tile's texels come from: a texel ``k`` texels along an axis from the crop's
first gets ``D * k / tile``. The copies one tile on then carry the crop's own tone, so the two sides of a cut
agree in tone wherever it runs, and the tile's tone continues across both wraps. Normal maps are left as
they are (lighting is not in them).

Measured (``benchmarks/lattice_tone.py``, ``results/lattice_tone.md``), not kept. At a ramp of 0.1 the bricks
the cut crosses are still split in two tones at 3x (the split is not only the light's: one median per axis
does not level it), yet the verdict passes the tile: every texel moves by a smooth amount, most by more than
the one 8-bit code within which the verdict finds a texel as a copy of its source, so the verdict cannot
read the tile as copies (it places 2-17 % of the texels, against 100 %) and judges it by its classifier
alone. That also passes the cuts of a brick whose scale drifts by 1-4 %, whose mortar lines jog at the cut
as before. A first form offset only a band beside each cut (each side cross-faded to the other's low-passed
tone), which keeps most texels copies; the verdict then names a seam along the band's straight edge, at 5
places on the ramp of 0.05 that it passed plain.
"""
from __future__ import annotations

import numpy as np

__all__ = ["tone_matched"]


def tone_matched(maps: list[np.ndarray], normals: list[bool], field: np.ndarray, offset: tuple[int, int],
                 tile: tuple[int, int], band: tuple[int, int]) -> list[np.ndarray]:
    """The tiles (float32, one per map) of a lattice or window cut (:func:`.cut.lattice_cut`'s ``field`` and
    ``offset``, for ``tile`` and ``band``) with the light's change over one tile removed (see the module
    notes).

    >>> y, x = np.mgrid[0:60, 0:60].astype(np.float32)
    >>> wall = (np.sin(2 * np.pi * x / 10) + 0.01 * x)[..., None]  # a pattern of period 10, lit unevenly
    >>> field = np.stack(np.mgrid[0:40, 0:40], -1) + 5
    >>> field[:, :4, 1] += 40  # the first 4 columns taken one tile on: 0.4 brighter than their neighbours
    >>> plain = wall[field[..., 0], field[..., 1]]
    >>> matched = tone_matched([wall], [False], field, (5, 5), (40, 40), (8, 8))[0]
    >>> step = lambda t: float(np.abs(t[:, 4] - t[:, 3] - (wall[0, 9] - wall[0, 8])).max())
    >>> round(step(plain), 2), step(matched) < 0.1
    (0.4, True)
    """
    (th, tw), (bh, bw) = tile, band
    y0, x0 = offset
    fy, fx = field[..., 0], field[..., 1]
    out = []
    for m, is_normal in zip(maps, normals):
        src = np.asarray(m, dtype=np.float32)
        src = src[..., None] if src.ndim == 2 else src
        t = np.ascontiguousarray(src[fy, fx])
        if is_normal or bw < 1 or bh < 1:
            out.append(t)
            continue
        # own - one tile on over each band, its median: the light's change over one tile, not the texels' own
        # differences where the copies sit a texel off the lattice or the pattern drifts
        d = np.median((src[y0: y0 + th + bh, x0: x0 + bw] - src[y0: y0 + th + bh, x0 + tw: x0 + tw + bw]
                       ).reshape(-1, src.shape[-1]), axis=0)
        e = np.median((src[y0: y0 + bh, x0: x0 + tw] - src[y0 + th: y0 + th + bh, x0: x0 + tw]
                       ).reshape(-1, src.shape[-1]), axis=0)
        ramp = d * ((fx - x0) / tw)[..., None] + e * ((fy - y0) / th)[..., None]
        t += ramp - ramp.mean(axis=(0, 1))
        out.append(t)
    return out

