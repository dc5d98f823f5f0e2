"""Several seeds of one stack trained side by side, and the GAN tile the fidelity figures choose.

One short GAN run depends on its seed: on the quality benchmark one seed's tile passes Q where
another's fails, or repeats a band along its centre line where the other does not
(``docs/decisions.md``, "Two seeds side by side"). A stack's training runs on one CPU thread (faster than two on
these small convolutions), so on a machine with two cores a second seed trains in the idle core's
time. ``config.seeds`` seeds (``seed, seed + 1, ...``) train in parallel, one thread each, and the
tile kept is the one whose figures against the working source (feature scale, patch distance,
border and centre seams) are furthest inside the targets. Each run is the same as a one-seed run of
its seed, weight for weight.

The discriminator's Q cannot rank the seeds: each run has its own discriminator, and their outputs are
not on one scale. Q still counts: a tile that passes Q is preferred to one that does not.
"""
from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import torch

from seamless_usd.metrics import TARGETS, centre_seam_ratios, patch_distance, scale_ratio, seam_ratios

from ..config import SynthesisConfig, side_by_side_seeds
from ..precision import pick_device
from .train import TrainedModel, train
from ..types import MapInput, TileResult, TrainingProgress

__all__ = ["SeedRun", "seed_list", "seed_checkpoint_dir", "seed_workers", "train_seeds", "fidelity_score",
           "choose_seed"]


@dataclass
class SeedRun:
    """One seed's GAN tile and its figures against the working source."""

    seed: int
    tile: TileResult
    scale: dict[str, float] = field(default_factory=dict)  # per map, scale ratio
    patch: dict[str, float] = field(default_factory=dict)  # per map, patch distance
    score: float = math.inf  # worst map's figure in units of its target (<= 1: inside every target)
    chosen: bool = False

    def summary(self) -> dict:
        return {"seed": self.seed, "q_passed": bool(self.tile.q_passed), "score": round(self.score, 3),
                "scale": self.scale, "patch": self.patch, "chosen": self.chosen}


def seed_list(seed: int, n: int) -> list[int]:
    """The seeds of an ``n``-seed run started from ``seed``.

    >>> seed_list(5, 3)
    [5, 6, 7]
    """
    return [seed + i for i in range(n)]


def seed_checkpoint_dir(checkpoint_dir: str | Path | None, index: int) -> Path | None:
    """The first seed checkpoints where a one-seed run does (so it resumes one), the others in ``seed-<i>``."""
    if checkpoint_dir is None:
        return None
    return Path(checkpoint_dir) if index == 0 else Path(checkpoint_dir) / f"seed-{index}"


def seed_workers(n: int, device_type: str, threads: int) -> int:
    """How many seeds train at once: one per CPU thread (up to ``n``); one at a time on a GPU.

    >>> seed_workers(2, "cpu", 2), seed_workers(2, "cpu", 1), seed_workers(2, "cuda", 16)
    (2, 1, 1)
    """
    if device_type != "cpu":
        return 1
    return side_by_side_seeds(n, threads)


def train_seeds(maps: list[MapInput], config: SynthesisConfig, seed: int, *, device=None,
                checkpoint_dir: str | Path | None = None,
                progress: Callable[[TrainingProgress], None] | None = None) -> list[TrainedModel]:
    """``config.seeds`` models of ``maps``, in seed order.

    In parallel on the CPU (each worker with an equal share of torch's threads), progress comes from the
    first seed; one after another, it counts the iterations of all seeds.
    """
    seeds = seed_list(seed, config.seeds)
    dev = pick_device(device)
    threads = torch.get_num_threads()
    workers = seed_workers(len(seeds), dev.type, threads)
    dirs = [seed_checkpoint_dir(checkpoint_dir, i) for i in range(len(seeds))]
    if workers == 1:
        models = []
        for i, (s, d) in enumerate(zip(seeds, dirs)):
            models.append(train(maps, config, seed=s, device=dev, checkpoint_dir=d,
                                progress=_offset_progress(progress, i, len(seeds))))
        return models
    with ThreadPoolExecutor(workers, thread_name_prefix="seamless-seed", initializer=torch.set_num_threads,
                            initargs=(max(1, threads // workers),)) as pool:
        futures = [pool.submit(train, maps, config, seed=s, device=dev, checkpoint_dir=d,
                               progress=progress if i == 0 else None)
                   for i, (s, d) in enumerate(zip(seeds, dirs))]
        return [f.result() for f in futures]


def _offset_progress(progress, index: int, count: int):
    """Progress of seed ``index`` of ``count`` run one after another, as iterations of the whole run."""
    if progress is None or count == 1:
        return progress

    def report(p: TrainingProgress) -> None:
        done = index * p.total + p.iteration
        total = count * p.total
        eta = (total - done) / max(p.it_per_s, 1e-9)
        progress(TrainingProgress(done, total, p.it_per_s, eta, p.losses, p.elapsed_s))

    return report


def fidelity_score(tile: dict[str, np.ndarray], working: list[MapInput]) -> tuple[float, dict, dict]:
    """The worst figure of any map in units of its target, with the per-map scale ratios and patch distances.

    Every figure of ``metrics.TARGETS`` counts: the scale ratio as |ln r| / |ln bound| (the bound on
    its side of 1), the others (patch distance, border and centre seam ratios) as value / bound. So 1 is
    the edge of the targets and a tile with every figure of every map inside scores <= 1.
    """
    scale, patch, worst = {}, {}, 0.0
    for m in working:
        px = tile[m.name]
        figures = {"scale_ratio": scale_ratio(px, m.pixels, m.is_normal),
                   "patch_distance": patch_distance(px, m.pixels, m.is_normal),
                   **seam_ratios(px, m.is_normal), **centre_seam_ratios(px, m.is_normal)}
        scale[m.name], patch[m.name] = round(figures["scale_ratio"], 3), round(figures["patch_distance"], 3)
        for key, (low, high) in TARGETS.items():
            v = figures[key]
            if key == "scale_ratio":
                bound = high if v >= 1 else low
                worst = max(worst, abs(math.log(max(v, 1e-6))) / abs(math.log(bound)))
            else:
                worst = max(worst, v / high)
    return worst, scale, patch


def choose_seed(runs: list[SeedRun]) -> SeedRun:
    """The run to keep: one whose tile passes Q before one that does not, then the lowest score, then seed order."""
    best = min(range(len(runs)), key=lambda i: (not runs[i].tile.q_passed, runs[i].score, i))
    for i, run in enumerate(runs):
        run.chosen = i == best
    return runs[best]
