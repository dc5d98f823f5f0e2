"""One adversarial-expansion training step: losses for D and G, and the update.

D is updated on every ``config.d_every``-th step only, and the style loss computed on every
``config.style_every``-th (beyond the paper; 1, every step, is the paper's).

Forward passes run under ``precision.autocast``; every loss is reduced in fp32. A step may hold several
crops; its loss is the mean of the per-crop losses. On the GPU the crops go through the networks as one
batch; on the CPU each crop is a micro-batch of its own, computed on a ``CropWorkers`` thread, and the
per-crop gradients are summed in crop order, so the weights do not depend on how many threads ran.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import torch
import torch.nn.functional as F
from torch import nn

from ..config import SynthesisConfig
from .adam import Adam
from .engine import CropWorkers
from .features import style_loss
from .networks import Discriminator, Generator
from ..precision import autocast

__all__ = ["Batch", "generate", "d_loss", "g_loss", "training_step", "step_parts", "StepFunctions"]


@dataclass
class Batch:
    source: torch.Tensor  # (N, Ctot, k, k) or (N, Ctot, k/2, k/2) for a seam-training step
    target: torch.Tensor  # (N, Ctot, 2k, 2k)
    seam: bool = False  # source is a half-size crop whose latent is tiled 2x2 before decoding

    def crops(self) -> list["Batch"]:
        """One single-crop batch per crop."""
        return [Batch(self.source[i: i + 1], self.target[i: i + 1], self.seam) for i in range(self.source.shape[0])]


def generate(G: Generator, batch: Batch) -> torch.Tensor:  # -> (N, Ctot, 2k, 2k)
    if batch.seam:
        x0 = G.encode(batch.source)  # (N, 2ngf, k/4, k/4)
        outs = G.decode(x0.repeat(1, 1, 2, 2))  # latent copies meet in the middle: G must heal the seam
    else:
        outs = G(batch.source)
    return torch.cat(outs, 1)


def _bce(logits: torch.Tensor, real: bool) -> torch.Tensor:
    logits = logits.float()
    return F.binary_cross_entropy_with_logits(logits, torch.full_like(logits, 1.0 if real else 0.0))


def d_loss(D: Discriminator, fake: torch.Tensor, target: torch.Tensor, device, precision: str) -> torch.Tensor:
    with autocast(device, precision):
        real_logits = D.logits(target)
        fake_logits = D.logits(fake.detach())
    return 0.5 * (_bce(real_logits, True) + _bce(fake_logits, False))


def g_loss(D: Discriminator, extractor: nn.Module, fake: torch.Tensor, batch: Batch, channels: list[int],
           config: SynthesisConfig, device, precision: str, use_style: bool = True
           ) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
    """Adversarial + L1 + style, and the parts as detached 0-d tensors (read as floats by the caller, outside a
    compiled graph: a ``float()`` here would break the graph). With ``config.style_every = n`` the style term
    is computed on every n-th step only (``use_style``), weighted n times, so its expected gradient is
    unchanged."""
    with autocast(device, precision):
        adv = _bce(D.logits(fake), True)
    fakes = torch.split(fake.float(), channels, 1)
    reals = torch.split(batch.target, channels, 1)
    l1 = fake.new_zeros((), dtype=torch.float32)
    if not batch.seam:  # a tiled latent has no pixel-aligned target; adversarial + style only
        l1 = sum(F.l1_loss(f, r) for f, r in zip(fakes, reals))
    sty = fake.new_zeros((), dtype=torch.float32)
    if config.lambda_style and use_style:
        with autocast(device, precision):
            sty = sum(style_loss(extractor, f, r) for f, r in zip(fakes, reals))
    total = config.lambda_adv * adv + config.lambda_l1 * l1 + config.lambda_style * config.style_every * sty
    parts = {"g_adv": adv.detach(), "l1": l1.detach()}
    if use_style:  # a step without it keeps the latest figure in the run's losses
        parts["style"] = sty.detach()
    return total, parts


def step_parts(config: SynthesisConfig, step: int) -> tuple[bool, bool]:
    """(update D, compute the style loss) at ``step``: every ``d_every``-th / ``style_every``-th step.

    >>> step_parts(SynthesisConfig(d_every=2, style_every=3), 3)
    (False, True)
    """
    return step % config.d_every == 0, step % config.style_every == 0


@dataclass
class StepFunctions:
    """The differentiable pieces of a step; ``train`` may swap in compiled versions (``engine.maybe_compile``)."""

    generate: Callable = generate
    d_loss: Callable = d_loss
    g_loss: Callable = g_loss


def training_step(G: Generator, D: Discriminator, opt_g: Adam, opt_d: Adam,
                  extractor: nn.Module, batch: Batch, channels: list[int], config: SynthesisConfig,
                  device: torch.device, precision: str, scaler=None, workers: CropWorkers | None = None,
                  stacked: bool = False, fns: StepFunctions | None = None, update_d: bool = True,
                  use_style: bool = True) -> dict[str, float]:
    """Update D once (unless ``update_d`` is false), then G once (pix2pix order), on every crop of ``batch``.

    Returns the mean losses as floats; ``"d"`` only when D was updated.
    ``stacked`` runs the crops as one batch (the GPU path, and the only one with an fp16 ``scaler``);
    otherwise each crop is a micro-batch, run on ``workers`` threads when given.
    """
    fns = fns or StepFunctions()
    if stacked or scaler is not None:
        return _stacked_step(G, D, opt_g, opt_d, extractor, batch, channels, config, device, precision, scaler, fns,
                             update_d, use_style)
    crops = batch.crops()
    n = len(crops)
    run = workers.map if workers is not None else (lambda fn, *xs: list(map(fn, *xs)))  # serial without a pool
    d_params = list(D.parameters())
    g_params = list(G.parameters())
    mean = lambda xs: sum(xs) / n  # noqa: E731
    out: dict[str, float] = {}

    def d_part(crop: Batch):
        with autocast(device, precision):
            fake = fns.generate(G, crop)  # (1, Ctot, 2k, 2k)
        loss = fns.d_loss(D, fake, crop.target, device, precision)
        return fake, float(loss.detach()), torch.autograd.grad(loss / n, d_params, allow_unused=True)

    fakes: list[torch.Tensor | None] = [None] * n
    if update_d:
        D.requires_grad_(True)
        d_out = run(d_part, crops)
        _set_grads(d_params, [g for _, _, g in d_out])
        opt_d.step()
        fakes = [f for f, _, _ in d_out]
        out["d"] = mean([d for _, d, _ in d_out])

    def g_part(crop: Batch, fake: torch.Tensor | None):
        if fake is None:  # no D step: the fake is made here, on this crop's worker
            with autocast(device, precision):
                fake = fns.generate(G, crop)
        loss, parts = fns.g_loss(D, extractor, fake, crop, channels, config, device, precision, use_style)
        return float(loss.detach()), _floats(parts), torch.autograd.grad(loss / n, g_params, allow_unused=True)

    D.requires_grad_(False)  # G's backward goes through D without computing D weight gradients
    g_out = run(g_part, crops, fakes)
    D.requires_grad_(True)
    _set_grads(g_params, [g for _, _, g in g_out])
    opt_g.step()
    parts = {k: mean([p[k] for _, p, _ in g_out]) for k in g_out[0][1]}
    return {**out, "g": mean([g for g, _, _ in g_out]), **parts}


def _set_grads(params: list[torch.Tensor], per_crop: list[tuple]) -> None:
    """``p.grad`` = the sum of the per-crop gradients, added in crop order (deterministic)."""
    for i, p in enumerate(params):
        total = None
        for grads in per_crop:
            g = grads[i]
            if g is not None:
                total = g if total is None else total + g
        p.grad = total


def _stacked_step(G, D, opt_g, opt_d, extractor, batch, channels, config, device, precision, scaler,
                  fns: StepFunctions, update_d: bool = True, use_style: bool = True) -> dict[str, float]:
    with autocast(device, precision):
        fake = fns.generate(G, batch)  # (N, Ctot, 2k, 2k)

    out: dict[str, float] = {}
    if update_d:
        D.requires_grad_(True)
        loss_d = fns.d_loss(D, fake, batch.target, device, precision)
        opt_d.zero_grad(set_to_none=True)
        _backward_step(loss_d, opt_d, scaler)
        out["d"] = float(loss_d.detach())

    D.requires_grad_(False)  # G's backward goes through D without accumulating D weight gradients
    loss_g, parts = fns.g_loss(D, extractor, fake, batch, channels, config, device, precision, use_style)
    opt_g.zero_grad(set_to_none=True)
    _backward_step(loss_g, opt_g, scaler)
    D.requires_grad_(True)
    if scaler is not None:
        scaler.update()
    return {**out, "g": float(loss_g.detach()), **_floats(parts)}


def _floats(parts: dict[str, torch.Tensor]) -> dict[str, float]:
    return {k: float(v) for k, v in parts.items()}


def _backward_step(loss: torch.Tensor, opt: Adam, scaler) -> None:
    if scaler is None:
        loss.backward()
        opt.step()
    else:
        scaler.scale(loss).backward()
        scaler.step(opt)
