"""The refinement's settings, apart from its code: a run that only reads them (a cache key) needs no torch."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["RefineConfig"]


@dataclass(frozen=True)
class RefineConfig:
    patch: int = 11  # patch side at every level; 11 beat 7 on the wood window (patch distance 1.07 vs 1.20) and
    #                  kept a 16 x 24 px pattern's periods within 3 % where 7 broke it into fragments
    dims: int = 24  # PCA descriptor size; 24 keeps > 95 % of the patch variance on the bundled stacks
    coarsest: int = 64  # longest tile side (px) at the coarsest level, where the layout is matched exactly
    iterations: int = 3  # vote + search iterations per level below the finest two
    fine_iterations: int = 1  # iterations at the two finest levels (the carried field is already good there)
    pm_rounds: int = 2  # PatchMatch rounds per search
    fine_jump: int = 2  # longest propagation jump (px) above the coarsest level, where the carried field is coherent
    fine_radius: int = 8  # random-search radius (px) at levels above the coarsest, around the carried match
    coherence: float = 1.0  # preference for coherent copies in the search (see patches.patchmatch)
    occurrence: float = 0.1  # weight of the occurrence penalty, relative to the median patch cost
    carry_above: int = 1024  # levels whose tile is longer than this (px) only carry the field: each texel block
    #                          is copied coherently from the source, with no search (2K-4K stay fast)
    vote_stride: int = 2  # offsets of the vote at the finest level (1: all p*p offsets)
    vote_until: float = 0.0  # levels at this scale or coarser search against Kwatra's vote; the others (all, by
    #                          default) against the copied texels themselves. On a 512 px wood window the vote's
    #                          averaging made the search pick smooth patches: patch distance 4.9 against 1.2
    #                          without it, and the grain washed out.
    coarse_patch: int = 0  # patch side at the levels that decide the structure (tile <= coarse_until px); 0: patch
    coarse_until: int = 256
    heal: int = 0  # passes of minimum-error boundary relaxation after each level (see .heal); 0: off
    heal_sigma: float = 1.5  # blur (px at the level) of the features the joins are judged on while healing
    robust_vote: int = 0  # iterations of Kwatra's robust vote (see .patches.robust_vote) making the output from the
    #                       final field: copies where the overlapping patches agree, voted values near the joins;
    #                       0: off, every texel an exact copy
    blend: int = 0  # width (texels) of the band around every join blended in the gradient domain (see .blend); 0: off,
    #                 every texel an exact copy
    lattice: bool = True  # every stack also gets a tile cut from the source: whole periods when it repeats on a
    #                       lattice (bricks, weaves), else one window joined across its wraps (see .lattice); the
    #                       verdict and the fidelity figures choose between the two
