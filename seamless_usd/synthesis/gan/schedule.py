"""Learning-rate schedule as a pure function of the iteration."""
from __future__ import annotations

__all__ = ["learning_rate"]


def learning_rate(step: int, total: int, base: float, milestones: tuple[float, ...], decay: float) -> float:
    """``base`` divided by ``decay`` once per milestone fraction of ``total`` already reached.

    >>> learning_rate(30_000, 50_000, 2e-4, (0.6, 0.8), 5.0)
    4e-05
    """
    n = sum(step >= round(m * total) for m in milestones)
    return base / decay**n
