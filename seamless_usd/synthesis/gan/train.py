"""Adversarial-expansion training loop with checkpoints, resume and progress reports."""
from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np
import torch

from .adam import Adam
from .checkpoint import CHECKPOINT_NAME, load_checkpoint, save_checkpoint, versions
from ..config import SynthesisConfig
from .data import effective_k, stack_tensor, training_crops
from .engine import CropWorkers, EnginePlan, engine_for, maybe_compile
from .features import build_feature_extractor
from .networks import Discriminator, Generator, init_weights
from ..precision import pick_device, resolve_precision
from .schedule import learning_rate
from .step import Batch, StepFunctions, d_loss, g_loss, generate, step_parts, training_step
from ..types import MapInput, TrainingProgress, stack_shape

__all__ = ["TrainedModel", "train", "training_hash", "build_networks"]


@dataclass
class TrainedModel:
    """A trained generator/discriminator pair with what is needed to sample from it."""

    G: Generator
    D: Discriminator
    config: SynthesisConfig
    hash: str  # hash of the stack's pixels, map layout, training config, seed and code version
    names: list[str]
    channels: list[int]
    is_normal: list[bool]
    k: int  # source crop size actually trained (config.k shrunk to fit small stacks)
    step: int  # iterations trained
    device: torch.device = field(default_factory=lambda: torch.device("cpu"))
    precision: str = "fp32"
    versions: dict = field(default_factory=versions)
    engine: EnginePlan | None = None  # how it was trained (None when loaded from a file)

    def _meta(self) -> dict:
        return {"kind": "model", "config": self.config.to_json(), "hash": self.hash, "names": self.names,
                "channels": self.channels, "is_normal": self.is_normal, "k": self.k, "step": self.step,
                "versions": self.versions}

    def save(self, path: str | Path) -> None:
        """Weights and metadata as one safetensors file."""
        tensors = {f"G.{k}": v for k, v in self.G.state_dict().items()}
        tensors.update({f"D.{k}": v for k, v in self.D.state_dict().items()})
        save_checkpoint(Path(path), tensors, self._meta())

    @classmethod
    def load(cls, path: str | Path, device: str | torch.device | None = None, precision: str | None = None
             ) -> "TrainedModel":
        """Load a model or training checkpoint written by this package (safetensors only, never pickles)."""
        tensors, meta = load_checkpoint(Path(path))
        config = SynthesisConfig.from_json(meta["config"])
        dev = pick_device(device)
        G, D = build_networks(config, meta["channels"], seed=0)
        G.load_state_dict({k[2:]: v for k, v in tensors.items() if k.startswith("G.")})
        D.load_state_dict({k[2:]: v for k, v in tensors.items() if k.startswith("D.")})
        return cls(G.to(dev).eval(), D.to(dev).eval(), config, meta["hash"], list(meta["names"]),
                   list(meta["channels"]), list(meta["is_normal"]), int(meta["k"]), int(meta["step"]), dev,
                   resolve_precision(precision or config.precision, dev), meta.get("versions", {}))


def build_networks(config: SynthesisConfig, channels: list[int], seed: int) -> tuple[Generator, Discriminator]:
    """G and D with N(0, init_std) weights drawn from ``seed`` (CPU generator, so every device agrees)."""
    total = sum(channels)
    G = Generator(total, channels, config.ngf, config.n_res_blocks, config.upsample)
    D = Discriminator(total, config.ndf)
    g = torch.Generator().manual_seed(seed)
    init_weights(G, config.init_std, g)
    init_weights(D, config.init_std, g)
    return G, D


def training_hash(maps: list[MapInput], config: SynthesisConfig, seed: int) -> str:
    h = hashlib.sha256()
    for m in maps:
        h.update(json.dumps([m.name, list(m.pixels.shape), bool(m.is_normal)]).encode())
        h.update(np.ascontiguousarray(m.pixels, dtype=np.float32).tobytes())
    h.update(json.dumps(config.training_fields(), sort_keys=True).encode())
    h.update(json.dumps({"seed": seed, "format": versions()["format"]}).encode())
    return h.hexdigest()[:16]


def train(maps: list[MapInput], config: SynthesisConfig, *, seed: int = 0, device: str | torch.device | None = None,
          checkpoint_dir: str | Path | None = None,
          progress: Callable[[TrainingProgress], None] | None = None) -> TrainedModel:
    """Train SeamlessGAN on one stack; resumes from ``checkpoint_dir`` when a checkpoint of this run is there.

    Parameters
    ----------
    maps : the aligned maps of the stack, (H, W, C) float32 in [-1, 1].
    config : a preset (``get_preset``) or a custom ``SynthesisConfig``.
    seed : fixes weight init and every training crop; same seed and machine, same weights.
    device : None picks CUDA when present, else the CPU.
    checkpoint_dir : where ``checkpoint.safetensors`` is written every ``config.checkpoint_every`` iterations
        and at the end.
    progress : called every ``config.progress_every`` iterations with a ``TrainingProgress``.
    """
    dev = pick_device(device)
    plan = engine_for(config, dev)
    precision = plan.precision
    H, W = stack_shape(maps)
    k = effective_k(config.k, H, W)
    channels = [m.channels for m in maps]
    key = training_hash(maps, config, seed)
    total = config.iterations

    G, D = build_networks(config, channels, seed)
    G, D = G.to(dev).train(), D.to(dev).train()
    extractor = build_feature_extractor(config).to(dev).eval()
    opt_g = Adam(G.parameters(), lr=config.lr, betas=config.betas)
    opt_d = Adam(D.parameters(), lr=config.lr, betas=config.betas)
    scaler = torch.amp.GradScaler(dev.type) if plan.grad_scaler else None
    fns = StepFunctions(maybe_compile(generate, plan), maybe_compile(d_loss, plan), maybe_compile(g_loss, plan))

    start = 0
    ckpt = Path(checkpoint_dir) / CHECKPOINT_NAME if checkpoint_dir is not None else None
    if ckpt is not None and ckpt.exists():
        tensors, meta = load_checkpoint(ckpt)
        if meta.get("hash") != key:
            raise ValueError(f"{ckpt}: checkpoint belongs to another stack/config/seed "
                             f"(hash {meta.get('hash')} != {key}); use another checkpoint_dir")
        G.load_state_dict({k_[2:]: v for k_, v in tensors.items() if k_.startswith("G.")})
        D.load_state_dict({k_[2:]: v for k_, v in tensors.items() if k_.startswith("D.")})
        opt_g.load_state_tensors("optG", tensors)
        opt_d.load_state_tensors("optD", tensors)
        start = int(meta["step"])

    model = TrainedModel(G, D, config, key, [m.name for m in maps], channels, [bool(m.is_normal) for m in maps],
                         k, start, dev, precision, engine=plan)

    def save(step: int) -> None:
        if ckpt is None:
            return
        tensors = {f"G.{k_}": v for k_, v in G.state_dict().items()}
        tensors.update({f"D.{k_}": v for k_, v in D.state_dict().items()})
        tensors.update(opt_g.state_tensors("optG"))
        tensors.update(opt_d.state_tensors("optD"))
        model.step = step
        save_checkpoint(ckpt, tensors, model._meta())

    x = stack_tensor(maps, dev)  # (1, Ctot, H, W)
    t0 = time.perf_counter()
    losses: dict[str, float] = {}  # the latest of each loss (D's from its latest update)
    with CropWorkers(plan) as workers:
        for step in range(start, total):
            lr = learning_rate(step, total, config.lr, config.lr_milestones, config.lr_decay)
            for opt in (opt_g, opt_d):
                for group in opt.param_groups:
                    group["lr"] = lr
            batch = _step_batch(x, seed, step, k, config)
            update_d, use_style = step_parts(config, step)
            losses = {**losses, **training_step(G, D, opt_g, opt_d, extractor, batch, channels, config, dev,
                                                precision, scaler, workers, plan.stacked, fns, update_d, use_style)}
            done = step + 1
            if done % config.checkpoint_every == 0 or done == total:
                save(done)
            if progress is not None and (done % config.progress_every == 0 or done == total):
                elapsed = time.perf_counter() - t0
                rate = (done - start) / max(elapsed, 1e-9)
                progress(TrainingProgress(done, total, rate, (total - done) / max(rate, 1e-9), losses, elapsed))
    model.step = total
    G.eval(), D.eval()
    return model


def _step_batch(x: torch.Tensor, seed: int, step: int, k: int, config: SynthesisConfig) -> Batch:
    """The ``config.batch`` crops of one step: 2k targets from the stack ``x`` (1, Ctot, H, W), k sources in them.

    A seam step (``seam_training_prob``) feeds every crop a k/2 source whose latent is tiled 2x2.
    """
    H, W = x.shape[2:]
    seam = config.seam_training_prob > 0 and (
        np.random.default_rng([seed, step, 1]).random() < config.seam_training_prob)
    size = k // 2 if seam else k
    sources, targets = [], []
    for index in range(config.batch):
        ty, tx, sy, sx = training_crops(seed, step, H, W, k, index)
        target = x[:, :, ty: ty + 2 * k, tx: tx + 2 * k]  # (1, Ctot, 2k, 2k)
        targets.append(target)
        sources.append(target[:, :, sy: sy + size, sx: sx + size])  # (1, Ctot, k, k), or k/2 for a seam step
    if config.batch == 1:
        return Batch(sources[0], targets[0], seam)
    return Batch(torch.cat(sources), torch.cat(targets), seam)
