"""Plain values passed in and out of the synthesis engine."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["MapInput", "QResult", "Candidate", "TileResult", "TrainingProgress", "stack_shape", "SCORE_SIDE",
           "score_halving"]

#: Layout candidates are compared on the source's grid, halved until its longest side is at most this (px).
SCORE_SIDE = 1024


def score_halving(height: int, width: int) -> int:
    """By how much a stack of ``height`` x ``width`` px is halved to compare its candidates (a power of two)."""
    return 2 ** max(0, math.ceil(math.log2(max(height, width) / SCORE_SIDE)))


@dataclass
class MapInput:
    """One map of a stack: ``pixels`` is (H, W, C) float32 in [-1, 1], C in 1..4."""

    name: str
    pixels: np.ndarray
    is_normal: bool = False
    #: one code value of the map's file in network units (2 / 255 for 8 bits, 0 for half and float:
    #: :attr:`.imaging.MapEncoding.network_code`), which decides how small a step the verdict can see in it
    code: float = 2 / 255

    def __post_init__(self) -> None:
        assert isinstance(self.pixels, np.ndarray) and self.pixels.ndim == 3, (
            f"map {self.name!r}: pixels must be an (H, W, C) array, got shape {getattr(self.pixels, 'shape', None)}")
        assert 1 <= self.pixels.shape[2] <= 4, f"map {self.name!r}: expected 1..4 channels, got {self.pixels.shape[2]}"

    @property
    def channels(self) -> int:
        return int(self.pixels.shape[2])


def stack_shape(maps: list[MapInput]) -> tuple[int, int]:
    """(H, W) shared by all maps; raises if they differ or names repeat."""
    assert maps, "a stack needs at least one map"
    names = [m.name for m in maps]
    assert len(set(names)) == len(names), f"map names must be unique, got {names}"
    shapes = {m.pixels.shape[:2] for m in maps}
    assert len(shapes) == 1, f"all maps of a stack must share H, W; got {sorted(shapes)}"
    for m in maps:
        assert np.isfinite(m.pixels).all(), f"map {m.name!r} has NaN or inf pixels"
    return tuple(int(v) for v in maps[0].pixels.shape[:2])


@dataclass
class QResult:
    """Discriminator-guided quality (paper section 4.2) of one candidate."""

    passed: bool
    tau: float  # gamma * min(D outside the bands)
    band_min_vertical: float
    band_min_horizontal: float
    d_map: np.ndarray  # (h, w) discriminator output (1 = real) on the tile
    band_vertical: np.ndarray  # (h, w) bool mask of the vertical band
    band_horizontal: np.ndarray  # (h, w) bool mask of the horizontal band

    @property
    def margin(self) -> float:
        """min(band minima) - tau; >= 0 exactly when passed. Ranks failing candidates."""
        return min(self.band_min_vertical, self.band_min_horizontal) - self.tau


@dataclass
class Candidate:
    crop_size: tuple[int, int]  # (c_h, c_w)
    offset: tuple[int, int]  # (y, x) of the crop in the input
    q: QResult
    seconds: float


@dataclass
class TileResult:
    maps: dict[str, np.ndarray]  # name -> (2c_h, 2c_w, C) float32 in [-1, 1], periodic
    crop_size: tuple[int, int]
    q_passed: bool  # Q of the chosen candidate: the crop search's criterion, not the product's verdict
    q: QResult
    candidates: list[Candidate]
    timings: dict[str, float]
    model_hash: str
    device: str
    precision: str
    offset: tuple[int, int] = (0, 0)  # (y, x) of the chosen crop


@dataclass
class TrainingProgress:
    iteration: int  # iterations done
    total: int
    it_per_s: float
    eta_s: float
    losses: dict[str, float] = field(default_factory=dict)
    elapsed_s: float = 0.0
