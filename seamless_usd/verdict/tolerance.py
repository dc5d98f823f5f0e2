"""Fidelity tolerances calibrated to the source's own spread.

Two halves of one source do not have exactly the same feature scale: on the bundled maps, half
against half reads 0.72-1.27 and quadrant against the whole 0.77-1.31. A tile as faithful as any part
of its source must not fail by chance, so a stack's scale tolerance is the fixed target
:data:`seamless_usd.metrics.TARGETS` widened to what the source's halves (top/bottom, left/right)
and quadrants score against the rest. The patch distance is already in units of the source's two halves'
distance from each other, so its tolerance is the fixed 1.2 of those units. A figure that could not
be measured (a tile or source too small for it) is outside its tolerance: it confirms nothing.
"""
from __future__ import annotations

import numpy as np

from seamless_usd.memo import ContentMemo
from seamless_usd.metrics import TARGETS, patch_distance, scale_ratio
from seamless_usd.metrics.fidelity import PATCH_SIZE

__all__ = ["FIDELITY_KEYS", "scale_tolerance", "faithfulness", "tolerance_words"]

FIDELITY_KEYS = ("scale_ratio", "patch_distance")


def _parts(source: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(part, rest) pairs: the halves against each other and every quadrant against the whole."""
    h, w = source.shape[:2]
    top, bottom = source[: h // 2], source[h // 2:]
    left, right = source[:, : w // 2], source[:, w // 2:]
    pairs = [(top, bottom), (bottom, top), (left, right), (right, left)]
    pairs += [(source[y: y + h // 2, x: x + w // 2], source) for y in (0, h // 2) for x in (0, w // 2)]
    return pairs


def scale_tolerance(source: np.ndarray, is_normal: bool = False) -> tuple[float, float]:
    """``(low, high)`` feature-scale tolerance for tiles of ``source`` (see the module notes).

    >>> rng = np.random.default_rng(0)
    >>> low, high = scale_tolerance(rng.normal(size=(64, 64)))
    >>> low <= 0.9 and high >= 1.1
    True
    """
    low, high = TARGETS["scale_ratio"]
    if min(source.shape[:2]) < 32:
        return low, high
    return _TOLERANCES.get((source,), is_normal, lambda: _scale_tolerance(source, is_normal, low, high))


#: Each source's scale tolerance, by its content: every candidate of a stack and the written tile are judged
#: against the same source.
_TOLERANCES: ContentMemo[tuple[float, float]] = ContentMemo()


def _scale_tolerance(source: np.ndarray, is_normal: bool, low: float, high: float) -> tuple[float, float]:
    ratios = [scale_ratio(a, b, is_normal) for a, b in _parts(source)]
    finite = [r for r in ratios if np.isfinite(r)]
    return (min([low] + finite), max([high] + finite))


def tolerance_words(low: float | None, high: float | None) -> str:
    """``"0.90-1.10"``, ``"at most 1.20"`` or ``"at least 0.90"``."""
    if low is not None and high is not None:
        return f"{low:.2f}-{high:.2f}"
    return f"at most {high:.2f}" if high is not None else f"at least {low:.2f}" if low is not None else "none"


def faithfulness(tiles: list[np.ndarray], sources: list[np.ndarray], normals: list[bool], names: list[str]
                 ) -> tuple[dict, dict, list[str]]:
    """Per map, its fidelity figures and tolerances, and the list of figures outside them."""
    figures: dict[str, dict[str, float | None]] = {}
    tolerances: dict[str, dict[str, list]] = {}
    failing: list[str] = []
    for tile, source, is_normal, name in zip(tiles, sources, normals, names):
        side = min(tile.shape[:2] + source.shape[:2])
        scale = scale_ratio(tile, source, is_normal) if side >= 16 else None
        patch = patch_distance(tile, source, is_normal) if side >= 4 * PATCH_SIZE else None
        bounds = {"scale_ratio": scale_tolerance(source, is_normal), "patch_distance": TARGETS["patch_distance"]}
        figures[name] = {"scale_ratio": None if scale is None else round(float(scale), 3),
                         "patch_distance": None if patch is None else round(float(patch), 3)}
        tolerances[name] = {k: [None if b is None else round(float(b), 3) for b in v] for k, v in bounds.items()}
        for key, value in figures[name].items():
            low, high = bounds[key]
            words = tolerance_words(low, high)
            if value is None:
                failing.append(f"{name}: {key} not measured (the tile is {side} px; tolerance {words})")
            elif not np.isfinite(value) or (low is not None and value < low) or (high is not None and value > high):
                failing.append(f"{name}: {key} {value:.3g} (tolerance {words})")
    return figures, tolerances, failing
