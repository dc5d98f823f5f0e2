"""The affine (optionally log-toned) map of a channel's linear values onto the network domain [-1, 1]:
:class:`ValueRange`, with its :class:`Tone` (see :mod:`.encoding`, "range")."""
from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

__all__ = ["Tone", "ValueRange"]


class Tone(str, Enum):
    """Curve applied before the affine range map."""

    LINEAR = "linear"  # values within [-1, 1]: the affine map alone (exact for LDR data)
    LOG = "log"  # sign(x) * log1p(|x|): HDR values, invertible with expm1


@dataclass(frozen=True)
class ValueRange:
    """Maps linear values in ``[lo, hi]`` to [-1, 1] through ``tone``; invertible, never clipping.

    Examples
    --------
    >>> r = ValueRange(0.0, 8.0, Tone.LOG)
    >>> float(r.to_network(np.array(8.0))), round(float(r.from_network(r.to_network(np.array(3.0)))), 9)
    (1.0, 3.0)
    """

    lo: float = 0.0
    hi: float = 1.0
    tone: Tone = Tone.LINEAR

    def __post_init__(self) -> None:
        if not self.hi > self.lo:
            raise ValueError(f"ValueRange needs hi > lo, got [{self.lo}, {self.hi}]")

    @classmethod
    def fit(cls, values: np.ndarray) -> ValueRange:
        """The range covering ``values`` and [0, 1], with the log tone when they leave [-1, 1]."""
        v = np.asarray(values, dtype=np.float64)
        v = v[np.isfinite(v)]
        lo = min(0.0, float(v.min())) if v.size else 0.0
        hi = max(1.0, float(v.max())) if v.size else 1.0
        tone = Tone.LOG if (hi > 1.0 or lo < -1.0) else Tone.LINEAR
        return cls(lo, hi, tone)

    def _curve(self, x: np.ndarray) -> np.ndarray:
        return x if self.tone is Tone.LINEAR else np.sign(x) * np.log1p(np.abs(x))

    def _uncurve(self, s: np.ndarray) -> np.ndarray:
        return s if self.tone is Tone.LINEAR else np.sign(s) * np.expm1(np.abs(s))

    def to_network(self, x: np.ndarray) -> np.ndarray:
        a, b = self._curve(np.float64(self.lo)), self._curve(np.float64(self.hi))
        return 2.0 * (self._curve(np.asarray(x, np.float64)) - a) / (b - a) - 1.0

    def from_network(self, y: np.ndarray) -> np.ndarray:
        a, b = self._curve(np.float64(self.lo)), self._curve(np.float64(self.hi))
        return self._uncurve((np.asarray(y, np.float64) + 1.0) * 0.5 * (b - a) + a)
