"""Patch descriptors, nearest-patch search on a torus and voting (vectorised torch, CPU and CUDA).

Conventions: a *field* is an ``(h, w, 2)`` int64 tensor giving, for every pixel of the tile (a
torus), the source pixel ``(y, x)`` its patch is copied from. Source positions are patch centres
whose whole patch lies inside the source (``r <= y < H - r``, ``r = patch // 2``), since the
source does not wrap; tile patches do wrap around. Features are ``(C, H, W)`` float32 tensors.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F

__all__ = ["PatchSpace", "patch_cost", "patchmatch", "vote", "robust_vote", "gather", "occurrence_bias", "clamp_field"]


class PatchSpace:
    """PCA descriptors of ``patch`` x ``patch`` patches of one source level.

    Descriptor ``D(p)`` is the projection of the patch around ``p`` on the ``dims`` principal
    axes of the source's patches, so ``|D(p) - D(q)|^2`` approximates the patch SSD at a
    fraction of the cost. The same basis describes tile patches (circular padding).
    """

    def __init__(self, source: torch.Tensor, patch: int, dims: int, generator: torch.Generator,
                 samples: int = 16384):
        c, h, w = source.shape
        assert h >= patch and w >= patch, f"source {h}x{w} is smaller than a {patch}x{patch} patch"
        self.patch, self.r = patch, patch // 2
        ny, nx = h - patch + 1, w - patch + 1
        n = min(samples, ny * nx)  # sampled patch positions (never the whole unfolded source: 2K-4K)
        idx = torch.randperm(ny * nx, generator=generator)[:n].to(source.device)
        ys, xs = idx // nx, idx % nx
        offs = torch.arange(patch, device=source.device)
        rows = (ys[:, None] + offs[None, :])[:, :, None]  # (n, p, 1)
        cols_ = (xs[:, None] + offs[None, :])[:, None, :]  # (n, 1, p)
        cols = source[:, rows, cols_].permute(1, 0, 2, 3).reshape(n, -1).T  # (C*p*p, n), unfold's order
        self.mean = cols.mean(dim=1, keepdim=True)  # (C*p*p, 1)
        centred = cols - self.mean
        cov = centred @ centred.T / max(cols.shape[1] - 1, 1)
        _, vecs = torch.linalg.eigh(cov.double())
        k = min(dims, vecs.shape[1])
        basis = vecs[:, -k:].flip(1).float()  # (C*p*p, k), largest variance first
        self.weight = basis.T.reshape(k, c, patch, patch).contiguous()  # conv filters
        self.bias = -(basis.T @ self.mean)[:, 0]
        self.source_desc = self.describe(source, periodic=False)  # (k, H - 2r, W - 2r)
        self.valid = self.source_desc.shape[1:]

    def describe(self, feats: torch.Tensor, periodic: bool) -> torch.Tensor:
        """(C, H, W) -> (k, H, W) for a periodic tile, (k, H - 2r, W - 2r) for the source."""
        x = feats[None]
        if periodic:
            x = F.pad(x, (self.r,) * 4, mode="circular")
        return F.conv2d(x, self.weight, self.bias)[0]


def clamp_field(field: torch.Tensor, valid: tuple[int, int], r: int) -> torch.Tensor:
    """Keep source positions inside the patch-centre range ``[r, valid + r)``."""
    y = field[..., 0].clamp(r, valid[0] + r - 1)
    x = field[..., 1].clamp(r, valid[1] + r - 1)
    return torch.stack([y, x], dim=-1)


def _flat(field: torch.Tensor, valid: tuple[int, int], r: int) -> torch.Tensor:
    return (field[..., 0] - r) * valid[1] + (field[..., 1] - r)


def patch_cost(tile_desc: torch.Tensor, space: PatchSpace, field: torch.Tensor, bias: torch.Tensor | None) -> torch.Tensor:
    """(h, w) squared descriptor distance of each tile patch to its source patch, plus the bias there."""
    k = tile_desc.shape[0]
    flat = _flat(field, space.valid, space.r).reshape(-1)
    src = space.source_desc.reshape(k, -1)[:, flat]  # (k, h*w)
    d = ((tile_desc.reshape(k, -1) - src) ** 2).sum(0)
    if bias is not None:
        d = d + bias.reshape(-1)[flat]
    return d.reshape(field.shape[:2])


def patchmatch(tile_desc: torch.Tensor, space: PatchSpace, field: torch.Tensor, bias: torch.Tensor | None,
               rounds: int, generator: torch.Generator, radius: int | None = None,
               coherence: float = 0.0, max_jump: int | None = None) -> torch.Tensor:
    """Improve ``field`` by PatchMatch (Barnes et al. 2009), all pixels at once, on the torus.

    Each round propagates matches from the neighbours at distances 1, 2, 4, ... (wrapping around
    the tile, up to ``max_jump``; a neighbour's match shifted back by the same step, so coherent
    copies grow) and
    then tries random candidates around the current match at halving radii from ``radius`` (the
    whole source by default). ``coherence`` > 0 favours coherent copies (Ashikhmin 2001): a
    neighbour's shifted match is taken unless it costs ``1 + coherence`` times more than the current
    one, and a random candidate must cost ``1 - coherence`` times less. Per-pixel best matches
    that disagree with their neighbours give a mosaic of single texels that reads as mush.
    """
    h, w = field.shape[:2]
    dev = field.device
    cost = patch_cost(tile_desc, space, field, bias)
    r = space.r
    vy, vx = space.valid
    reach = radius if radius is not None else max(vy, vx)

    parity = (torch.arange(h, device=dev)[:, None] + torch.arange(w, device=dev)[None, :]) % 2

    def consider(cand: torch.Tensor, factor: float, only: torch.Tensor | None = None) -> None:
        nonlocal field, cost
        cand = clamp_field(cand, space.valid, r)
        c = patch_cost(tile_desc, space, cand, bias)
        better = (c * factor < cost) & (cand != field).any(-1)
        if only is not None:
            better &= only
        field = torch.where(better[..., None], cand, field)
        cost = torch.where(better, c, cost)

    steps = []
    s = 1
    while s < max(h, w) and (max_jump is None or s <= max_jump):
        steps.append(s)
        s *= 2
    for _ in range(rounds):
        for s in reversed(steps):  # far jumps first, then the immediate neighbours
            for dy, dx in ((s, 0), (-s, 0), (0, s), (0, -s)):
                # red-black passes: neighbours never swap their matches in one simultaneous update
                for colour in (0, 1):
                    shifted = torch.roll(field, shifts=(dy, dx), dims=(0, 1))  # field of the pixel (y-dy, x-dx)
                    consider(shifted + torch.tensor([dy, dx], device=dev),
                             1.0 / (1.0 + coherence) if s == 1 else 1.0, parity == colour)
        rad = reach
        while rad >= 1:
            jitter = torch.randint(-rad, rad + 1, (h, w, 2), generator=generator).to(dev)
            consider(field + jitter, 1.0 / max(1.0 - coherence, 1e-3))
            rad //= 2
    return field


def occurrence_bias(field: torch.Tensor, space: PatchSpace, weight: float, scale: float) -> torch.Tensor | None:
    """Cost added to each source position for how often its neighbourhood is used already.

    ``weight * scale * density / expected``, where density is the number of tile pixels copying
    from within the patch around a source position (per pixel) and ``expected`` the count if the
    tile used the source uniformly (Kaspar et al. 2015's occurrence term). Discourages copying
    one source region over and over.
    """
    if weight <= 0:
        return None
    vy, vx = space.valid
    r = space.r
    flat = _flat(field, space.valid, r).reshape(-1)
    hist = torch.zeros(vy * vx, device=field.device)
    hist.index_add_(0, flat, torch.ones_like(flat, dtype=hist.dtype))
    p = space.patch
    density = F.avg_pool2d(hist.reshape(1, 1, vy, vx), p, stride=1, padding=r, count_include_pad=False)[0, 0]
    expected = field.shape[0] * field.shape[1] / float(vy * vx)
    return weight * scale * density / max(expected, 1e-12)


def gather(source: torch.Tensor, field: torch.Tensor) -> torch.Tensor:
    """(C, H, W) source, (h, w, 2) field -> (C, h, w): each tile pixel's source pixel."""
    c, H, W = source.shape
    flat = (field[..., 0] * W + field[..., 1]).reshape(-1)
    return source.reshape(c, -1)[:, flat].reshape(c, *field.shape[:2])


def _offsets(r: int, stride: int) -> list[tuple[int, int]]:
    return [(dy, dx) for dy in range(-r, r + 1, stride) for dx in range(-r, r + 1, stride)]


def _copied_at(source: torch.Tensor, field: torch.Tensor, dy: int, dx: int) -> torch.Tensor:
    """(C, h, w): what the patch centred at ``p + d`` copies onto every pixel ``p`` (``d = (dy, dx)``): pixel
    ``p`` lies at offset ``-d`` in it, so the source pixel ``field(p + d) - d``, clamped to the source."""
    H, W = source.shape[1:]
    pos = torch.roll(field, shifts=(-dy, -dx), dims=(0, 1)) - torch.tensor([dy, dx], device=field.device)
    pos = torch.stack([pos[..., 0].clamp(0, H - 1), pos[..., 1].clamp(0, W - 1)], -1)
    return gather(source, pos)


def vote(source: torch.Tensor, field: torch.Tensor, r: int, stride: int = 1) -> torch.Tensor:
    """Texture-optimisation vote (Kwatra et al. 2005): every pixel averages what the overlapping
    patches copy onto it (see :func:`_copied_at`). ``stride`` > 1 samples the offsets sparsely."""
    acc = torch.zeros((source.shape[0],) + tuple(field.shape[:2]), device=source.device)
    offs = _offsets(r, stride)
    for dy, dx in offs:
        acc += _copied_at(source, field, dy, dx)
    return acc / len(offs)


def robust_vote(source: torch.Tensor, field: torch.Tensor, r: int, stride: int = 1, iterations: int = 3,
                power: float = 0.8) -> torch.Tensor:
    """Kwatra et al. (2005)'s robust vote: every pixel takes the value that minimises the sum over the patches
    overlapping it of ``|value - what the patch copies there| ** power`` (``power`` < 1: the value most
    patches agree on, not their mean), by iteratively reweighted least squares from the mean vote. Where the
    overlapping patches copy the same texel (inside a coherent block) that texel comes out; at a join, the
    side more patches copy wins instead of a blend. ``source`` (C, H, W) at the field's resolution."""
    x = vote(source, field, r, stride)
    eps = 1e-3 * float(source.std()) + 1e-8
    for _ in range(iterations):
        acc = torch.zeros_like(x)
        total = torch.zeros_like(x[:1])
        for dy, dx in _offsets(r, stride):
            c = _copied_at(source, field, dy, dx)
            w = ((c - x).norm(dim=0, keepdim=True) + eps) ** (power - 2)
            acc += w * c
            total += w
        x = acc / total
    return x
