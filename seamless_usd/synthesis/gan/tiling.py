"""Latent-space tiling (paper section 4.1): encode a crop, tile x0, decode, keep one period.

Two equivalent views of the same idea:

* ``"repeat"`` -- the paper, literally: repeat x0 2x2, decode to 4c, keep the central 2c.
* ``"circular"`` -- the central 2c of an *infinitely* repeated x0: x0 is rolled by half its size (so the
  copies meet in the middle, as in the paper's centre crop) and decoded with circular padding. The result
  is exactly one period, costs a quarter of ``"repeat"``, and the decoders can run in row chunks whose
  InstanceNorm statistics are gathered first, so a 2048 px input fits in a few GiB.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F

from .networks import Decoder, Generator, Padded

__all__ = ["tile_generate", "decode_chunked"]

_HALO = 3  # latent rows of context per chunk side; the decoder's vertical receptive radius is < 2 latent rows


def tile_generate(G: Generator, source: torch.Tensor, tiling: str = "circular",
                  chunk_pixels: int | None = None) -> list[torch.Tensor]:
    """(1, Ctot, c_h, c_w) input crop -> [(1, C_i, 2c_h, 2c_w)] one period of the tiled output per map."""
    _, _, ch, cw = source.shape
    assert ch % 4 == 0 and cw % 4 == 0, f"crop sides must be multiples of 4, got {ch}x{cw}"
    x0 = G.encode(source)  # (1, 2ngf, c_h/2, c_w/2), training (reflect) padding as in the paper
    if tiling == "repeat":
        outs = G.decode(x0.repeat(1, 1, 2, 2))  # [(1, C, 4c_h, 4c_w)]
        return [o[:, :, ch: 3 * ch, cw: 3 * cw] for o in outs]
    assert tiling == "circular", f"tiling must be 'circular' or 'repeat', got {tiling!r}"
    h, w = x0.shape[2:]
    window = torch.roll(x0, shifts=(h // 2, w // 2), dims=(2, 3))  # the centre window of the 2x2 repeat
    G.set_padding(periodic=True)
    try:
        x = G.res(window)  # (1, 2ngf, h, w)
        return [decode_chunked(d, x, chunk_pixels) for d in G.decoders]
    finally:
        G.set_padding(periodic=False)


def _instance_norm(y: torch.Tensor, stats: tuple[torch.Tensor, torch.Tensor], eps: float) -> torch.Tensor:
    mean, var = stats  # (C,) float64 over the whole period
    shape = (1, -1, 1, 1)
    out = (y.float() - mean.to(torch.float32).view(shape)) * torch.rsqrt(var.to(torch.float32).view(shape) + eps)
    return out.to(y.dtype)


def decode_chunked(dec: Decoder, x: torch.Tensor, chunk_pixels: int | None) -> torch.Tensor:
    """Run ``dec`` (circular padding set) on periodic latent ``x`` (1, 2ngf, h, w) in row chunks.

    InstanceNorm needs statistics over the whole map: pass 1 gathers them for the first upsampling,
    pass 2 for the second, pass 3 writes the output. Matches the unchunked decoder to float tolerance.
    """
    _, _, h, w = x.shape
    if chunk_pixels is None or 16 * h * w <= chunk_pixels:
        return dec(x)  # (1, C, 4h, 4w)
    rows = max(1, chunk_pixels // (16 * w))
    convs = [m for m in dec.modules() if isinstance(m, Padded)]
    (conv1, norm1, _), (conv2, norm2, _) = list(dec.up1), list(dec.up2)
    for m in convs:
        m.pad_h = False  # vertical context comes from the halo rows instead
    try:
        def run(r0: int, r1: int, upto: int, stats: list) -> torch.Tensor:
            idx = torch.arange(r0 - _HALO, r1 + _HALO, device=x.device) % h
            y = conv1(x[:, :, idx])  # (1, ngf, 2n, 2w)
            if upto == 1:
                return y[:, :, 2 * _HALO: 2 * _HALO + 2 * (r1 - r0)]
            y = F.relu(_instance_norm(y, stats[0], norm1.eps))
            y = conv2(y)  # (1, ngf/2, 4n, 4w)
            if upto == 2:
                return y[:, :, 4 * _HALO: 4 * _HALO + 4 * (r1 - r0)]
            y = F.relu(_instance_norm(y, stats[1], norm2.eps))
            y = dec.out(y)  # no vertical padding: row j is input row j + 3
            return torch.tanh(y[:, :, 4 * _HALO - 3: 4 * _HALO - 3 + 4 * (r1 - r0)])

        spans = [(r, min(r + rows, h)) for r in range(0, h, rows)]
        stats: list = []
        for upto in (1, 2):
            s = s2 = n = 0
            for r0, r1 in spans:
                y = run(r0, r1, upto, stats).double()
                s = s + y.sum((0, 2, 3))
                s2 = s2 + (y * y).sum((0, 2, 3))
                n += y.shape[0] * y.shape[2] * y.shape[3]
            mean = s / n
            stats.append((mean, (s2 / n - mean * mean).clamp_min(0)))
        return torch.cat([run(r0, r1, 3, stats) for r0, r1 in spans], 2)  # (1, C, 4h, 4w)
    finally:
        for m in convs:
            m.pad_h = True
