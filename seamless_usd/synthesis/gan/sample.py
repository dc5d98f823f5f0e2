"""Discriminator-guided search for the largest tileable crop (paper section 4.2)."""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Iterator

import numpy as np
import torch

from .data import stack_tensor
from ..precision import autocast
from .quality import quality
from .tiling import tile_generate
from .train import TrainedModel
from ..types import Candidate, MapInput, QResult, TileResult, stack_shape

__all__ = ["sample", "judge", "crop_plan", "SamplingProgress"]


@dataclass
class SamplingProgress:
    index: int  # candidates evaluated so far
    planned: int  # candidates in the plan (the search may stop earlier)
    candidate: Candidate


#: Source-sized tiles: the crop search starts at half the stack (its 2c tile is the stack's size) and
#: stops where the tile would be magnified by more than 1/0.8 = 1.25 when brought to that size.
SOURCE_TILE_MIN_FRACTION = 0.8


def crop_plan(height: int, width: int, config, seed: int, tile_size: str = "paper"
              ) -> Iterator[tuple[tuple[int, int], tuple[int, int]]]:
    """((c_h, c_w), (y, x)) candidates, the aspect kept, the larger side shrinking by ``crop_step``.

    ``tile_size="paper"``: the whole stack first, then ``crops_per_size`` random crops per smaller size
    until the smaller side is below c_min (paper section 4.2). ``"source"``: the tile is to have the
    stack's own size, so crops start at half the stack (the centre one, then ``crops_per_size`` random
    ones at that size) and stop at ``SOURCE_TILE_MIN_FRACTION`` of it.
    """
    assert tile_size in ("paper", "source"), f"tile_size must be 'paper' or 'source', got {tile_size!r}"
    rng = np.random.default_rng([seed, 7])
    long_side = max(height, width)
    size = long_side if tile_size == "paper" else long_side // 2
    stop = max(config.c_min, 16) if tile_size == "paper" else 16
    smallest = 0 if tile_size == "paper" else SOURCE_TILE_MIN_FRACTION * long_side / 2
    first = True
    count = 0
    while True:
        ch = int(height * size / long_side) // 4 * 4
        cw = int(width * size / long_side) // 4 * 4
        if min(ch, cw) < stop or size < smallest:
            return
        if first:
            offsets = [((height - ch) // 2, (width - cw) // 2)]
            if tile_size == "source":
                offsets += [(int(rng.integers(0, height - ch + 1)), int(rng.integers(0, width - cw + 1)))
                            for _ in range(config.crops_per_size)]
        else:
            offsets = [(int(rng.integers(0, height - ch + 1)), int(rng.integers(0, width - cw + 1)))
                       for _ in range(config.crops_per_size)]
        for off in offsets:
            if config.max_candidates is not None and count >= config.max_candidates:
                return
            count += 1
            yield (ch, cw), off
        first = False
        size -= config.crop_step


def _to_numpy(t: torch.Tensor, is_normal: bool) -> np.ndarray:  # (1, C, H, W) -> (H, W, C) float32
    t = t.float()[0]
    if is_normal and t.shape[0] >= 3:
        t = torch.cat([torch.nn.functional.normalize(t[:3], dim=0, eps=1e-6), t[3:]], 0)
    return np.ascontiguousarray(t.clamp(-1, 1).permute(1, 2, 0).cpu().numpy())


@torch.no_grad()
def sample(model: TrainedModel, maps: list[MapInput], *, seed: int = 0, tile_size: str = "paper",
           progress: Callable[[SamplingProgress], None] | None = None) -> TileResult:
    """Search crops from c_max down to c_min; return the first tileable stack, or the best one flagged failing.

    The returned maps are (2c_h, 2c_w, C) float32 in [-1, 1], exactly one period when ``config.tiling`` is
    "circular". Normal maps (``is_normal``) come back renormalised to unit length.
    """
    names = [m.name for m in maps]
    assert names == model.names, f"maps {names} differ from the trained stack {model.names}"
    assert [m.channels for m in maps] == model.channels, (
        f"channels {[m.channels for m in maps]} differ from the trained {model.channels}")
    cfg = model.config
    H, W = stack_shape(maps)
    dev, precision = model.device, model.precision
    x = stack_tensor(maps, dev)  # (1, Ctot, H, W)
    G, D = model.G.eval(), model.D.eval()

    t_start = time.perf_counter()
    timings = {"generate_s": 0.0, "quality_s": 0.0}
    plan = list(crop_plan(H, W, cfg, seed, tile_size))
    assert plan, f"stack {H}x{W} is smaller than c_min={cfg.c_min}"
    candidates: list[Candidate] = []
    best: tuple[float, int, list[torch.Tensor]] | None = None
    chosen = None
    for i, ((ch, cw), (y, x0)) in enumerate(plan):
        t0 = time.perf_counter()
        with autocast(dev, precision):
            outs = tile_generate(G, x[:, :, y: y + ch, x0: x0 + cw], cfg.tiling, cfg.chunk_pixels)
        outs = [o.float() for o in outs]  # [(1, C_i, 2c_h, 2c_w)]
        t1 = time.perf_counter()
        with autocast(dev, precision):
            d_map = D(torch.cat(outs, 1))  # (1, 1, h, w)
        q = quality(d_map.float()[0, 0].cpu().numpy(), cfg.gamma, cfg.band_fraction)
        t2 = time.perf_counter()
        timings["generate_s"] += t1 - t0
        timings["quality_s"] += t2 - t1
        cand = Candidate((ch, cw), (y, x0), q, t2 - t0)
        candidates.append(cand)
        if progress is not None:
            progress(SamplingProgress(i + 1, len(plan), cand))
        if best is None or q.margin > best[0]:
            best = (q.margin, i, outs)
        if q.passed:
            chosen = (i, outs)
            break
    if chosen is None:
        chosen = (best[1], best[2])
    i, outs = chosen
    cand = candidates[i]
    timings["search_s"] = time.perf_counter() - t_start
    maps_out = {m.name: _to_numpy(o, m.is_normal) for m, o in zip(maps, outs)}
    return TileResult(maps=maps_out, crop_size=cand.crop_size, q_passed=cand.q.passed, q=cand.q,
                      candidates=candidates, timings=timings, model_hash=model.hash, device=str(dev),
                      precision=precision, offset=cand.offset)


@torch.no_grad()
def judge(model: TrainedModel, tile: dict[str, np.ndarray]) -> QResult:
    """Q of a periodic tile that G did not make (one cut from the source, say), at the working resolution.

    The discriminator sees the tile rolled by half its size, so the tile's own wrap-around seams lie
    in the centre bands that Q reads, where the latent copies of a GAN tile meet.
    """
    x = stack_tensor([MapInput(n, np.ascontiguousarray(tile[n], dtype=np.float32)) for n in model.names],
                     model.device)
    x = torch.roll(x, (x.shape[2] // 2, x.shape[3] // 2), dims=(2, 3))
    D = model.D.eval()
    with autocast(model.device, model.precision):
        d_map = D(x)
    return quality(d_map.float()[0, 0].cpu().numpy(), model.config.gamma, model.config.band_fraction)
