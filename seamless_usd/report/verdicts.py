"""Verdicts in words for the report's figures: "scale kept (0.98)", "centre seam visible (1.6)".

Each figure with a target (the quality benchmark's targets, ``seamless_usd.metrics.TARGETS``: a
mapping ``key -> (low or None, high or None)``) gets a short sentence saying what the number means
for the tile and whether it is within its target. The targets are read when first needed; while
the metrics package does not provide them, the values below are used.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["FALLBACK_TARGETS", "LABELS", "SEAM_KEYS", "TORUS_NOTE", "Verdict", "targets", "verdict", "target_text"]

#: The quality benchmark's targets, used when ``seamless_usd.metrics.TARGETS`` is not there.
FALLBACK_TARGETS: dict[str, tuple[float | None, float | None]] = {
    "seam_ratio_x": (None, 1.15),
    "seam_ratio_y": (None, 1.15),
    "centre_seam_x": (None, 1.15),
    "centre_seam_y": (None, 1.15),
    "scale_ratio": (0.9, 1.1),
    "patch_distance": (None, 1.2),
}

#: Readable names of the figures (``x``: the seam met walking across the picture, a vertical line).
LABELS: dict[str, str] = {
    "seam_ratio_x": "border seam, left|right",
    "seam_ratio_y": "border seam, top|bottom",
    "seam_ratio2_x": "border seam (2nd diff.), left|right",
    "seam_ratio2_y": "border seam (2nd diff.), top|bottom",
    "centre_seam_x": "centre seam, vertical line",
    "centre_seam_y": "centre seam, horizontal line",
    "scale_ratio": "feature scale vs source",
    "patch_distance": "patch distance vs source",
    "ps_score": "periodic-plus-smooth score",
    "detail_ratio": "detail at the borders",
    "detail_ratio_centre": "detail at the centre lines",
    "ssim": "SSIM vs source",
    "gram_distance": "Gram distance vs source",
    "bad_joins": "bad joins between copied blocks",
    "join_length": "their length (texels)",
    "coherence": "coherence of the copies",
    "structure": "structure vs source (≤ 1.5: lines and cells kept)",
}

# key -> (words when within target, words below the low bound, words above the high bound)
_WORDS: dict[str, tuple[str, str, str]] = {
    "seam_ratio_x": ("no border seam", "no border seam", "border seam visible"),
    "seam_ratio_y": ("no border seam", "no border seam", "border seam visible"),
    "seam_ratio2_x": ("no border seam", "no border seam", "border seam visible"),
    "seam_ratio2_y": ("no border seam", "no border seam", "border seam visible"),
    "centre_seam_x": ("no centre seam", "no centre seam", "centre seam visible"),
    "centre_seam_y": ("no centre seam", "no centre seam", "centre seam visible"),
    "scale_ratio": ("scale kept", "magnified or blurred", "shrunk or sharpened"),
    "patch_distance": ("patches like the source's", "patches like the source's", "patches unlike the source's"),
    "detail_ratio": ("detail kept at the borders", "borders blurred", "borders harsher than the rest"),
    "detail_ratio_centre": ("detail kept at the centre", "centre blurred", "centre harsher than the rest"),
    "ssim": ("close to the source", "far from the source", "close to the source"),
}


# The seam figures of a tile made on a torus (refined, or cut from the source): its border and centre lines
# are lines of the texture like any other, so a high figure there reads a strong line, which may be the
# texture's own (a mortar joint) as much as a join.
_TORUS_WORDS: dict[str, tuple[str, str, str]] = {
    **{k: ("no strong line at the border", "no strong line at the border", "strong line at the border")
       for k in ("seam_ratio_x", "seam_ratio_y", "seam_ratio2_x", "seam_ratio2_y")},
    **{k: ("no strong line at the centre", "no strong line at the centre", "strong line at the centre")
       for k in ("centre_seam_x", "centre_seam_y")},
}

#: The seam figures, whose words change on a tile made on a torus.
SEAM_KEYS: tuple[str, ...] = tuple(_TORUS_WORDS)

#: What a high seam figure means on a tile made on a torus, for the report beside those figures.
TORUS_NOTE = ("This tile was made on a torus (refined, or cut from the source): its border and centre lines are "
              "lines of the texture like any other, so a strong line there may be the texture's own, a mortar "
              "joint say, as much as a join. Whether it is a seam is the verdict's call: its seam detector "
              "compares every line with the source's own lines.")


@dataclass(frozen=True)
class Verdict:
    """A figure in words: ``text`` ("scale kept (0.98)"), ``ok`` (True within target, False
    outside, None without a target) and the ``target`` it was judged against."""

    key: str
    value: float | None
    text: str
    ok: bool | None
    target: tuple[float | None, float | None] | None = None


def targets(tolerances: dict[str, list] | None = None) -> dict[str, tuple[float | None, float | None]]:
    """The figures the verdict holds to a tolerance (feature scale, patch distance), with ``tolerances``
    (the stack's own, from its verdict: ``key -> [low, high]``) over the fixed targets. The seam ratios
    have none: whether a tile has a seam is the seam detector's call, not theirs."""
    merged: dict[str, tuple[float | None, float | None]] = {k: v for k, v in FALLBACK_TARGETS.items()
                                                             if k not in SEAM_KEYS}
    try:
        from seamless_usd import metrics

        found = getattr(metrics, "TARGETS", None)
    except ImportError:  # pragma: no cover - the metrics package is part of the project
        found = None
    if isinstance(found, dict):
        merged.update({k: tuple(v) for k, v in found.items() if k in merged})
    for key, bounds in (tolerances or {}).items():
        if key in merged and len(bounds) == 2:
            merged[key] = (bounds[0], bounds[1])
    return merged


def _num(value: float) -> str:
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:.3g}" if abs(value) < 100 else f"{value:.0f}"


def target_text(bounds: tuple[float | None, float | None] | None) -> str:
    """``"≤ 1.15"``, ``"≥ 0.5"``, ``"0.9-1.1"`` or ``""``."""
    if not bounds:
        return ""
    low, high = bounds
    if low is not None and high is not None:
        return f"{_num(low)}–{_num(high)}"
    if high is not None:
        return f"≤ {_num(high)}"
    if low is not None:
        return f"≥ {_num(low)}"
    return ""


def verdict(key: str, value: float | None, bounds: tuple[float | None, float | None] | None = None,
            torus: bool = False) -> Verdict:
    """The verdict on one figure of a new tile.

    Parameters
    ----------
    key : the metric's key (``scale_ratio``, ``centre_seam_x``, ...).
    value : its value; None or NaN gives "not measured".
    bounds : ``(low, high)`` target; default from :func:`targets`.
    torus : the tile was made on a torus (refined, or cut from the source), where the seam figures read
        a line of the texture, not the place where copies of it meet (see :data:`TORUS_NOTE`).

    Examples
    --------
    >>> verdict("scale_ratio", 0.98).text
    'scale kept (0.98)'
    >>> verdict("centre_seam_x", 1.6, (None, 1.15)).text, verdict("centre_seam_x", 1.6, (None, 1.15)).ok
    ('centre seam visible (1.6)', False)
    >>> verdict("seam_ratio_x", 1.53, (None, 1.15), torus=True).text
    'strong line at the border (1.53)'
    >>> verdict("seam_ratio_x", 1.53).ok is None  # no target: whether there is a seam is the verdict's call
    """
    bounds = bounds if bounds is not None else targets().get(key)
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return Verdict(key, None, "not measured", None, bounds)
    value = float(value)
    words = _TORUS_WORDS if torus and key in _TORUS_WORDS else _WORDS
    within_words, low_words, high_words = words.get(key, ("within target", "below target", "above target"))
    if not bounds or bounds == (None, None):
        return Verdict(key, value, "", None, None)
    low, high = bounds
    if low is not None and value < low:
        return Verdict(key, value, f"{low_words} ({_num(value)})", False, bounds)
    if high is not None and value > high:
        return Verdict(key, value, f"{high_words} ({_num(value)})", False, bounds)
    return Verdict(key, value, f"{within_words} ({_num(value)})", True, bounds)
