"""A stack's tile end to end: working resolution, SeamlessGAN training and sampling, refinement.

>>> from seamless_usd.synthesis import MapInput, get_preset
>>> import numpy as np
>>> maps = [MapInput("albedo", np.random.default_rng(0).uniform(-1, 1, (64, 64, 3)).astype(np.float32))]
>>> made = make_tile(maps, get_preset("tiny"))          # doctest: +SKIP
>>> made.maps["albedo"].shape                            # doctest: +SKIP
(64, 64, 3)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch
import torch.nn.functional as F

from seamless_usd.metrics import scale_ratio

from .config import SynthesisConfig
from .data import effective_k
from .refine import RefineConfig, refine
from .sample import sample
from .scale import structure_size, working_factor
from .seeds import SeedRun, choose_seed, fidelity_score, seed_list, train_seeds
from .types import MapInput, TileResult, stack_shape

__all__ = ["MadeTile", "make_tile", "downsample_maps", "TILE_SIZES", "LAYOUT_SCALE_RANGE"]

TILE_SIZES = ("source", "paper")

#: A GAN tile seeds the refinement only when every map's feature scale is within this range of the
#: working source's: a generator that has not learnt the texture yet (noise: about 6 with the tiny
#: test preset) would only be copied faithfully into nonsense, and the refinement starts from a
#: random field instead. The default preset's brick tile scores 1.0-1.3.
LAYOUT_SCALE_RANGE = (0.5, 2.0)


@dataclass
class MadeTile:
    """The written tile of a stack and how it was made."""

    maps: dict[str, np.ndarray]  # name -> (h, w, C) float32, periodic; source texels when refined
    tile_size: tuple[int, int]  # (h, w) of ``maps``
    grid_size: tuple[int, int]  # (h, w) of the pixel grid the tile's texels belong to (the UV unit square)
    uv_scale: tuple[float, float]  # (u, v): multiply UVs by this to keep the texel density
    structure_px: float  # structure size estimated on the source (px at the source's resolution)
    working_factor: float  # GAN working resolution / source resolution
    working_size: tuple[int, int]  # (h, w) the GAN trained at
    gan: TileResult  # the SeamlessGAN candidate chosen by Q (crop, Q, candidates) at the working resolution
    refined: bool
    layout_scale: dict[str, float] = field(default_factory=dict)  # per map, the GAN tile's scale ratio
    layout_used: bool = False  # whether the GAN tile seeded the refinement
    refine_levels: list[dict] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    seeds: list[dict] = field(default_factory=list)  # with config.seeds > 1: each seed's figures and which won


def downsample_maps(maps: list[MapInput], size: tuple[int, int]) -> list[MapInput]:
    """Maps resized to ``size = (h, w)`` (bilinear, antialiased when shrinking; normals renormalised)."""
    out = []
    for m in maps:
        if m.pixels.shape[:2] == tuple(size):
            out.append(m)
            continue
        t = torch.from_numpy(np.ascontiguousarray(m.pixels.transpose(2, 0, 1)))[None]
        r = F.interpolate(t, size=size, mode="bilinear", antialias=True, align_corners=False)[0]
        if m.is_normal and r.shape[0] >= 3:
            r = torch.cat([F.normalize(r[:3], dim=0, eps=1e-6), r[3:]], 0)
        out.append(MapInput(m.name, np.ascontiguousarray(r.clamp(-1, 1).permute(1, 2, 0).numpy()), m.is_normal))
    return out


def make_tile(maps: list[MapInput], config: SynthesisConfig, *, refine_config: RefineConfig | None = RefineConfig(),
              tile_size: str = "source", seed: int = 0, device: str | torch.device | None = None,
              checkpoint_dir: str | Path | None = None,
              progress: Callable[[str, Any], None] | None = None) -> MadeTile:
    """Make a tileable stack from ``maps`` (full resolution, network domain).

    1. Estimate the structure size and the working resolution (:mod:`.scale`); train SeamlessGAN there,
       ``config.seeds`` seeds side by side (:mod:`.seeds`).
    2. Sample: the crop search with the discriminator's Q (``tile_size="source"``: crops of half the
       working stack, so the tile has the stack's size; ``"paper"``: from the whole stack down). With
       several seeds, the tile whose fidelity and seam figures are best is kept.
    3. With ``refine_config``, refine the GAN tile (when its feature scale is plausible, see
       :data:`LAYOUT_SCALE_RANGE`; else a random start) into a tile of source texels at full resolution,
       ``tile_size`` deciding its pixel size (the source's, or the paper's 2c brought to full
       resolution). Without it, the GAN tile at the working resolution is the result.
    """
    assert tile_size in TILE_SIZES, f"tile_size must be one of {TILE_SIZES}, got {tile_size!r}"
    emit = progress or (lambda kind, detail: None)
    timings: dict[str, float] = {}
    H, W = stack_shape(maps)
    t0 = time.perf_counter()
    structure = structure_size([m.pixels for m in maps])
    f = working_factor(H, W, effective_k(config.k, H, W), structure)
    work_hw = (max(32, round(H * f) // 4 * 4), max(32, round(W * f) // 4 * 4))
    work_hw = (min(work_hw[0], H), min(work_hw[1], W))
    f_y, f_x = work_hw[0] / H, work_hw[1] / W
    working = downsample_maps(maps, work_hw)
    timings["scale"] = time.perf_counter() - t0

    t1 = time.perf_counter()
    models = train_seeds(working, config, seed, device=device, checkpoint_dir=checkpoint_dir,
                         progress=lambda p: emit("train", p))
    timings["train"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    runs = []
    for s, model in zip(seed_list(seed, config.seeds), models):
        run = SeedRun(s, sample(model, working, seed=s, tile_size=tile_size, progress=lambda p: emit("sample", p)))
        if len(models) > 1:
            run.score, run.scale, run.patch = fidelity_score(run.tile.maps, working)
        runs.append(run)
    chosen = choose_seed(runs)
    gan = chosen.tile
    seeds = [r.summary() for r in runs] if len(runs) > 1 else []
    timings["sample"] = time.perf_counter() - t2
    gan_hw = next(iter(gan.maps.values())).shape[:2]

    if refine_config is None:
        uv = (work_hw[1] / gan_hw[1], work_hw[0] / gan_hw[0])
        return MadeTile(dict(gan.maps), tuple(gan_hw), work_hw, uv, structure, f, work_hw, gan, False,
                        timings=timings, seeds=seeds)
    if tile_size == "source":
        out_hw = (H, W)
    else:  # the paper's 2c x 2c, at the source's resolution
        out_hw = (round(gan_hw[0] / f_y), round(gan_hw[1] / f_x))
    t3 = time.perf_counter()
    layout_scale = chosen.scale or {  # the seed choice measured it already
        w.name: round(scale_ratio(gan.maps[w.name], w.pixels, w.is_normal), 3) for w in working}
    low, high = LAYOUT_SCALE_RANGE
    use_layout = all(low <= v <= high for v in layout_scale.values())
    layout = [gan.maps[m.name] for m in maps] if use_layout else None
    result = refine([m.pixels for m in maps], layout, out_hw, refine_config,
                    seed=seed, device=device, progress=lambda info: emit("refine", info))
    timings["refine"] = time.perf_counter() - t3
    tiles = {m.name: np.ascontiguousarray(t, dtype=np.float32) for m, t in zip(maps, result.maps)}
    uv = (W / out_hw[1], H / out_hw[0])
    return MadeTile(tiles, out_hw, (H, W), uv, structure, f, work_hw, gan, True, layout_scale, use_layout,
                    result.levels, timings, seeds)
