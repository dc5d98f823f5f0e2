"""A stack's tile end to end: working resolution, SeamlessGAN training and sampling, refinement.

>>> from seamless_usd.synthesis import MapInput, get_preset
>>> import numpy as np
>>> maps = [MapInput("albedo", np.random.default_rng(0).uniform(-1, 1, (64, 64, 3)).astype(np.float32))]
>>> made = make_tile(maps, get_preset("tiny"))          # doctest: +SKIP
>>> made.maps["albedo"].shape                            # doctest: +SKIP
(64, 64, 3)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch

from seamless_usd.metrics import scale_ratio

from seamless_usd.errors import SeamlessUsdError

from .advice import QUILT_MAX_DIFFERENCE, joins_hide, structure_advice, written_lattice_ratio
from .candidates import (GAN_MIN_SIDE, QUILT_CELLS, QUILT_TRIES, SCORE_SIDE, CutCheck, best_cut, gated, judged,
                         passes_at_full_resolution)
from .config import SynthesisConfig
from .gan.data import effective_k
from .gan.sample import judge, sample
from .gan.seeds import SeedRun, choose_seed, fidelity_score, seed_list, train_seeds
from .grid import downsample_maps, on_grid
from .refinement.refine import RefineConfig, refine
from .scale import structure_size, working_factor
from .types import MapInput, QResult, TileResult, stack_shape

__all__ = ["MadeTile", "make_tile", "downsample_maps", "written_lattice_ratio", "structure_advice", "TILE_SIZES",
           "LAYOUT_SCALE_RANGE", "QUILT_CELLS", "QUILT_TRIES", "QUILT_MAX_DIFFERENCE", "SCORE_SIDE"]

TILE_SIZES = ("source", "paper")

#: A GAN tile seeds the refinement only when every map's feature scale is within this range of the
#: working source's: a generator that has not learnt the texture yet (noise: about 6 with the tiny
#: test preset) would only be copied faithfully into nonsense, and the refinement starts from a
#: random field instead. The default preset's brick tile scores 1.0-1.3.
LAYOUT_SCALE_RANGE = (0.5, 2.0)

@dataclass
class MadeTile:
    """The written tile of a stack and how it was made."""

    maps: dict[str, np.ndarray]  # name -> (h, w, C) float32, periodic; source texels when refined
    tile_size: tuple[int, int]  # (h, w) of ``maps``
    grid_size: tuple[int, int]  # (h, w) of the pixel grid the tile's texels belong to (the UV unit square)
    uv_scale: tuple[float, float]  # (u, v): multiply UVs by this to keep the texel density
    structure_px: float  # structure size estimated on the source (px at the source's resolution)
    working_factor: float  # GAN working resolution / source resolution
    working_size: tuple[int, int]  # (h, w) the GAN trained at
    gan: TileResult | None  # the SeamlessGAN candidate chosen by Q (crop, Q, candidates) at the working resolution;
    #                        None: not trained, the tile cut from the source passed first
    refined: bool
    layout_scale: dict[str, float] = field(default_factory=dict)  # per map, the GAN tile's scale ratio
    layout_used: bool = False  # whether the GAN tile seeded the refinement
    refine_levels: list[dict] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    seeds: list[dict] = field(default_factory=list)  # with config.seeds > 1: each seed's figures and which won
    layout_kind: str = "gan"  # "gan" or "random": what seeded the refinement; "lattice", "window", "mend",
    #                           "quilt": a cut (see .lattice)
    lattice: dict = field(default_factory=dict)  # the stack's lattice, and each layout candidate's figures
    q: QResult | None = None  # Q of the written tile: the GAN sample's, else D's verdict on the tile itself
    alternatives: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)  # the candidate not written
    level_pictures: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (caption, first map): the GAN's
    #                 layout, then every refinement level seen through its field (see refine's ``pictures``)
    levelled: dict = field(default_factory=dict)  # the cut was made of the maps with their light levelled
    #                 (:func:`.imaging.level.level_maps`' facts: how far texel values were scaled); empty: not
    evened: dict = field(default_factory=dict)  # the cut was made of the maps with their lattice evened
    #                 (:func:`.lattice.drift.even_lattice`'s facts: how far texels moved); empty: not

    def __post_init__(self) -> None:
        if self.q is None and self.gan is not None:
            self.q = self.gan.q

    @property
    def q_passed(self) -> bool | None:
        """Whether the discriminator's Q passes on the written tile (through its layout for a refined GAN tile);
        None when no GAN was trained. The discriminator's view only: whether the tile *passed* is the
        verdict's (:mod:`seamless_usd.verdict`)."""
        return None if self.q is None else bool(self.q.passed)


#: Longest side (px) of the per-level pictures of the refinement.
LEVEL_PICTURE = 384


def make_tile(maps: list[MapInput], config: SynthesisConfig, *, refine_config: RefineConfig | None = RefineConfig(),
              tile_size: str = "source", seed: int = 0, device: str | torch.device | None = None,
              checkpoint_dir: str | Path | None = None, progress: Callable[[str, Any], None] | None = None,
              keep_alternatives: bool = False) -> MadeTile:
    """Make a tileable stack from ``maps`` (full resolution, network domain).

    0. With ``refine_config.lattice`` and source-sized tiles, the tile cut from the source comes first
       (:func:`.candidates.check_cut`: whole lattice periods, one window, or a quilt): when the verdict passes
       it on the source's grid, it is written and no GAN is trained (the GAN earns its time only where no
       cut passes). When none passes, the same cuts of the maps with their light levelled
       (:func:`.candidates.best_cut`), then with their drifting lattice evened: one that passes is written,
       ``MadeTile.levelled`` or ``MadeTile.evened`` saying so.
       With ``refine_config``, a stack smaller than GAN_MIN_SIDE gets its cut, passed or not (and an error
       when none can be cut). Otherwise:
    1. Estimate the structure size and the working resolution (:mod:`.scale`); train SeamlessGAN there,
       ``config.seeds`` seeds side by side (:mod:`.seeds`).
    2. Sample: the crop search with the discriminator's Q (``tile_size="source"``: crops of half the
       working stack, so the tile has the stack's size; ``"paper"``: from the whole stack down). With
       several seeds, the tile whose fidelity and seam figures are best is kept.
    3. With ``refine_config``, refine the GAN tile (when its feature scale is plausible, see
       :data:`LAYOUT_SCALE_RANGE`; else a random start) into a tile of source texels at full resolution,
       ``tile_size`` deciding its pixel size (the source's, or the paper's 2c brought to full
       resolution). Without it, the GAN tile at the working resolution is the result.
    4. For a stack that repeats on a lattice, the tile's lattice ratio is measured; with
       ``refine_config.lattice`` and source-sized tiles, the stack also gets a tile cut from the source:
       whole lattice periods when it repeats (:mod:`.lattice.cut`), else, when it continues itself at
       some lags, one window of it joined across its wraps (:mod:`.lattice.window`); the written tile
       is the one that passes (the verdict: no seam and fidelity inside the source's tolerances; the
       lattice ratio, which sees a broken bond), then the one with the lower score.
       ``keep_alternatives`` keeps the candidate not written in ``MadeTile.alternatives``.
    """
    assert tile_size in TILE_SIZES, f"tile_size must be one of {TILE_SIZES}, got {tile_size!r}"
    emit = progress or (lambda kind, detail: None)
    timings: dict[str, float] = {}
    H, W = stack_shape(maps)
    t0 = time.perf_counter()
    structure = structure_size([m.pixels for m in maps])
    f = working_factor(H, W, effective_k(config.k, H, W), structure)
    work_hw = (max(32, round(H * f) // 4 * 4), max(32, round(W * f) // 4 * 4))
    work_hw = (min(work_hw[0], H), min(work_hw[1], W))
    f_y, f_x = work_hw[0] / H, work_hw[1] / W
    timings["scale"] = time.perf_counter() - t0
    if refine_config is not None:
        small = min(H, W) < GAN_MIN_SIDE  # too small to train on: the cut is the tile, passed or not
        cutting = small or (refine_config.lattice and tile_size == "source")
        cut, made_so = best_cut(maps, cutting, seed, timings, stage=lambda what: emit("stage", what))
        if made_so:  # the cut of the maps with their light levelled, or their lattice evened, passes
            how = "its light levelled" if "levelled" in made_so else "its lattice evened"
            made = _made_from_cut(cut, (H, W), structure, f, work_hw, timings,
                                  f"not trained: the tile cut from the source, {how}, passed as it was cut")
            made.levelled, made.evened = made_so.get("levelled", {}), made_so.get("evened", {})
            return made
        if small and cut.kind is None:
            raise SeamlessUsdError(f"the stack is {W}x{H} px: too small for SeamlessGAN ({GAN_MIN_SIDE} px) and no tile "
                                   "can be cut from it; use a larger source")
        if small:
            return _made_from_cut(cut, (H, W), structure, f, work_hw, timings,
                                  f"not trained: the stack is below {GAN_MIN_SIDE} px")
        if cut.passes:
            return _made_from_cut(cut, (H, W), structure, f, work_hw, timings)
    working = downsample_maps(maps, work_hw)

    t1 = time.perf_counter()
    emit("stage", f"no cut passed: training SeamlessGAN ({config.iterations} iterations at "
                  f"{work_hw[1]}x{work_hw[0]} px)")
    models = train_seeds(working, config, seed, device=device, checkpoint_dir=checkpoint_dir,
                         progress=lambda p: emit("train", p))
    timings["train"] = time.perf_counter() - t1
    t2 = time.perf_counter()
    runs = []
    for s, model in zip(seed_list(seed, config.seeds), models):
        run = SeedRun(s, sample(model, working, seed=s, tile_size=tile_size, progress=lambda p: emit("sample", p)))
        if len(models) > 1:
            run.score, run.scale, run.patch = fidelity_score(run.tile.maps, working)
        runs.append(run)
    chosen = choose_seed(runs)
    gan = chosen.tile
    seeds = [r.summary() for r in runs] if len(runs) > 1 else []
    timings["sample"] = time.perf_counter() - t2
    gan_hw = next(iter(gan.maps.values())).shape[:2]

    if refine_config is None:
        uv = (work_hw[1] / gan_hw[1], work_hw[0] / gan_hw[0])
        return MadeTile(dict(gan.maps), tuple(gan_hw), work_hw, uv, structure, f, work_hw, gan, False,
                        timings=timings, seeds=seeds)
    if tile_size == "source":
        out_hw = (H, W)
    else:  # the paper's 2c x 2c, at the source's resolution
        out_hw = (round(gan_hw[0] / f_y), round(gan_hw[1] / f_x))
    t3 = time.perf_counter()
    layout_scale = chosen.scale or {  # the seed choice measured it already
        w.name: round(scale_ratio(gan.maps[w.name], w.pixels, w.is_normal), 3) for w in working}
    low, high = LAYOUT_SCALE_RANGE
    use_layout = all(low <= v <= high for v in layout_scale.values())
    layout = [gan.maps[m.name] for m in maps] if use_layout else None
    result = refine([m.pixels for m in maps], layout, out_hw, refine_config,
                    seed=seed, device=device, progress=lambda info: emit("refine", info), pictures=LEVEL_PICTURE,
                    normals=[m.is_normal for m in maps])
    timings["refine"] = time.perf_counter() - t3
    tiles = {m.name: np.ascontiguousarray(t, dtype=np.float32) for m, t in zip(maps, result.maps)}
    model = models[runs.index(chosen)]
    # the refinement follows the GAN tile, so it inherits the sample's Q; from a random start it does
    # not, and the discriminator judges the refined tile itself
    q = None if use_layout else judge(model, on_grid(tiles, maps, (f_y, f_x)))
    made = MadeTile(tiles, out_hw, (H, W), (W / out_hw[1], H / out_hw[0]), structure, f, work_hw, gan, True,
                    layout_scale, use_layout, result.levels, timings, seeds, "gan" if use_layout else "random", q=q,
                    level_pictures=_level_pictures(gan.maps[maps[0].name], use_layout, result))
    t4 = time.perf_counter()
    _try_lattice(made, maps, model, cut, keep_alternatives)
    timings["lattice"] += time.perf_counter() - t4
    return made


def _made_from_cut(cut: CutCheck, grid_hw: tuple[int, int], structure: float, factor: float,
                   work_hw: tuple[int, int], timings: dict[str, float],
                   why: str = "not trained: the tile cut from the source passed as it was cut") -> MadeTile:
    """The written tile made before any training (the cut passes, or the stack is too small to train on): every
    texel a source copy, no GAN."""
    H, W = grid_hw
    tile_hw = tuple(next(iter(cut.tiles.values())).shape[:2])
    notes = {**cut.notes, "cut": cut.kind, "tile": list(tile_hw), "passes": cut.passes, "score": round(cut.score, 3),
             "chosen": True, "gan": why, **cut.figures}
    if cut.ratio is not None:
        notes["lattice_ratio"] = round(cut.ratio, 3)
    return MadeTile(dict(cut.tiles), tile_hw, (H, W), (W / tile_hw[1], H / tile_hw[0]), structure, factor, work_hw,
                    None, False, timings=timings, layout_kind=cut.kind, lattice=notes)


def _level_pictures(layout: np.ndarray, used: bool, result) -> list[tuple[str, np.ndarray]]:
    """Where a structure breaks, stage by stage: the GAN's layout, then each refinement level's field."""
    h, w = layout.shape[:2]
    out = [(f"GAN layout, {w} x {h} px (working resolution)" + ("" if used else "; not used: its scale was off"),
            np.ascontiguousarray(layout, dtype=np.float32))]
    for info, pic in zip(result.levels, result.pictures):
        th, tw = info["tile"]
        how = "carried (no search)" if info["iterations"] == 0 else f"searched, {info['iterations']} iterations"
        out.append((f"refinement level {tw} x {th} px, {how}", pic))
    return out


def _try_lattice(made: MadeTile, maps: list[MapInput], model, cut: CutCheck, keep_alternatives: bool) -> None:
    """Measure the written tile against the tile cut from the source (``cut``, made and judged before
    training) and keep the cut when it wins: the candidate that passes (the verdict: no seam, fidelity inside
    the source's tolerances; for a stack that repeats, the lattice ratio) before one that does not, then the
    lower score (see :func:`.candidates.judged`). The figures are taken on the source's grid, halved down to
    SCORE_SIDE; whether a candidate passes, at full resolution."""
    H, W = made.grid_size
    made.lattice = dict(cut.notes)
    if not cut.lattice.found and cut.kind is None:
        return
    halve = cut.halve
    current, current_passes, current_ratio = judged(on_grid(made.maps, maps, (1 / halve, 1 / halve)), cut.grid,
                                                    cut.grid_lattice, cut.reference)
    if halve > 1:  # scored on the halved grid, passed or not at full resolution (as the cut: check_cut)
        current_passes = passes_at_full_resolution(made.maps, maps, current_ratio)
    kind = made.layout_kind
    made.lattice.update({f"q_passed_{kind}": made.q_passed, f"passes_{kind}": current_passes,
                         f"score_{kind}": round(current, 3)})
    if current_ratio is not None:
        made.lattice[f"lattice_ratio_{kind}"] = round(current_ratio, 3)
    if cut.kind is None:
        return
    cut_kind, tiles, figures, score, passes = cut.kind, cut.tiles, cut.figures, cut.score, cut.passes
    tile_hw = next(iter(tiles.values())).shape[:2]
    q = judge(model, on_grid(tiles, maps, (made.working_size[0] / H, made.working_size[1] / W)))
    wins = (not passes, score) < (not current_passes, current)
    if wins and gated(cut_kind, figures) and not joins_hide(figures):
        # a cut whose joins do not hide (a quilt, a mend of lines, a lattice across an axis that does not repeat)
        # is written only where the verdict sees them, never as a tile that
        # passes (the cut's verdict is the full resolution's, as the written tile's: .candidates.check_cut)
        if cut.verdict_passes:
            wins = False
            made.lattice[f"{cut_kind}_refused"] = {"difference_worst": figures["difference_worst"],
                                                   "most": QUILT_MAX_DIFFERENCE}
    made.lattice.update({"cut": cut_kind, "tile": list(tile_hw), "q_passed": bool(q.passed), "passes": passes,
                         "score": round(score, 3), "chosen": wins, **figures})
    if cut.ratio is not None:
        made.lattice["lattice_ratio"] = round(cut.ratio, 3)
    if wins:
        loser_kind, loser = made.layout_kind, dict(made.maps)
        made.maps, made.tile_size, made.q = tiles, tuple(tile_hw), q
        made.uv_scale = (W / tile_hw[1], H / tile_hw[0])
        made.layout_kind, made.refine_levels = cut_kind, []  # copied through the cut's field, not refined
        made.level_pictures = made.level_pictures[:1]  # the GAN's layout only: the cut is not refined
    else:
        loser_kind, loser = cut_kind, tiles
    if keep_alternatives:
        made.alternatives[loser_kind] = loser
