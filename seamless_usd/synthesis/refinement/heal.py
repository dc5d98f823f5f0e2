"""Healing the joins between copied blocks: minimum-error boundaries, found on the field itself.

A refined tile is a mosaic of blocks, each copied coherently from one place of the source. Where two
blocks meet, the search put the boundary wherever the blocks' patches happened to end: often a straight
line through a stone or across a plank gap. Graph-cut texture synthesis (Kwatra et al. 2003) instead
places each boundary where the two overlapping copies agree, so it follows the texture's own edges.

Here the same idea works directly on the field. Every texel may keep its source position or take a
neighbour's, continued by one texel (that is, extend the neighbour's block over it). The cost of a
labelling is the sum over neighbouring texel pairs copied from different blocks of how much the two
copies disagree there (Kwatra's seam cost: the difference between the two candidate copies at both
texels), read on features blurred by a texel or two so that tone counts, not grain. Iterated
conditional modes on a checkerboard lower it: a boundary texel changes block when that lowers its cost,
so islands and slivers are absorbed and ragged boundaries straighten along where the copies agree. It
is a local method: a straight boundary through texture that disagrees everywhere near it stays where it
is (a graph cut over a band would move it further; not done). Nothing is blended: every texel stays an
exact copy of a source texel; all maps follow the one field, so they stay aligned; the field lives on
the tile's torus, so the tile still wraps.
"""
from __future__ import annotations

import torch
import torch.nn.functional as F

__all__ = ["out_of_source_penalty", "relax_boundaries", "seam_cost", "smoothed"]

_STEPS = ((0, 1), (0, -1), (1, 0), (-1, 0))  # (dy, dx) from a texel to its neighbour


def smoothed(src: torch.Tensor, sigma: float) -> torch.Tensor:
    """(C, H, W) features blurred by a Gaussian of ``sigma`` px: a join is judged by the tone the eye sees on
    both sides, not by the grain, which differs between any two texels of the same surface."""
    if sigma <= 0:
        return src
    r = max(1, round(2.5 * sigma))
    x = torch.arange(-r, r + 1, dtype=src.dtype, device=src.device)
    k = torch.exp(-0.5 * (x / sigma) ** 2)
    k = k / k.sum()
    c = src.shape[0]
    out = F.pad(src[None], (r, r, r, r), mode="replicate")
    out = F.conv2d(out, k.view(1, 1, 1, -1).expand(c, 1, 1, -1), groups=c)
    out = F.conv2d(out, k.view(1, 1, -1, 1).expand(c, 1, -1, 1), groups=c)
    return out[0]


class _Flat:
    """The source as rows of features, looked up by ``(y, x)`` with an inside test."""

    def __init__(self, src: torch.Tensor):
        self.c, self.h, self.w = src.shape
        self.rows = src.reshape(self.c, -1).t().contiguous()

    def at(self, pos: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        y, x = pos[..., 0], pos[..., 1]
        inside = (y >= 0) & (y < self.h) & (x >= 0) & (x < self.w)
        idx = y.clamp(0, self.h - 1) * self.w + x.clamp(0, self.w - 1)
        return self.rows[idx], inside


def _cost(src: _Flat, label: torch.Tensor, nbr: list[torch.Tensor], penalty: float) -> torch.Tensor:
    """(M,) seam cost of texels labelled ``label`` (M, 2) against their four neighbours' source positions
    ``nbr[k]`` (M, 2), neighbour ``k`` lying at step ``_STEPS[k]``.

    A neighbour ``q = p + d`` copied from ``f(q)`` costs nothing when ``f(q) = label + d`` (one block); else
    the two copies' disagreement at ``p`` (``src[label]`` vs ``src[f(q) - d]``) plus at ``q``
    (``src[label + d]`` vs ``src[f(q)]``): Kwatra's seam cost.
    """
    own, _ = src.at(label)
    total = torch.zeros(label.shape[0], dtype=src.rows.dtype, device=label.device)
    for (dy, dx), fq in zip(_STEPS, nbr):
        d = torch.tensor([dy, dx], device=label.device)
        same = (fq == label + d).all(-1)
        a, in_a = src.at(label + d)
        b, in_b = src.at(fq - d)
        q, _ = src.at(fq)
        cost = (own - b).norm(dim=-1) + (a - q).norm(dim=-1)
        cost = torch.where(in_a & in_b, cost, torch.full_like(cost, penalty))
        total += torch.where(same, torch.zeros_like(cost), cost)
    return total


def _neighbours(field: torch.Tensor) -> list[torch.Tensor]:
    """Per step ``d``, the source position of the neighbour at ``p + d`` (torus), at every ``p``."""
    return [torch.roll(field, shifts=(-dy, -dx), dims=(0, 1)) for dy, dx in _STEPS]


def out_of_source_penalty(src: torch.Tensor) -> float:
    """Seam cost of a pair whose continuation leaves the source: that of two unrelated texels, twice."""
    return 2.0 * 1.414 * float(src.reshape(src.shape[0], -1).std(dim=1).norm())


def seam_cost(src: torch.Tensor, field: torch.Tensor, penalty: float | None = None) -> float:
    """Mean seam cost per texel of a field (see :func:`_cost`; each pair counted from both sides)."""
    flat = _Flat(src)
    nbr = [n.reshape(-1, 2) for n in _neighbours(field)]
    pen = out_of_source_penalty(src) if penalty is None else penalty
    return float(_cost(flat, field.reshape(-1, 2), nbr, pen).mean())


def relax_boundaries(src: torch.Tensor, field: torch.Tensor, passes: int = 8, penalty: float | None = None
                     ) -> torch.Tensor:
    """Move the boundaries between the field's blocks to where the copies agree (see the module notes).

    ``src`` is the (C, H, W) source in the units the joins are judged in; ``field`` the (h, w, 2) int64
    source position of every tile texel. Returns a new field whose texels are all source positions and whose
    seam cost is no higher. ``passes`` bounds how far a boundary moves (texels). Only texels on a boundary
    are visited, so a pass costs in proportion to the boundaries' length.
    """
    field = field.clone()
    h, w = field.shape[:2]
    flat = _Flat(src)
    if penalty is None:
        penalty = out_of_source_penalty(src)
    dev = field.device
    parity = ((torch.arange(h, device=dev)[:, None] + torch.arange(w, device=dev)[None, :]) % 2).reshape(-1)
    for _ in range(passes):
        moved = 0
        for colour in (0, 1):
            nbr = _neighbours(field)
            joined = torch.zeros((h, w), dtype=torch.bool, device=dev)
            for (dy, dx), fq in zip(_STEPS, nbr):
                joined |= ~(fq == field + torch.tensor([dy, dx], device=dev)).all(-1)
            idx = torch.nonzero(joined.reshape(-1) & (parity == colour)).squeeze(1)
            if idx.numel() == 0:
                continue
            flat_field = field.reshape(-1, 2)
            around = [n.reshape(-1, 2)[idx] for n in nbr]
            current = flat_field[idx]
            best = _cost(flat, current, around, penalty)
            choice = current
            for (dy, dx), fq in zip(_STEPS, around):
                d = torch.tensor([dy, dx], device=dev)
                cand = fq - d  # the neighbour's block continued over this texel
                _, inside = flat.at(cand)
                cost = _cost(flat, cand, around, penalty)
                better = inside & (cost < best - 1e-6)
                best = torch.where(better, cost, best)
                choice = torch.where(better[:, None], cand, choice)
            changed = (choice != current).any(-1)
            moved += int(changed.sum())
            flat_field[idx] = choice
            field = flat_field.reshape(h, w, 2)
        if moved == 0:
            break
    return field
