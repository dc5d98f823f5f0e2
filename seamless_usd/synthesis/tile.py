"""A stack's tile end to end: working resolution, SeamlessGAN training and sampling, refinement.

>>> from seamless_usd.synthesis import MapInput, get_preset
>>> import numpy as np
>>> maps = [MapInput("albedo", np.random.default_rng(0).uniform(-1, 1, (64, 64, 3)).astype(np.float32))]
>>> made = make_tile(maps, get_preset("tiny"))          # doctest: +SKIP
>>> made.maps["albedo"].shape                            # doctest: +SKIP
(64, 64, 3)
"""
from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch
import torch.nn.functional as F

from seamless_usd.metrics import scale_ratio
from seamless_usd.metrics.structure import STRUCTURE_TARGET, structure_figures
from seamless_usd.verdict import Reading, Reference, judge_reading
from seamless_usd.verdict import judge as verdict_of

from .config import SynthesisConfig
from .gan.data import effective_k
from .gan.sample import judge, sample
from .gan.seeds import SeedRun, choose_seed, fidelity_score, seed_list, train_seeds
from .lattice.cut import LATTICE_TARGET, Lattice, find_lattice, lattice_cut, lattice_ratio, lattice_tile_size
from .lattice.quilt import best_quilt
from .lattice.window import WINDOW_MAX_DIFFERENCE, continues_itself, window_tile_size
from .refinement.refine import RefineConfig, refine, resize_periodic
from .scale import structure_size, working_factor
from .types import MapInput, QResult, TileResult, stack_shape

__all__ = ["MadeTile", "make_tile", "downsample_maps", "written_lattice_ratio", "structure_advice", "TILE_SIZES",
           "LAYOUT_SCALE_RANGE"]

TILE_SIZES = ("source", "paper")

#: A GAN tile seeds the refinement only when every map's feature scale is within this range of the
#: working source's: a generator that has not learnt the texture yet (noise: about 6 with the tiny
#: test preset) would only be copied faithfully into nonsense, and the refinement starts from a
#: random field instead. The default preset's brick tile scores 1.0-1.3.
LAYOUT_SCALE_RANGE = (0.5, 2.0)

#: Blocks (rows, columns) of a quilted tile (:mod:`.lattice.quilt`): the fewest that still let every block be
#: chosen to fit its neighbours; each block keeps a stone or a run of plank whole.
QUILT_CELLS = (2, 2)
#: Quilts tried (seeds) for a stack; the one whose worst join costs least is weighed.
QUILT_TRIES = 3
#: A quilt whose two blocks differ along some cut by more than this (mean squared difference over that of
#: two unrelated texels) may be written only where the verdict does not pass it. The window cut's
#: threshold, fixed on window cuts looked at along their wraps (``benchmarks/experiments/results/window_gate.md``);
#: quilts looked at afterwards: the two the verdict passed at or under it are seamless, the three it
#: passed over it (0.10-0.36) show two-tone stones, stepped tone patches and stripes ending at a cut.
QUILT_MAX_DIFFERENCE = WINDOW_MAX_DIFFERENCE

#: Layout candidates are compared on the source's grid, halved until its longest side is at most this (px).
SCORE_SIDE = 1024


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
    gan: TileResult  # the SeamlessGAN candidate chosen by Q (crop, Q, candidates) at the working resolution
    refined: bool
    layout_scale: dict[str, float] = field(default_factory=dict)  # per map, the GAN tile's scale ratio
    layout_used: bool = False  # whether the GAN tile seeded the refinement
    refine_levels: list[dict] = field(default_factory=list)
    timings: dict[str, float] = field(default_factory=dict)
    seeds: list[dict] = field(default_factory=list)  # with config.seeds > 1: each seed's figures and which won
    layout_kind: str = "gan"  # "gan" or "random": what seeded the refinement; "lattice", "window", "quilt": a cut (see
    #                           .lattice)
    lattice: dict = field(default_factory=dict)  # the stack's lattice, and each layout candidate's figures
    q: QResult | None = None  # Q of the written tile: the GAN sample's, else D's verdict on the tile itself
    alternatives: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)  # the candidate not written
    level_pictures: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (caption, first map): the GAN's
    #                 layout, then every refinement level seen through its field (see refine's ``pictures``)

    def __post_init__(self) -> None:
        if self.q is None:
            self.q = self.gan.q

    @property
    def q_passed(self) -> bool:
        """Whether the discriminator's Q passes on the written tile (through its layout for a refined GAN tile).
        The discriminator's view only: whether the tile *passed* is the verdict's (:mod:`seamless_usd.verdict`)."""
        return bool(self.q.passed)


#: Longest side (px) of the per-level pictures of the refinement.
LEVEL_PICTURE = 384


def downsample_maps(maps: list[MapInput], size: tuple[int, int]) -> list[MapInput]:
    """Maps resized to ``size = (h, w)`` (bilinear, antialiased when shrinking; normals renormalised)."""
    return [m if m.pixels.shape[:2] == tuple(size) else
            MapInput(m.name, _resized(m.pixels, size, m.is_normal), m.is_normal) for m in maps]


def _resized(pixels: np.ndarray, size: tuple[int, int], is_normal: bool, periodic: bool = False) -> np.ndarray:
    """(H, W, C) pixels resized to ``size``: bilinear with antialiasing, or, for a periodic tile, area
    averaging with wrap-around (:func:`.refine.resize_periodic`); normals renormalised, values clamped."""
    t = torch.from_numpy(np.ascontiguousarray(pixels.transpose(2, 0, 1)))
    if periodic:
        r = resize_periodic(t, size)
    else:
        r = F.interpolate(t[None], size=size, mode="bilinear", antialias=True, align_corners=False)[0]
    if is_normal and r.shape[0] >= 3:
        r = torch.cat([F.normalize(r[:3], dim=0, eps=1e-6), r[3:]], 0)
    return np.ascontiguousarray(r.clamp(-1, 1).permute(1, 2, 0).numpy())


def make_tile(maps: list[MapInput], config: SynthesisConfig, *, refine_config: RefineConfig | None = RefineConfig(),
              tile_size: str = "source", seed: int = 0, device: str | torch.device | None = None,
              checkpoint_dir: str | Path | None = None, progress: Callable[[str, Any], None] | None = None,
              keep_alternatives: bool = False) -> MadeTile:
    """Make a tileable stack from ``maps`` (full resolution, network domain).

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
    working = downsample_maps(maps, work_hw)
    timings["scale"] = time.perf_counter() - t0

    t1 = time.perf_counter()
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
    q = None if use_layout else judge(model, _on_grid(tiles, maps, (f_y, f_x)))
    made = MadeTile(tiles, out_hw, (H, W), (W / out_hw[1], H / out_hw[0]), structure, f, work_hw, gan, True,
                    layout_scale, use_layout, result.levels, timings, seeds, "gan" if use_layout else "random", q=q,
                    level_pictures=_level_pictures(gan.maps[maps[0].name], use_layout, result))
    t4 = time.perf_counter()
    _try_lattice(made, maps, model, refine_config.lattice and tile_size == "source", keep_alternatives, seed)
    timings["lattice"] = time.perf_counter() - t4
    return made


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


def written_lattice_ratio(lattice: dict, layout_kind: str | None) -> float | None:
    """The lattice ratio of the written tile, from ``MadeTile.lattice`` and ``MadeTile.layout_kind`` (as
    recorded, e.g. in a cached stack's metadata); None when the stack does not repeat."""
    cut = layout_kind in ("lattice", "window", "quilt")  # the cut's figures carry no suffix
    return lattice.get("lattice_ratio" if cut else f"lattice_ratio_{layout_kind}")


def structure_advice(lattice: dict, layout_kind: str | None) -> str | None:
    """What to do about a stack whose written tile's joins cannot hide, from ``MadeTile.lattice`` and
    ``MadeTile.layout_kind`` as recorded; None for any other. Such a stack neither repeats (no lattice) nor
    continues itself at a window's lags (its window was refused), and what was written is the refined tile or
    a quilt whose blocks differ along a cut: every lever measured on such stacks leaves joins that show
    (two-tone stones, stepped tone patches, jogging courses, stripes that end; ``benchmarks/experiments/results/levers*.md``)."""
    refused = lattice.get("window_refused")
    if refused is None or any(p is not None for p in lattice.get("period_px") or []):
        return None
    if layout_kind == "quilt" and _joins_hide(lattice):
        return None
    lags = ", ".join(f"{axis} {value:.2f}" for axis, value in refused["lag_difference"].items())
    return (f"the texture neither repeats nor continues itself (its window lags differ by {lags}; a cut hides at "
            f"{refused['most']:.2f} or less), so joins between copies of it show: use a source made to repeat, "
            "or mend the joins by hand")


def _on_grid(tiles: dict[str, np.ndarray], maps: list[MapInput], factor: tuple[float, float]) -> dict[str, np.ndarray]:
    """Periodic tiles resized by ``factor`` per axis (working / source size: onto the working grid)."""
    out = {}
    for m in maps:
        h, w = tiles[m.name].shape[:2]
        hw = (max(8, round(h * factor[0])), max(8, round(w * factor[1])))
        out[m.name] = _resized(tiles[m.name], hw, m.is_normal, periodic=True)
    return out


def _judged(tiles: dict[str, np.ndarray], maps: list[MapInput], lattice: Lattice, reference: Reference
            ) -> tuple[float, bool, float | None]:
    """(score, passes, lattice ratio) of a candidate tile; ``reference``: ``maps`` prepared for the verdict once
    for every candidate.

    The score is the worst figure in units of its target: :func:`.seeds.fidelity_score`; the structure
    figure (value over STRUCTURE_TARGET: broken joints and chopped lines, which no fidelity figure sees);
    the verdict's strongest seam run over its threshold (between two tiles that both have seams, the one
    whose worst join is weaker); and for a stack that repeats, the lattice ratio ((1 - r) over
    (1 - LATTICE_TARGET)): none of the fidelity and seam figures sees a broken bond, the lattice ratio does.
    The tile passes as a stack would (the verdict: no seam, fidelity inside the source's tolerances) and
    keeps the repeat."""
    score, _, _ = fidelity_score(tiles, maps)
    score = max([score] + [structure_figures(tiles[m.name], m.pixels)["structure"] / STRUCTURE_TARGET for m in maps])
    ratio = lattice_ratio([tiles[m.name] for m in maps], [m.pixels for m in maps], lattice)
    if ratio is not None:
        score = max(score, (1 - ratio) / (1 - LATTICE_TARGET))
    verdict = judge_reading(Reading([tiles[m.name] for m in maps], reference.normals, reference.names, reference))
    score = max(score, verdict.strongest / verdict.margin)
    return score, bool(verdict.passed and (ratio is None or ratio >= LATTICE_TARGET)), ratio


def _cut_candidate(maps: list[MapInput], lattice: Lattice, H: int, W: int, notes: dict, seed: int):
    """The cut tile for this stack: whole lattice periods when it repeats and they fit (:mod:`.lattice.cut`),
    else one window of the source when the texture continues itself at the window's lags
    (:mod:`.lattice.window`; a window refused is recorded in ``notes["window_refused"]``), else source-sized
    tile quilted from QUILT_CELLS large source blocks (:mod:`.lattice.quilt`; of QUILT_TRIES seeds, the one
    whose worst join costs least; cuts by the blocks' difference: cuts along the texture's lines thickened
    and forked its joints and read worse on every figure, ``benchmarks/experiments/results/levers_quilt*.md``). Returns
    (kind, field (h, w, 2) of source texels, figures), or None."""
    pixels = [m.pixels for m in maps]
    if lattice.found:
        sizes = lattice_tile_size((H, W), lattice)
        if sizes is not None:
            field_, offset = lattice_cut(pixels, *sizes)
            return "lattice", field_, {"band": list(sizes[1]), "offset": list(offset)}
    sizes = window_tile_size(pixels)
    if sizes is not None:
        if continues_itself(sizes[2]):
            field_, offset = lattice_cut(pixels, sizes[0], sizes[1])
            return "window", field_, {"band": list(sizes[1]), "offset": list(offset), "lag_difference": sizes[2]}
        notes["window_refused"] = {"lag_difference": sizes[2], "most": WINDOW_MAX_DIFFERENCE}
    quilt = best_quilt(pixels, (H, W), QUILT_CELLS, QUILT_TRIES, seed)
    if quilt is None:
        return None
    keys = ("cells", "overlap", "blocks", "join_mean", "join_worst", "difference_worst")
    return "quilt", quilt[0], {k: quilt[1][k] for k in keys}


def _joins_hide(figures: dict) -> bool:
    """Whether a quilt's joins hide: the two blocks agree along every cut to within QUILT_MAX_DIFFERENCE
    (its ``difference_worst``). Where they do not, the verdict passed seamed quilts (two-tone stones, tone
    patches, stripes ending at a cut: ``benchmarks/experiments/results/quilt_gate.md``)."""
    return figures["difference_worst"] <= QUILT_MAX_DIFFERENCE


def _try_lattice(made: MadeTile, maps: list[MapInput], model, cut: bool, keep_alternatives: bool, seed: int = 0) -> None:
    """Measure the written tile against a tile cut from the source and, with ``cut``, keep the cut when it
    wins: the candidate that passes (the verdict: no seam, fidelity inside the source's tolerances; for a
    stack that repeats, the lattice ratio) before one that does not, then the lower score (see
    :func:`_judged`). A stack that repeats on a lattice is cut to whole periods
    (:func:`.lattice.lattice_cut`); any other that continues itself to one window of the source joined
    across its wraps (:mod:`.lattice.window`). The figures are taken on the source's grid, halved down
    to SCORE_SIDE; a stack that does neither gets a quilt (:mod:`.lattice.quilt`)."""
    H, W = made.grid_size
    lattice = find_lattice([m.pixels for m in maps])
    made.lattice = lattice.as_dict()
    candidate = _cut_candidate(maps, lattice, H, W, made.lattice, seed) if cut else None
    if not lattice.found and candidate is None:
        return
    halve = 2 ** max(0, math.ceil(math.log2(max(H, W) / SCORE_SIDE)))
    # the sources are halved with the tiles' filter (area), so the two autocorrelations compare
    half = (max(8, round(H / halve)), max(8, round(W / halve)))
    grid = [MapInput(m.name, _resized(m.pixels, half, m.is_normal, periodic=True), m.is_normal)
            for m in maps] if halve > 1 else maps
    grid_lattice = dataclasses.replace(lattice, period=tuple(None if p is None else p / halve for p in lattice.period))
    reference = Reference([m.pixels for m in grid], [m.is_normal for m in grid], [m.name for m in grid])
    current, current_passes, current_ratio = _judged(_on_grid(made.maps, maps, (1 / halve, 1 / halve)), grid,
                                                     grid_lattice, reference)
    kind = made.layout_kind
    made.lattice.update({f"q_passed_{kind}": made.q_passed, f"passes_{kind}": current_passes,
                         f"score_{kind}": round(current, 3)})
    if current_ratio is not None:
        made.lattice[f"lattice_ratio_{kind}"] = round(current_ratio, 3)
    if candidate is None:
        return
    cut_kind, field_, figures = candidate
    tiles = {m.name: np.ascontiguousarray(m.pixels[field_[..., 0], field_[..., 1]]) for m in maps}
    score, verdict_passes, ratio = _judged(_on_grid(tiles, maps, (1 / halve, 1 / halve)), grid, grid_lattice,
                                           reference)
    # the verdict misses joins like a quilt's that do not hide (benchmarks/experiments/results/quilt_gate.md)
    passes = verdict_passes and (cut_kind != "quilt" or _joins_hide(figures))
    tile_hw = next(iter(tiles.values())).shape[:2]
    q = judge(model, _on_grid(tiles, maps, (made.working_size[0] / H, made.working_size[1] / W)))
    wins = (not passes, score) < (not current_passes, current)
    if wins and cut_kind == "quilt" and not _joins_hide(figures):
        # written, it would be judged at full resolution: a quilt whose joins do not hide is written only
        # where that verdict sees them, never as a tile that passes (on a grid not halved, it was so judged)
        if halve > 1:
            verdict_passes = verdict_of([tiles[m.name] for m in maps], [m.pixels for m in maps],
                                        [m.is_normal for m in maps], [m.name for m in maps]).passed
        if verdict_passes:
            wins = False
            made.lattice["quilt_refused"] = {"difference_worst": figures["difference_worst"],
                                             "most": QUILT_MAX_DIFFERENCE}
    made.lattice.update({"cut": cut_kind, "tile": list(tile_hw), "q_passed": bool(q.passed), "passes": passes,
                         "score": round(score, 3), "chosen": wins, **figures})
    if ratio is not None:
        made.lattice["lattice_ratio"] = round(ratio, 3)
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
