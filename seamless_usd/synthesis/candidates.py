"""Tiles cut from the source (whole lattice periods, one window, a quilt of large blocks), and how every
candidate tile of a stack is weighed: the verdict, then a score, on the source's grid halved to SCORE_SIDE.

:func:`check_cut` makes and judges the cut before any training: when it passes, the stack needs no GAN
(:func:`.tile.make_tile`); when it does not, it is weighed against the refined tile (:func:`.tile._try_lattice`).
"""
from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from seamless_usd.metrics.structure import STRUCTURE_TARGET, structure_figures
from seamless_usd.verdict import Reading, Reference, judge, judge_reading

from .gan.seeds import fidelity_score
from .grid import on_grid, resized
from .lattice.cut import LATTICE_TARGET, Lattice, find_lattice, lattice_cut, lattice_ratio, lattice_tile_size
from .lattice.lines import has_thin_lines
from .lattice.mend import best_mend
from .lattice.quilt import best_quilt, line_mask, line_sigma
from .advice import QUILT_MAX_DIFFERENCE, WINDOW_MAX_DIFFERENCE, joins_hide
from .lattice.window import continues_itself, window_tile_size
from .types import SCORE_SIDE, MapInput, score_halving

__all__ = ["GAN_MIN_SIDE", "QUILT_CELLS", "QUILT_TRIES", "QUILT_MAX_DIFFERENCE", "SCORE_SIDE", "CutCheck", "check_cut", "judged",
           "cut_candidates", "joins_hide", "gated", "MEND_TRIES", "check_levelled", "check_evened",
           "passes_at_full_resolution", "best_cut"]

#: The smallest side (px) SeamlessGAN is trained on (its minimum crop, ``discover.tokens.MIN_CROP``): a smaller
#: stack gets the tile cut from its source only, passed or not.
GAN_MIN_SIDE = 100

#: Blocks (rows, columns) of a quilted tile (:mod:`.lattice.quilt`): the fewest that still let every block be
#: chosen to fit its neighbours; each block keeps a stone or a run of plank whole.
QUILT_CELLS = (2, 2)
#: Quilts tried (seeds) for a stack; the one whose worst join costs least is weighed.
QUILT_TRIES = 3

#: Mends tried (seeds) for a stack; the one whose worst join costs least is weighed.
MEND_TRIES = 3



def judged(tiles: dict[str, np.ndarray], maps: list[MapInput], lattice: Lattice, reference: Reference
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
    verdict = judge_reading(Reading([tiles[m.name] for m in maps], reference.normals, reference.names, reference,
                                    [m.code for m in maps]))
    score = max(score, verdict.strongest / verdict.margin)
    return score, bool(verdict.passed and (ratio is None or ratio >= LATTICE_TARGET)), ratio


def passes_at_full_resolution(tiles: dict[str, np.ndarray], maps: list[MapInput], ratio: float | None) -> bool:
    """Whether a candidate tile passes as :func:`judged` decides, with the verdict read at full resolution (a
    tile of copies at odd offsets is no longer copies on a halved grid, see :func:`check_cut`)."""
    verdict = judge([tiles[m.name] for m in maps], [m.pixels for m in maps], [m.is_normal for m in maps],
                    [m.name for m in maps], codes=[m.code for m in maps])
    return bool(verdict.passed and (ratio is None or ratio >= LATTICE_TARGET))


def cut_candidates(maps: list[MapInput], lattice: Lattice, H: int, W: int, notes: dict, seed: int):
    """The tiles cut from this stack's source, cheapest and most faithful first, each as (kind, field (h, w, 2) of
    source texels, figures), made one at a time as they are asked for:

    - whole lattice periods when the stack repeats and they fit (:mod:`.lattice.cut`), and nothing else: the
      other cuts join copies at any phase, and on a drifting repeat a quilt that passed the verdict measured
      three periods where the source has one;
    - one window of the source when the texture continues itself at the window's lags (:mod:`.lattice.window`;
      a window refused is recorded in ``notes["window_refused"]``);
    - the source kept whole, rolled by half, with a band over its seams re-laid from itself (:mod:`.lattice.mend`;
      of MEND_TRIES seeds, the one whose worst join costs least);
    - a source-sized tile quilted from QUILT_CELLS large source blocks (:mod:`.lattice.quilt`; of QUILT_TRIES
      seeds, the one whose worst join costs least; cuts by the blocks' difference: cuts along the texture's
      lines thickened and forked its joints and read worse on every figure,
      ``benchmarks/experiments/results/levers_quilt*.md``)."""
    pixels = [m.pixels for m in maps]
    if lattice.found:
        sizes = lattice_tile_size((H, W), lattice)
        if sizes is not None:
            differences: dict = {}
            field_, offset = lattice_cut(pixels, *sizes, differences=differences)
            figures = {"band": list(sizes[1]), "offset": list(offset), "difference": differences}
            open_axes = [axis for axis, period in zip("yx", lattice.period) if period is None]
            if open_axes:  # its wrap there joins unrelated rows (columns), as a window's: gated (see gated)
                figures.update(open_axes=open_axes, difference_worst=max(differences[a] for a in open_axes))
            yield "lattice", field_, figures
            return  # any other cut breaks the repeat's phase at its joins
    sizes = window_tile_size(pixels)
    if sizes is not None:
        if continues_itself(sizes[2]):
            field_, offset = lattice_cut(pixels, sizes[0], sizes[1])
            yield "window", field_, {"band": list(sizes[1]), "offset": list(offset), "lag_difference": sizes[2]}
        else:
            notes["window_refused"] = {"lag_difference": sizes[2], "most": WINDOW_MAX_DIFFERENCE}
    mend = best_mend(pixels, MEND_TRIES, seed)
    if mend is not None:
        keys = ("band", "segment", "blocks", "join_mean", "join_worst", "difference_worst")
        overlap = mend[1]["band"][1]
        lines = line_mask(pixels, line_sigma((overlap, overlap))) is not None or has_thin_lines(pixels)
        yield "mend", mend[0], {**{k: mend[1][k] for k in keys}, "lines": lines}
    quilt = best_quilt(pixels, (H, W), QUILT_CELLS, QUILT_TRIES, seed)
    if quilt is not None:
        keys = ("cells", "overlap", "blocks", "join_mean", "join_worst", "difference_worst")
        yield "quilt", quilt[0], {k: quilt[1][k] for k in keys}


def gated(kind: str | None, figures: dict) -> bool:
    """Whether a cut of ``kind`` passes only where its joins hide (:func:`joins_hide`), not on the verdict alone:
    a quilt, and a mend of a texture with long lines (``figures["lines"]``: joints, plank gaps, stripes, as broad
    as :func:`.lattice.quilt.line_mask` sees them or as thin as :func:`.lattice.lines.has_thin_lines` does). A mend
    of a texture without them has no such gate: on real photos its worst difference does not tell the seamless
    from the seamed (bark and grass mends seamless at 0.37, a veneer's seamed at 0.27; docs/decisions.md,
    "Keep and mend").

    A lattice cut of a stack that repeats along one axis only is gated too (``figures["open_axes"]``): its wrap
    along the other axis joins two unrelated rows (or columns), as a window's does, and a window is offered only
    where such joins hide. The verdict passed a brick pavement's lattice cut whose courses break at that wrap
    (strongest 0.86 against 0.90; docs/verdict.md, "Known false passes"), and its cut's difference reads 0.21;
    a concrete-tile facade's, seamless by eye, reads 0.04."""
    return (kind == "quilt" or (kind == "mend" and bool(figures.get("lines")))
            or (kind == "lattice" and bool(figures.get("open_axes"))))


@dataclass
class CutCheck:
    """The stack's lattice, its cut (if any) and how the cut is judged, on the source's grid halved ``halve``
    times to at most SCORE_SIDE; ``reference`` is that grid prepared for the verdict once for every candidate."""

    lattice: Lattice
    notes: dict  # lattice.as_dict(), and why a window was refused
    halve: int
    grid: list[MapInput]
    grid_lattice: Lattice
    reference: Reference
    kind: str | None = None  # "lattice", "window", "mend" or "quilt"; None: no cut
    tiles: dict[str, np.ndarray] = field(default_factory=dict)  # the cut at full resolution
    figures: dict = field(default_factory=dict)  # the cut's own figures (band, offset, joins)
    score: float = math.inf
    verdict_passes: bool = False
    ratio: float | None = None

    @property
    def passes(self) -> bool:
        """The verdict passes the cut and, for a quilt or a mend of a texture with long lines (:func:`gated`), its
        joins hide (the verdict misses joins like a quilt's that do not:
        ``benchmarks/experiments/results/quilt_gate.md``)."""
        hide = not gated(self.kind, self.figures) or joins_hide(self.figures)
        return self.kind is not None and self.verdict_passes and hide


def check_cut(maps: list[MapInput], cut: bool, seed: int = 0) -> CutCheck:
    """Find the stack's lattice and, with ``cut``, make the tiles cut from its source (:func:`cut_candidates`) one
    after another and judge each: the first that passes is the stack's cut, else the one that scores best.
    Each is scored on the source's grid halved to SCORE_SIDE; where that grid is halved, whether it passes is
    the verdict's at full resolution, as the written tile's will be: a cut whose copies lie at odd offsets is
    no longer copies once halved, and a 1536 px cobblestone mend that passes at full resolution read twelve
    seams on its 768 px grid (the cliff's passed there and shows a step of tone at full resolution).
    ``notes["candidates"]`` records each one tried, with whether it passed (``passes_on_grid``: the halved
    grid's verdict, where it was read) and its score."""
    H, W = maps[0].pixels.shape[:2]
    lattice = find_lattice([m.pixels for m in maps])
    notes = lattice.as_dict()
    halve = score_halving(H, W)
    # the sources are halved with the tiles' filter (area), so the two autocorrelations compare
    half = (max(8, round(H / halve)), max(8, round(W / halve)))
    grid = [dataclasses.replace(m, pixels=resized(m.pixels, half, m.is_normal, periodic=True))
            for m in maps] if halve > 1 else maps
    grid_lattice = dataclasses.replace(lattice, period=tuple(None if p is None else p / halve for p in lattice.period))
    reference = Reference([m.pixels for m in grid], [m.is_normal for m in grid], [m.name for m in grid])
    best = CutCheck(lattice, notes, halve, grid, grid_lattice, reference)
    tried = []
    for kind, field_, figures in (cut_candidates(maps, lattice, H, W, notes, seed) if cut else ()):
        check = dataclasses.replace(best, kind=kind, figures=figures)
        check.tiles = {m.name: np.ascontiguousarray(m.pixels[field_[..., 0], field_[..., 1]]) for m in maps}
        check.score, check.verdict_passes, check.ratio = judged(
            on_grid(check.tiles, maps, (1 / halve, 1 / halve)), grid, grid_lattice, reference)
        on_grid_passes = None
        if halve > 1:  # the verdict that decides is the full resolution's, as the written tile's will be
            on_grid_passes = check.verdict_passes
            check.verdict_passes = passes_at_full_resolution(check.tiles, maps, check.ratio)
        tried.append({"kind": kind, "passes": check.passes, "score": round(check.score, 3),
                      **({} if on_grid_passes is None else {"passes_on_grid": on_grid_passes})})
        if best.kind is None or (not check.passes, check.score) < (not best.passes, best.score):
            best = check
        if check.passes:
            break
    if len(tried) > 1 or halve > 1:
        notes["candidates"] = tried
    return best


def _check_made(maps: list[MapInput], values: list[np.ndarray], facts: dict, seed: int) -> tuple[CutCheck, dict] | None:
    """(cut, facts) of the cuts made of ``maps`` holding ``values`` (the maps made anew, texels moved or scaled) when
    one passes, judged against those values; None when none does, or nothing was moved (``facts["moved"]``)."""
    if not facts["moved"]:
        return None
    made = [dataclasses.replace(m, pixels=v) for m, v in zip(maps, values)]
    cut = check_cut(made, True, seed)
    return (cut, facts) if cut.passes else None


def check_levelled(maps: list[MapInput], seed: int = 0) -> tuple[CutCheck, dict] | None:
    """(cut, facts) of the cuts made of ``maps`` with their light levelled (:func:`.imaging.level.level_maps`) when
    one passes, judged against the levelled maps; None when none does, or the light is already even.

    Copies of a photo lit unevenly meet in a step of tone that no cut hides (the rusty panel, a stone wall, a
    bowl of chopped tomatoes: ``docs/decisions.md``, "Levelling a photo's light"); levelled, every texel keeps
    its place and the cut is still made of copies, so the verdict judges its joins as any other cut's."""
    from seamless_usd.imaging.level import level_maps

    return _check_made(maps, *level_maps([m.pixels for m in maps], [m.is_normal for m in maps]), seed)


def check_evened(maps: list[MapInput], lattice: Lattice, seed: int = 0) -> tuple[CutCheck, dict] | None:
    """(cut, facts) of the cuts made of ``maps`` resampled so that their ``lattice`` repeats evenly
    (:func:`.lattice.drift.even_lattice`) when one passes, judged against the evened maps; None when none does,
    nothing repeats, or the lattice does not drift (or drifts more than that reading is trusted with).

    Where a photo's lattice drifts a texel or two, a cut of whole periods jogs every joint that crosses its wrap
    (a tiled floor: ``docs/decisions.md``, "Evening a drifting lattice"); evened, the cut is made of copies of
    the evened maps, and the verdict judges its joins as any other cut's."""
    if not lattice.found:
        return None
    from .lattice.drift import even_lattice

    return _check_made(maps, *even_lattice([m.pixels for m in maps], [m.is_normal for m in maps], lattice), seed)


def best_cut(maps: list[MapInput], cut: bool, seed: int = 0, timings: dict[str, float] | None = None,
             stage: Callable[[str], None] | None = None) -> tuple[CutCheck, dict]:
    """(cut, made): :func:`check_cut`, and where its cut does not pass (``cut``: cuts are made), the cut of the
    maps with their light levelled when that one passes (:func:`check_levelled`), else the cut of the maps with
    their lattice evened (:func:`check_evened`). ``made``: ``{"levelled": facts}`` or ``{"evened": facts}`` for
    the cut that passed so, empty when the cut is of the maps as they are. ``timings`` gets the seconds of each
    (``"lattice"``, ``"level"``, ``"even"``); ``stage`` is told each as it starts (minutes each on a 4K stack)."""
    timings = {} if timings is None else timings
    stage = stage or (lambda what: None)
    t0 = time.perf_counter()
    stage("cutting tiles from the source" if cut else "finding the source's lattice")
    check = check_cut(maps, cut, seed)
    timings["lattice"] = time.perf_counter() - t0
    if not cut or check.passes:
        return check, {}
    for key, name, attempt in (("level", "levelled", lambda: check_levelled(maps, seed)),
                               ("even", "evened", lambda: check_evened(maps, check.lattice, seed))):
        stage(f"cutting tiles from the source with its {'light levelled' if key == 'level' else 'lattice evened'}")
        t1 = time.perf_counter()
        made = attempt()
        timings[key] = time.perf_counter() - t1
        if made is not None:
            return made[0], {name: made[1]}
    return check, {}
