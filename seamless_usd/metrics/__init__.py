"""Seamlessness and fidelity metrics for texture tiles (numpy only).

Used by the process report (per-map seam figures) and by ``benchmarks/quality.py``.

Conventions
-----------
Value domain
    Every function takes a tile as a float array of shape ``(H, W)`` or ``(H, W, C)``. The
    *network domain* is ``[-1, 1]`` (file value ``v`` in ``[0, 1]`` maps to ``2 v - 1``); it is
    what :mod:`seamless_usd.synthesis` produces and what the benchmark feeds in. The seam,
    periodic-plus-smooth and detail figures are ratios, so they do not depend on an affine change
    of the values: file values in ``[0, 1]`` give the same numbers. Only SSIM needs the value range
    (``data_range``, 2.0 for the network domain, 1.0 for file values).
Normal maps
    With ``is_normal=True`` the tile holds tangent-space normal *vectors* in ``[-1, 1]`` (the
    network domain; decode a ``[0, 1]`` file with ``2 v - 1`` first), with 2 channels (x, y; z is
    rebuilt as ``sqrt(1 - x^2 - y^2)``) or 3 channels. They are normalised to unit length, and
    differences between neighbours are measured as the angle between the unit normals.
Axes
    ``x`` names the seam met when walking horizontally across the tile's left/right border
    (between column ``W - 1`` and column ``0``), ``y`` the one met walking vertically across the
    top/bottom border (between row ``H - 1`` and row ``0``). These are exactly the seams of the
    2x2 tiling of the tile.
Non-finite values
    NaN or infinite pixels make every metric undefined: each function raises ``ValueError``
    saying how many there are. A ratio whose numerator and denominator are both zero (a constant
    image) is 1.0; a non-zero numerator over a zero denominator is ``inf``.

Metrics
-------
seam ratio (:func:`seam_ratios`)
    mean |wrap-around neighbour difference| / mean |interior neighbour difference|, per axis, and
    the same with second differences. About 1 for a tileable image, well above 1 across a seam.
periodic-plus-smooth score (:func:`ps_score`)
    Moisan (2011) splits ``u = p + s`` into a periodic part ``p`` and a smooth part ``s`` carrying
    the border discontinuities; the score is ``||s|| / ||u - mean(u)||`` (near 0 when tileable).
detail ratio (:func:`detail_ratio`)
    RMS of the high-pass image (``u`` minus its periodic Gaussian blur) inside the seam bands over
    the same outside them. A blurred seam (crossfade) gives < 1, a hard seam > 1.
fidelity (:func:`scale_ratio`, :func:`patch_distance`, :func:`ssim_tiled`, :func:`gram_distance`)
    Measured against the source, so they see what seam figures cannot: a magnified, blurred or
    invented tile. The feature-scale ratio compares power-weighted mean log radial frequencies
    (about 1 when the scale is kept, 0.5 when magnified 2x or blurred); the patch distance is a
    sliced Wasserstein distance between 7x7 patch distributions on three pyramid levels, in units
    of the same figure between the source's two halves. SSIM of the tile repeated to the source's
    size (the paper's Table 2 protocol) and a Gram distance complete them.

Reference: L. Moisan, "Periodic plus smooth image decomposition", J. Math. Imaging Vis. 39 (2011).
"""
from __future__ import annotations

import numpy as np

from .common import BAND_FRACTION, HIGHPASS_SIGMA, _prepare, as_hwc, unit_normals
from .fidelity import (PATCH_SIZE, FeatureFn, gram_distance, gram_matrix, mean_log_frequency, patch_distance, patch_sw,
                       scale_ratio, source_halves, ssim_tiled, tile_to)
from .pictures import preview_uint8, tile_2x2
from .seams import (centre_band_mask, centre_seam_ratios, detail_ratio, highpass, periodic_smooth_decomposition,
                    ps_score, seam_band_mask, seam_ratios)

__all__ = [
    "METRIC_KEYS",
    "BAND_FRACTION",
    "HIGHPASS_SIGMA",
    "as_hwc",
    "unit_normals",
    "seam_ratios",
    "centre_seam_ratios",
    "periodic_smooth_decomposition",
    "ps_score",
    "seam_band_mask",
    "centre_band_mask",
    "highpass",
    "detail_ratio",
    "tile_to",
    "ssim_tiled",
    "gram_matrix",
    "gram_distance",
    "map_metrics",
    "TARGETS",
    "FIDELITY_KEYS",
    "outside_target",
    "failing_figures",
    "scale_ratio",
    "mean_log_frequency",
    "patch_distance",
    "patch_sw",
    "source_halves",
    "tile_2x2",
    "preview_uint8",
]

#: Keys of :func:`map_metrics`' result, in a stable order (also the benchmark's table columns).
METRIC_KEYS: tuple[str, ...] = (
    "seam_ratio_x",
    "seam_ratio_y",
    "seam_ratio2_x",
    "seam_ratio2_y",
    "centre_seam_x",
    "centre_seam_y",
    "ps_score",
    "detail_ratio",
    "detail_ratio_centre",
    "ssim",
    "gram_distance",
    "scale_ratio",
    "patch_distance",
)

#: Targets per figure, ``key -> (low, high)`` (None: unbounded). The quality benchmark holds every
#: map to all of them. Whether a processed stack *passed* is the verdict's (:mod:`seamless_usd.verdict`):
#: its seam detector, and tolerances for :data:`FIDELITY_KEYS` that start from these targets and widen
#: to the source's own spread; the seam ratios below are figures for the benchmark and the report only. Feature scale within 10 % of the source's; patch distribution no
#: further from the source than 1.2x the source's two halves are from each other; seams across the
#: border and the centre lines at most 15 % stronger than the tile's own interior edges.
TARGETS: dict[str, tuple[float | None, float | None]] = {
    "scale_ratio": (0.9, 1.1),
    "patch_distance": (None, 1.2),
    "seam_ratio_x": (None, 1.15),
    "seam_ratio_y": (None, 1.15),
    "centre_seam_x": (None, 1.15),
    "centre_seam_y": (None, 1.15),
}

#: The figures measured against the source that decide whether a stack passes.
FIDELITY_KEYS: tuple[str, ...] = ("scale_ratio", "patch_distance")


def outside_target(key: str, value: float | None) -> bool:
    """Whether ``value`` of figure ``key`` misses its :data:`TARGETS` entry (False without a target).
    A figure that was not measured (None) confirms nothing, so it misses its target.

    >>> outside_target("scale_ratio", 0.5), outside_target("scale_ratio", 1.0), outside_target("scale_ratio", None)
    (True, False, True)
    """
    if key not in TARGETS:
        return False
    if value is None:
        return True
    low, high = TARGETS[key]
    v = float(value)
    return not np.isfinite(v) or (low is not None and v < low) or (high is not None and v > high)


def failing_figures(figures: dict[str, float | None], keys: tuple[str, ...] = FIDELITY_KEYS) -> list[str]:
    """``"key value"`` for every figure of ``keys`` outside its target, e.g. ``["scale_ratio 0.62"]``."""
    return [f"{k} {figures[k]:.3g}" if figures.get(k) is not None else f"{k} not measured"
            for k in keys if outside_target(k, figures.get(k))]


# --------------------------------------------------------------------------------------------
# Everything at once
# --------------------------------------------------------------------------------------------


def map_metrics(
    tile: np.ndarray,
    source: np.ndarray | None = None,
    is_normal: bool = False,
    *,
    features: FeatureFn | None = None,
    data_range: float = 2.0,
    band: float = BAND_FRACTION,
    sigma: float = HIGHPASS_SIGMA,
) -> dict[str, float | None]:
    """All metrics of one map's tile, keyed by :data:`METRIC_KEYS` (in that order).

    Parameters
    ----------
    tile : array_like
        The tileable output ``(H, W)`` or ``(H, W, C)``, network domain ``[-1, 1]``.
    source : array_like, optional
        The input map in the same domain; without it ``ssim`` and ``gram_distance`` are None.
    is_normal : bool
        Whether the map holds normal vectors.
    features : callable, optional
        Feature extractor for :func:`gram_distance`; without it ``gram_distance`` is None.
        Normal maps are passed to it as unit vectors.
    data_range : float
        SSIM value range (2.0 for the network domain).
    band, sigma : float
        Seam band half-width fraction and high-pass sigma (see :func:`detail_ratio`).

    Returns
    -------
    dict
        ``seam_ratio_x``, ``seam_ratio_y``, ``seam_ratio2_x``, ``seam_ratio2_y``,
        ``centre_seam_x``, ``centre_seam_y`` (across the centre lines), ``ps_score``,
        ``detail_ratio`` (seam bands), ``detail_ratio_centre`` (centre bands), ``ssim``,
        ``gram_distance``, ``scale_ratio`` and ``patch_distance`` (against the source; None without
        one, or below 16 and 28 px).

    Raises
    ------
    ValueError
        On NaN/inf values or unusable shapes.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> m = map_metrics(rng.uniform(-1, 1, (32, 32, 3)), rng.uniform(-1, 1, (48, 48, 3)))
    >>> list(m) == list(METRIC_KEYS)
    True
    """
    u = _prepare(tile, is_normal)
    out: dict[str, float | None] = dict.fromkeys(METRIC_KEYS)
    out.update(seam_ratios(u, is_normal))
    out.update(centre_seam_ratios(u, is_normal))
    out["ps_score"] = ps_score(u)
    out["detail_ratio"] = detail_ratio(u, band=band, sigma=sigma, where="seams")
    out["detail_ratio_centre"] = detail_ratio(u, band=band, sigma=sigma, where="centre")
    if source is not None:
        s = _prepare(source, is_normal, "source")
        out["ssim"] = ssim_tiled(u, s, data_range=2.0 if is_normal else data_range)
        if features is not None:
            out["gram_distance"] = gram_distance(tile_to(u, s.shape), s, features)
        side = min(u.shape[:2] + s.shape[:2])
        if side >= 16:
            out["scale_ratio"] = scale_ratio(u, s, is_normal)
        if side >= 4 * PATCH_SIZE:  # room for 7x7 patches in each half of the source
            out["patch_distance"] = patch_distance(u, s, is_normal)
    return out


