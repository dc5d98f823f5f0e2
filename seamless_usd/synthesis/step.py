"""One adversarial-expansion training step: losses for D and G, and the update.

Forward passes run under ``precision.autocast``; every loss is reduced in fp32.
"""
from __future__ import annotations

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import nn

from .config import SynthesisConfig
from .features import style_loss
from .networks import Discriminator, Generator
from .precision import autocast

__all__ = ["Batch", "generate", "d_loss", "g_loss", "training_step"]


@dataclass
class Batch:
    source: torch.Tensor  # (1, Ctot, k, k) or (1, Ctot, k/2, k/2) for a seam-training step
    target: torch.Tensor  # (1, Ctot, 2k, 2k)
    seam: bool = False  # source is a half-size crop whose latent is tiled 2x2 before decoding


def generate(G: Generator, batch: Batch) -> torch.Tensor:  # -> (1, Ctot, 2k, 2k)
    if batch.seam:
        x0 = G.encode(batch.source)  # (1, 2ngf, k/4, k/4)
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
           config: SynthesisConfig, device, precision: str) -> tuple[torch.Tensor, dict[str, float]]:
    with autocast(device, precision):
        adv = _bce(D.logits(fake), True)
    fakes = torch.split(fake.float(), channels, 1)
    reals = torch.split(batch.target, channels, 1)
    l1 = fake.new_zeros((), dtype=torch.float32)
    if not batch.seam:  # a tiled latent has no pixel-aligned target; adversarial + style only
        l1 = sum(F.l1_loss(f, r) for f, r in zip(fakes, reals))
    sty = fake.new_zeros((), dtype=torch.float32)
    if config.lambda_style:
        with autocast(device, precision):
            sty = sum(style_loss(extractor, f, r) for f, r in zip(fakes, reals))
    total = config.lambda_adv * adv + config.lambda_l1 * l1 + config.lambda_style * sty
    return total, {"g_adv": float(adv.detach()), "l1": float(l1.detach()), "style": float(sty.detach())}


def training_step(G: Generator, D: Discriminator, opt_g: torch.optim.Optimizer, opt_d: torch.optim.Optimizer,
                  extractor: nn.Module, batch: Batch, channels: list[int], config: SynthesisConfig,
                  device: torch.device, precision: str, scaler=None) -> dict[str, float]:
    """Update D once, then G once (pix2pix order). Returns the losses as floats."""
    with autocast(device, precision):
        fake = generate(G, batch)  # (1, Ctot, 2k, 2k)

    D.requires_grad_(True)
    loss_d = d_loss(D, fake, batch.target, device, precision)
    opt_d.zero_grad(set_to_none=True)
    _backward_step(loss_d, opt_d, scaler)

    D.requires_grad_(False)  # G's backward goes through D without accumulating D weight gradients
    loss_g, parts = g_loss(D, extractor, fake, batch, channels, config, device, precision)
    opt_g.zero_grad(set_to_none=True)
    _backward_step(loss_g, opt_g, scaler)
    D.requires_grad_(True)
    if scaler is not None:
        scaler.update()
    return {"d": float(loss_d.detach()), "g": float(loss_g.detach()), **parts}


def _backward_step(loss: torch.Tensor, opt: torch.optim.Optimizer, scaler) -> None:
    if scaler is None:
        loss.backward()
        opt.step()
    else:
        scaler.scale(loss).backward()
        scaler.step(opt)
