"""Structure figure: whether a tile keeps the source's long lines and closed cells whole.

Scale and patch distance compare local statistics: a tile whose stones are cut in half and glued to
other halves, whose plank gaps stop and restart a few texels aside, reads right on both. This figure
reads the texture's *line network* instead, segmentation-free:

1. the map (its first principal channel, read at most :data:`WORK_SIDE` px) is high-passed at each of
   :data:`SIGMAS` px, and its darkest :data:`DARK_SHARE` (a threshold taken on the source, applied to
   both) are the texture's lines: joints, gaps, cracks, dark grain;
2. the lines are thinned to one texel (a skeleton), pieces shorter than :data:`MIN_PIECE` dropped as
   grain, and read as a graph: its *line ends* (skeleton
   texels with one neighbour) per 1000 texels of line, and its *line length*, the length-weighted
   mean length of its connected pieces;
3. each is a ratio to the source's. A joint broken into dashes doubles the ends and shortens the
   pieces; a cell cut in half ends its joints mid-stone.

At each scale the figure is the worse of the two as a ratio >= 1 (``exp(max |log ratio|)``; 1.0 is the
source's structure) and its tolerance the source's own spread, the same figure between the source's
halves (top against bottom, left against right). The structure figure is the largest figure/spread over
the scales: above 1.0, the tile's lines break (or merge) more than the source's vary across itself.
"""
from __future__ import annotations

import numpy as np

from ..memo import ContentMemo

__all__ = ["WORK_SIDE", "SIGMAS", "DARK_SHARE", "STRUCTURE_TARGET", "line_network", "structure_figures"]

#: Longest side (px) the network is read at: structure (planks, stones, joints) lives at coarse scale.
WORK_SIDE = 512
#: High-pass scales (px at the working size): grain lines at the finest, joints and plank gaps above.
SIGMAS = (2.0, 4.0, 8.0, 16.0)
#: Largest structure figure that passes. 1.0 would be the source's own half-vs-half spread; another
#: sample of the same stone pattern reads 1.30 and the source moved by three texels up to 1.14, while
#: tiles rebuilt from 48 px blocks of the source read 1.6-20 (cells, stripes, the turned brick, wood
#: roughness; wood colour's grain is short strokes and reads 0.97 cut or not).
STRUCTURE_TARGET = 1.5
#: Share of the source's texels taken as its lines.
DARK_SHARE = 0.2
#: Skeleton pieces shorter than this (texels at the working size) are grain, not lines.
MIN_PIECE = 12


def _channel(m: np.ndarray, basis: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The map's first principal channel (the source's axis when ``basis`` is given), and that axis."""
    a = np.asarray(m, dtype=np.float64)
    a = a[..., None] if a.ndim == 2 else a
    flat = a.reshape(-1, a.shape[-1])
    if basis is None:
        if a.shape[-1] == 1:
            basis = np.ones(1)
        else:
            cov = np.cov(flat - flat.mean(0), rowvar=False)
            basis = np.linalg.eigh(cov)[1][:, -1]
            basis = basis * np.sign(basis.sum() or 1.0)  # brighter is positive
    return (flat @ basis).reshape(a.shape[:2]), basis


def _working(u: np.ndarray) -> np.ndarray:
    f = max(1, int(np.ceil(max(u.shape) / WORK_SIDE)))
    if f == 1:
        return u
    h, w = (u.shape[0] // f) * f, (u.shape[1] // f) * f
    return u[:h, :w].reshape(h // f, f, w // f, f).mean(axis=(1, 3))


def _highpass(u: np.ndarray, periodic: bool, sigma: float) -> np.ndarray:
    from scipy import ndimage

    return u - ndimage.gaussian_filter(u, sigma, mode="wrap" if periodic else "reflect")


def line_network(lines: np.ndarray) -> dict[str, float]:
    """Ends per 1000 line texels and length-weighted mean piece length (texels) of a bool line mask."""
    from scipy import ndimage
    from skimage.morphology import skeletonize

    skel = skeletonize(lines)
    labels, _ = ndimage.label(skel, structure=np.ones((3, 3), bool))
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    skel &= sizes[labels] >= MIN_PIECE  # specks of grain are not lines
    sizes = sizes[sizes >= MIN_PIECE].astype(np.float64)
    total = int(skel.sum())
    if total == 0:
        return {"ends": 0.0, "length": 0.0, "texels": 0}
    nb = ndimage.convolve(skel.astype(np.int32), np.ones((3, 3), np.int32), mode="constant") - 1
    ends = int((skel & (nb == 1)).sum())
    return {"ends": 1000.0 * ends / total, "length": float((sizes ** 2).sum() / sizes.sum()), "texels": total}


def _network(u: np.ndarray, threshold: float, periodic: bool, sigma: float) -> dict[str, float]:
    hp = _highpass(u, periodic, sigma)
    return line_network(hp < threshold)


def _ratio_figure(a: dict[str, float], b: dict[str, float]) -> tuple[float, float, float]:
    """(ends ratio, length ratio, figure) of network ``a`` against ``b``."""
    ends = (a["ends"] + 1.0) / (b["ends"] + 1.0)  # +1: a source without ends is not divided by zero
    length = (a["length"] + 1.0) / (b["length"] + 1.0)
    worst = max(abs(np.log(ends)), abs(np.log(length)))
    return float(ends), float(length), float(np.exp(worst))


def _split(s: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    h, w = s.shape
    return [(s[: h // 2], s[h // 2:]), (s[:, : w // 2], s[:, w // 2:])]


#: A source's principal axis and, per scale, its line threshold, network and half-vs-half spread: every
#: candidate tile of a stack (and every seed's) is read against the same source.
_SOURCES: ContentMemo[tuple[np.ndarray, dict]] = ContentMemo(keep=16)


def _source_network(source: np.ndarray) -> tuple[np.ndarray, dict]:
    s, basis = _channel(source, None)
    s = _working(s)
    own = {}
    for sigma in SIGMAS:
        threshold = float(np.quantile(_highpass(s, False, sigma), DARK_SHARE))
        spread = max([1.0] + [_ratio_figure(_network(a, threshold, False, sigma), _network(b, threshold, False, sigma))[2]
                              for a, b in _split(s)])
        own[sigma] = (threshold, _network(s, threshold, False, sigma), spread)
    return basis, own


def structure_figures(tile: np.ndarray, source: np.ndarray) -> dict:
    """The structure of a periodic tile against its source (both at one texel scale; see the module notes).

    Returns ``{"structure": worst excess, "scales": {sigma: {"figure", "spread", "ends", "length"}}}``: at
    each high-pass scale, the tile's figure against the source and the source's own half-vs-half spread;
    ``structure`` is the largest ``figure / spread``: 1.0 when the tile's line network differs from the
    source's as much as the source's halves differ from each other; :data:`STRUCTURE_TARGET` is the pass mark.
    """
    basis, own = _SOURCES.get((np.asarray(source),), None, lambda: _source_network(source))
    t = _working(_channel(tile, basis)[0])
    scales = {}
    for sigma in SIGMAS:
        threshold, src, spread = own[sigma]
        ends, length, figure = _ratio_figure(_network(t, threshold, True, sigma), src)
        scales[sigma] = {"figure": round(figure, 3), "spread": round(spread, 3), "ends": round(ends, 3),
                         "length": round(length, 3)}
    worst = max(v["figure"] / v["spread"] for v in scales.values())
    return {"structure": round(float(worst), 3), "scales": scales}
