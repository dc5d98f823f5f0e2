"""Toroidal exemplar refinement: from the GAN's tileable layout to the source's full resolution.

Beyond the paper. The GAN trains at a working resolution where its crop spans the texture's
structure; its tile is tileable and has the right arrangement but not the source's crispness. A
coarse-to-fine texture optimisation on a torus (Kwatra et al. 2005, with PatchMatch search and
Kaspar et al. 2015's occurrence penalty) rebuilds it from the source's own patches:

1. the layout (all maps, jointly) seeds the coarsest level: from a block-random start, PatchMatch
   finds source patches matching the layout's, coherent and spread over the source;
2. each level iterates copy (every tile pixel takes its match's source texel) and search
   (PatchMatch with wrap-around on the tile, favouring coherent copies), the exemplar's patches
   driving; a vote (Kwatra's average of overlapping patches) is an option, off by default since it
   blurs the target and the search then picks smooth patches;
3. the match field is carried to the next level, up to the source's resolution; levels above
   ``carry_above`` px only carry it (each coarse match brings its block of real source texels).

The output maps are copied from the source through the final field: one field for every map, so
the maps stay pixel-aligned and keep real source texels (bit depth, colour space, unit normals),
and the tile wraps around by construction. Two options, off by default, make new values near the
joins instead (a gradient-domain blend of a band, :mod:`.blend`, or Kwatra's robust vote).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import torch
import torch.nn.functional as F

from .blend import blend_band
from .settings import RefineConfig
from .heal import relax_boundaries, smoothed
from .patches import PatchSpace, clamp_field, gather, occurrence_bias, patch_cost, patchmatch, robust_vote, vote
from ..precision import pick_device

__all__ = ["RefineConfig", "RefineResult", "refine", "field_picture", "joint_features", "level_scales", "resize_periodic", "spread"]


@dataclass
class RefineResult:
    field: np.ndarray  # (h, w, 2) int64 source (y, x) of every tile pixel, at full resolution
    maps: list[np.ndarray]  # per map, (h, w, C_i) float32 copied from the source through ``field``
    levels: list[dict] = field(default_factory=list)  # per level: scale, size, seconds, mean cost
    seconds: float = 0.0
    pictures: list[np.ndarray] = field(default_factory=list)  # per level: the first map through its field (small)
    band: np.ndarray | None = None  # (h, w) bool: texels blended across a join (``blend``); None: all are copies


def field_picture(source: np.ndarray, fld: torch.Tensor, level_source_hw: tuple[int, int], side: int) -> np.ndarray:
    """The full-resolution ``source`` seen through a level's field: at most ``side`` px, one texel per sample
    (nearest), so a block edge or a broken line shows as it is, not smoothed."""
    h, w = fld.shape[:2]
    n = max(1, math.ceil(max(h, w) / side))
    sub = fld[::n, ::n].cpu().numpy()
    sy = source.shape[0] / level_source_hw[0]
    sx = source.shape[1] / level_source_hw[1]
    y = np.clip(np.round(sub[..., 0] * sy).astype(np.int64), 0, source.shape[0] - 1)
    x = np.clip(np.round(sub[..., 1] * sx).astype(np.int64), 0, source.shape[1] - 1)
    return np.ascontiguousarray(source[y, x], dtype=np.float32)


def spread(m: np.ndarray) -> float:
    """RMS distance of a map's pixels to its mean colour (at least 1e-3, for flat maps)."""
    m = np.asarray(m, dtype=np.float32)
    return max(float(np.sqrt(((m - m.mean(axis=(0, 1))) ** 2).sum(axis=-1).mean())), 1e-3)


def joint_features(maps: list[np.ndarray], like: list[np.ndarray] | None = None) -> np.ndarray:
    """(H, W, sum C_i) float32: every map divided by its spread (that of ``like``'s map when given),
    so that each contributes equally to patch distances."""
    parts = [np.asarray(m, dtype=np.float32) / spread(ref) for m, ref in zip(maps, like or maps)]
    return np.concatenate(parts, axis=2)


def level_scales(tile_hw: tuple[int, int], coarsest: int) -> list[float]:
    """Scales (<= 1) of the pyramid levels, coarsest first, doubling, the last exactly 1."""
    long_side = max(tile_hw)
    n = max(0, math.ceil(math.log2(max(long_side / coarsest, 1.0))))
    return [1.0 / 2 ** i for i in range(n, 0, -1)] + [1.0]


def _resize(x: torch.Tensor, hw: tuple[int, int]) -> torch.Tensor:
    """(C, H, W) -> (C, h, w) by area averaging (downsampling) or bilinear interpolation."""
    if tuple(x.shape[1:]) == tuple(hw):
        return x
    if hw[0] <= x.shape[1] and hw[1] <= x.shape[2]:
        return F.interpolate(x[None], size=hw, mode="area")[0]
    return F.interpolate(x[None], size=hw, mode="bilinear", align_corners=False)[0]


def resize_periodic(x: torch.Tensor, hw: tuple[int, int]) -> torch.Tensor:
    """Resize a periodic tile: pad circularly first so the borders see their wrapped neighbours."""
    if tuple(x.shape[1:]) == tuple(hw):
        return x
    pad = 2
    big = F.pad(x[None], (pad,) * 4, mode="circular")[0]
    sy, sx = hw[0] / x.shape[1], hw[1] / x.shape[2]
    out = _resize(big, (round(big.shape[1] * sy), round(big.shape[2] * sx)))
    oy, ox = round(pad * sy), round(pad * sx)
    return out[:, oy: oy + hw[0], ox: ox + hw[1]]


def _carry(fld: torch.Tensor, dst_tile: tuple[int, int], ratio: tuple[float, float],
           src_ratio: tuple[float, float], r: int, valid: tuple[int, int]) -> torch.Tensor:
    """Match field of a coarser level carried to a finer one: each fine pixel keeps its coarse
    pixel's match, shifted by its own offset inside that pixel, so coherent copies stay coherent."""
    h, w = dst_tile
    dev = fld.device
    ys = torch.arange(h, device=dev)
    xs = torch.arange(w, device=dev)
    cy = torch.clamp((ys.float() / ratio[0]).long(), max=fld.shape[0] - 1)
    cx = torch.clamp((xs.float() / ratio[1]).long(), max=fld.shape[1] - 1)
    coarse = fld[cy][:, cx]  # (h, w, 2)
    off_y = ys[:, None] - torch.round(cy.float() * ratio[0]).long()[:, None]
    off_x = xs[None, :] - torch.round(cx.float() * ratio[1]).long()[None, :]
    y = torch.round(coarse[..., 0].float() * src_ratio[0]).long() + off_y
    x = torch.round(coarse[..., 1].float() * src_ratio[1]).long() + off_x
    return clamp_field(torch.stack([y, x], -1), valid, r)


def _random_field(tile: tuple[int, int], valid: tuple[int, int], r: int, block: int,
                  generator: torch.Generator, device: torch.device) -> torch.Tensor:
    """A block-random start: blocks of ``block`` px copied from random source positions."""
    h, w = tile
    by, bx = -(-h // block), -(-w // block)
    oy = torch.randint(0, valid[0], (by, bx), generator=generator)
    ox = torch.randint(0, valid[1], (by, bx), generator=generator)
    ys, xs = torch.arange(h), torch.arange(w)
    y = oy[ys // block][:, xs // block] + (ys % block)[:, None] + r
    x = ox[ys // block][:, xs // block] + (xs % block)[None, :] + r
    return clamp_field(torch.stack([y, x], -1).to(device), valid, r)


def _voted(sources: list[np.ndarray], fld: torch.Tensor, config: RefineConfig, normals: list[bool] | None
           ) -> list[np.ndarray]:
    """The maps made by the robust vote over the final field, on the joint features (one set of weights for
    every map, so they stay aligned), back in each map's units; normal maps renormalised."""
    src = torch.from_numpy(np.ascontiguousarray(joint_features(sources).transpose(2, 0, 1))).to(fld.device)
    r = config.patch // 2
    voted = robust_vote(src, fld, r, config.vote_stride, config.robust_vote).cpu().numpy().transpose(1, 2, 0)
    f = fld.cpu().numpy()
    parts, copies, at = [], [], 0
    for m in sources:
        c = m.shape[2]
        parts.append(voted[..., at:at + c] * spread(m))
        copies.append(np.asarray(m, dtype=np.float32)[f[..., 0], f[..., 1]])
        at += c
    # where the vote is the copy (every overlapping patch agreed) the texel stays that exact source texel,
    # not the copy through the feature scaling and back
    kept = np.all([np.abs(p - q).max(axis=-1) < 1e-5 for p, q in zip(parts, copies)], axis=0)
    out = []
    for i, (part, copy) in enumerate(zip(parts, copies)):
        if normals is not None and normals[i] and part.shape[2] >= 3:
            part[..., :3] /= np.maximum(np.linalg.norm(part[..., :3], axis=-1, keepdims=True), 1e-8)
        out.append(np.ascontiguousarray(np.where(kept[..., None], copy, part), dtype=np.float32))
    return out


def refine(sources: list[np.ndarray], layout: list[np.ndarray] | None, tile_hw: tuple[int, int],
           config: RefineConfig = RefineConfig(), *, seed: int = 0, device: str | torch.device | None = None,
           progress=None, pictures: int = 0, normals: list[bool] | None = None) -> RefineResult:
    """Refine a tileable layout into a full-resolution tile made of source texels.

    Parameters
    ----------
    sources : the stack's maps at full resolution, each (H, W, C_i) float32 (network domain).
    layout : the GAN's tileable tile, one array per map (h', w', C_i), any resolution; None starts
        from a block-random field instead (the "refinement alone" baseline).
    tile_hw : (h, w) of the output tile at the sources' resolution.
    progress : called with a dict per finished level.
    pictures : when > 0, keep for every level the first map seen through its field, at most this many px.
    normals : which maps are normal maps (blended or voted as vectors, then renormalised, when
        ``config.blend`` or ``config.robust_vote`` is on).

    With ``config.blend`` or ``config.robust_vote`` (both off by default) the texels near the joins are
    new values, not copies (``RefineResult.band`` marks the blended ones).
    """
    t_start = time.perf_counter()
    dev = pick_device(device)
    gen = torch.Generator().manual_seed(seed)
    src = torch.from_numpy(np.ascontiguousarray(joint_features(sources).transpose(2, 0, 1))).to(dev)
    if layout is not None:
        assert len(layout) == len(sources), f"layout has {len(layout)} maps, the stack {len(sources)}"
        lay_np = joint_features(layout, like=sources)  # in the source's feature units
        lay = torch.from_numpy(np.ascontiguousarray(lay_np.transpose(2, 0, 1))).to(dev)
    H, W = src.shape[1:]
    th, tw = tile_hw
    scales = level_scales(tile_hw, config.coarsest)
    levels: list[dict] = []
    shots: list[np.ndarray] = []

    def finish(info: dict, s_hw: tuple[int, int]) -> None:  # a level is done: record, picture, report
        levels.append(info)
        if pictures:
            shots.append(field_picture(sources[0], fld, s_hw, pictures))
        if progress is not None:
            progress(info)

    fld = None
    prev_tile = prev_src = None
    for li, s in enumerate(scales):
        t0 = time.perf_counter()
        t_hw = (max(config.patch, round(th * s)), max(config.patch, round(tw * s)))
        patch = config.coarse_patch if config.coarse_patch and max(t_hw) <= config.coarse_until else config.patch
        r = patch // 2
        s_hw = (max(patch + 1, round(H * s)), max(patch + 1, round(W * s)))
        t_hw = (max(patch, t_hw[0]), max(patch, t_hw[1]))
        if li > 0 and max(t_hw) > config.carry_above:  # carry only: no descriptors, no search
            valid = (s_hw[0] - 2 * r, s_hw[1] - 2 * r)
            ratio = (t_hw[0] / prev_tile[0], t_hw[1] / prev_tile[1])
            fld = _carry(fld, t_hw, ratio, (s_hw[0] / prev_src[0], s_hw[1] / prev_src[1]), r, valid)
            if config.heal:
                fld = relax_boundaries(smoothed(_resize(src, s_hw), config.heal_sigma), fld, config.heal)
            prev_tile, prev_src = t_hw, s_hw
            finish({"scale": s, "tile": list(t_hw), "source": list(s_hw), "iterations": 0, "mean_cost": None,
                    "seconds": round(time.perf_counter() - t0, 3)}, s_hw)
            continue
        level_src = _resize(src, s_hw)
        space = PatchSpace(level_src, patch, config.dims, gen)
        finest_two = li >= len(scales) - 2
        iters = config.iterations if not finest_two or li == 0 else config.fine_iterations
        if fld is None:
            # a coherent block-random start; with a layout, the coarsest level's searches match the layout
            # (PatchMatch with the coherence and occurrence terms: an exact per-pixel search collapses
            # onto the few source patches nearest to a smooth layout and carries a texel grid upward)
            fld = _random_field(t_hw, space.valid, r, max(4, patch), gen, dev)
            guide = space.describe(resize_periodic(lay, t_hw), periodic=True) if layout is not None else None
            radius = None
        else:
            ratio = (t_hw[0] / prev_tile[0], t_hw[1] / prev_tile[1])
            src_ratio = (s_hw[0] / prev_src[0], s_hw[1] / prev_src[1])
            fld = _carry(fld, t_hw, ratio, src_ratio, r, space.valid)
            radius = config.fine_radius
        cost = None
        for it in range(iters):
            stride = config.vote_stride if li == len(scales) - 1 else 1
            if li == 0 and guide is not None:
                desc = guide
            else:
                target = vote(level_src, fld, r, stride) if s <= config.vote_until else gather(level_src, fld)
                desc = space.describe(target, periodic=True)
            scale = float(cost.median()) if cost is not None else float(desc.var(dim=(1, 2)).sum())
            bias = occurrence_bias(fld, space, config.occurrence, scale)
            fld = patchmatch(desc, space, fld, bias, config.pm_rounds, gen, radius=radius,
                             coherence=config.coherence, max_jump=None if li == 0 else config.fine_jump)
            cost = patch_cost(desc, space, fld, None)  # without the occurrence term
        if config.heal:
            fld = relax_boundaries(smoothed(level_src, config.heal_sigma), fld, config.heal)
        prev_tile, prev_src = t_hw, s_hw
        if cost is None:
            cost = patch_cost(space.describe(gather(level_src, fld), periodic=True), space, fld, None)
        finish({"scale": s, "tile": list(t_hw), "source": list(s_hw), "iterations": iters, "patch": patch,
                "mean_cost": float(cost.mean()), "seconds": round(time.perf_counter() - t0, 3)}, s_hw)
    assert tuple(fld.shape[:2]) == (th, tw), f"field {tuple(fld.shape[:2])} != tile {(th, tw)}"
    field_np = fld.cpu().numpy()
    band = None
    if config.robust_vote > 0:
        maps = _voted(sources, fld, config, normals)
    elif config.blend > 0:
        maps, band = blend_band(sources, field_np, config.blend, normals)
    else:
        maps = [np.ascontiguousarray(np.asarray(m)[field_np[..., 0], field_np[..., 1]]) for m in sources]
    return RefineResult(field=field_np, maps=maps, levels=levels, seconds=time.perf_counter() - t_start,
                        pictures=shots, band=band)
