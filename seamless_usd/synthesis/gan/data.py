"""Stack <-> tensor conversion and the deterministic training crops."""
from __future__ import annotations

import numpy as np
import torch

from ..types import MapInput, stack_shape

__all__ = ["stack_tensor", "split_maps", "training_crops", "effective_k"]


def stack_tensor(maps: list[MapInput], device: torch.device) -> torch.Tensor:
    """Concatenate the maps along channels: (1, sum C_i, H, W) float32 on ``device``."""
    stack_shape(maps)
    arr = np.concatenate([np.asarray(m.pixels, dtype=np.float32) for m in maps], axis=2)  # (H, W, Ctot)
    return torch.from_numpy(np.ascontiguousarray(arr.transpose(2, 0, 1)))[None].to(device)


def split_maps(x: torch.Tensor, channels: list[int]) -> list[torch.Tensor]:
    """(N, sum C_i, H, W) -> [(N, C_i, H, W)]."""
    assert x.shape[1] == sum(channels), f"expected {sum(channels)} channels, got {x.shape[1]}"
    return list(torch.split(x, channels, dim=1))


def effective_k(k: int, height: int, width: int) -> int:
    """``k`` shrunk (multiple of 8) so that the 2k target crop fits the stack."""
    fit = min(k, min(height, width) // 2) // 8 * 8
    assert fit >= 16, f"stack of {height}x{width} is too small to train on (needs at least 32x32)"
    return fit


def training_crops(seed: int, step: int, height: int, width: int, k: int, index: int = 0) -> tuple[int, int, int, int]:
    """(ty, tx, sy, sx): the 2k target crop's corner in the stack and the k source crop's corner inside it.

    A pure function of (seed, step, index), so a resumed run sees exactly the crops an uninterrupted one
    would; ``index`` numbers the crops of one step (crop 0 is the one a one-crop run sees).
    """
    rng = np.random.default_rng([seed, step] if index == 0 else [seed, step, 1000 + index])
    ty = int(rng.integers(0, height - 2 * k + 1))
    tx = int(rng.integers(0, width - 2 * k + 1))
    sy = int(rng.integers(0, k + 1))
    sx = int(rng.integers(0, k + 1))
    return ty, tx, sy, sx
