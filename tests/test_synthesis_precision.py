"""Guard for the default fast path: one training step's gradients must agree with an fp32 eager reference.

The default CPU path is bf16 autocast (when the CPU has native bf16) in the default contiguous memory
format; torch 2.13 is known to give wrong InstanceNorm gradients under channels_last, so any change of
the default path must keep this test green.
"""
import numpy as np
import pytest
import torch

from seamless_usd.synthesis import get_preset
from seamless_usd.synthesis.gan.features import build_feature_extractor
from seamless_usd.synthesis.precision import resolve_precision
from seamless_usd.synthesis.gan.step import Batch, d_loss, g_loss, generate
from seamless_usd.synthesis.gan.train import build_networks


pytestmark = pytest.mark.usefixtures("one_thread")  # tiny networks: fastest and steadiest on one thread


CHANNELS = [3, 1, 3]
CONFIG = get_preset("tiny").replace(k=32, ngf=16, ndf=16, n_res_blocks=2)


def _step_gradients(precision: str) -> dict[str, torch.Tensor]:
    """Flattened gradients per parameter group after one D and one G backward on a fixed batch."""
    dev = torch.device("cpu")
    G, D = build_networks(CONFIG, CHANNELS, seed=0)
    extractor = build_feature_extractor(CONFIG)
    g = torch.Generator().manual_seed(0)
    target = torch.rand(1, sum(CHANNELS), 64, 64, generator=g) * 2 - 1  # (N, C, 2k, 2k)
    batch = Batch(target[:, :, 8:40, 16:48], target)
    from seamless_usd.synthesis.precision import autocast
    with autocast(dev, precision):
        fake = generate(G, batch)
    d_loss(D, fake, target, dev, precision).backward()
    D.requires_grad_(False)
    loss, _ = g_loss(D, extractor, fake, batch, CHANNELS, CONFIG, dev, precision)
    loss.backward()
    groups = {"encoder": G.encoder, "res": G.res, "D": D}
    groups.update({f"decoder{i}": d for i, d in enumerate(G.decoders)})
    return {name: torch.cat([p.grad.flatten() for p in mod.parameters() if p.grad is not None])
            for name, mod in groups.items()}


def test_default_precision_is_resolved_at_run_time():
    cpu = torch.device("cpu")
    assert resolve_precision("auto", cpu) == "fp32"
    assert resolve_precision("fp32", cpu) == "fp32"


def test_bf16_autocast_gradients_match_fp32_eager():
    ref = _step_gradients("fp32")
    fast = _step_gradients("bf16")
    for name in ref:
        assert torch.isfinite(fast[name]).all(), f"{name}: non-finite bf16 gradients"
        cos = torch.nn.functional.cosine_similarity(ref[name], fast[name], dim=0).item()
        assert cos > 0.95, f"{name}: bf16 gradient cosine similarity {cos:.3f} vs fp32 (expected > 0.95)"


def test_channels_last_is_not_the_default():
    G, _ = build_networks(CONFIG, CHANNELS, seed=0)
    out = G(torch.zeros(1, 7, 32, 32))
    assert all(o.is_contiguous() for o in out)
