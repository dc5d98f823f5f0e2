"""The working-resolution policy and resampling (OpenImageIO ``ImageBufAlgo.resize``).

Every map of a stack covers the same UV square, so the maps are brought to one pixel grid, the
*working size* ``(W, H)``:

1. ``common="largest"`` (default): ``W`` = the largest width, ``H`` = the largest height of the
   stack's maps, so no map loses detail; ``"smallest"``: the smallest width and height.
2. When ``max_size`` is set and the longer side exceeds it, both sides are scaled by the same
   factor so the longer side is ``max_size`` (aspect ratio kept, rounded, at least 1 px).

Maps whose size differs from the working size are resampled with ``filter`` (``"auto"``:
``lanczos3`` when enlarging, ``blackman-harris`` when shrinking, OpenImageIO's own choices; the
filter widens with the shrink factor, so shrinking averages properly).
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
import OpenImageIO as oiio

from seamless_usd.errors import UsageError

__all__ = ["FILTERS", "WorkingResolution", "grown_linear", "resample"]

# OpenImageIO 2D filter names accepted by ImageBufAlgo.resize, plus "auto".
FILTERS = (
    "auto",
    "box",
    "triangle",
    "gaussian",
    "sharp-gaussian",
    "catmull-rom",
    "blackman-harris",
    "sinc",
    "lanczos3",
    "radial-lanczos3",
    "mitchell",
    "bspline",
    "cubic",
    "keys",
    "simon",
    "rifman",
)
_COMMON = ("largest", "smallest")


@dataclass(frozen=True)
class WorkingResolution:
    """How the maps of a stack are brought to one working size (see the module docstring).

    Examples
    --------
    >>> WorkingResolution(max_size=256).working_size([(512, 512), (1024, 512)])
    (256, 128)
    >>> WorkingResolution.native().working_size([(300, 200), (150, 100)])
    (300, 200)
    """

    max_size: int | None = None  # cap on the longer side; None = native (no cap): presets set it
    filter: str = "auto"  # one of FILTERS
    common: str = "largest"  # "largest" keeps every map's detail; "smallest" never upsamples

    def __post_init__(self) -> None:
        if self.filter not in FILTERS:
            raise UsageError(f"unknown resampling filter {self.filter!r}; valid: {', '.join(FILTERS)}")
        if self.common not in _COMMON:
            raise UsageError(f"unknown common size {self.common!r}; valid: {', '.join(_COMMON)}")
        if self.max_size is not None and self.max_size < 1:
            raise UsageError(f"max_size must be a positive number of pixels, got {self.max_size}")

    @classmethod
    def native(cls) -> WorkingResolution:
        """No cap: the largest map's size."""
        return cls()

    def working_size(self, sizes: Sequence[tuple[int, int]]) -> tuple[int, int]:
        """The common ``(W, H)`` for maps of the given ``(W, H)`` sizes."""
        if not sizes:
            raise ValueError("a stack needs at least one map")
        pick = max if self.common == "largest" else min
        w, h = pick(s[0] for s in sizes), pick(s[1] for s in sizes)
        if self.max_size is not None and max(w, h) > self.max_size:
            factor = self.max_size / max(w, h)
            w, h = max(1, round(w * factor)), max(1, round(h * factor))
        return int(w), int(h)

    def to_dict(self) -> dict:
        return asdict(self)


def resample(values: np.ndarray, size: tuple[int, int], filter: str = "auto") -> np.ndarray:
    """Resize ``(H, W, C)`` (or ``(H, W)``) float values to ``size = (W, H)``.

    Returns the input unchanged when it already has that size. Values may overshoot their
    range with ringing filters; callers clip or renormalise.

    Examples
    --------
    >>> resample(np.ones((4, 4, 2), np.float32), (8, 2)).shape
    (2, 8, 2)
    """
    if filter not in FILTERS:
        raise UsageError(f"unknown resampling filter {filter!r}; valid: {', '.join(FILTERS)}")
    a = np.asarray(values, dtype=np.float32)
    flat = a.ndim == 2
    if flat:
        a = a[..., None]
    h, w, c = a.shape
    new_w, new_h = size
    if (new_w, new_h) == (w, h):
        return a[..., 0] if flat else a
    if filter == "auto":
        filter = "lanczos3" if new_w * new_h > w * h else "blackman-harris"
    src = oiio.ImageBuf(oiio.ImageSpec(w, h, c, oiio.FLOAT))
    src.set_pixels(oiio.ROI(), np.ascontiguousarray(a))
    dst = oiio.ImageBufAlgo.resize(src, filter, roi=oiio.ROI(0, new_w, 0, new_h, 0, 1, 0, c))
    if dst.has_error:
        raise RuntimeError(f"resampling to {new_w}x{new_h} failed: {dst.geterror()}")
    out = np.asarray(dst.get_pixels(oiio.FLOAT), dtype=np.float32).reshape(new_h, new_w, c)
    return out[..., 0] if flat else out


def grown_linear(a: np.ndarray, hw: tuple[int, int]) -> np.ndarray:
    """``a`` (h, w) brought to (H, W) by linear interpolation between texel centres (held at the border): a
    smooth field read on a small grid (a photo's light, a lattice's drift) brought to full resolution."""
    h, w = a.shape

    def axis(n: int, size: int) -> np.ndarray:
        return np.clip((np.arange(size) + 0.5) * n / size - 0.5, 0, n - 1)

    ys, xs = axis(h, hw[0]), axis(w, hw[1])
    rows = np.stack([np.interp(ys, np.arange(h), a[:, j]) for j in range(w)], 1)
    return np.stack([np.interp(xs, np.arange(w), rows[i]) for i in range(hw[0])], 0).astype(np.float32)
