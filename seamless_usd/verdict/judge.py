"""The verdict on a tile: seamless (no seam at its wrap or inside) and faithful to its source.

``passed`` means exactly this, everywhere in the product (the status, the exit code, the report, the
USD provenance and ``seamless-usd check``):

* **seamless**: no line of the tile, read as it repeats (the wrap lines, the centre lines and every
  interior line), is a join the texture would not make, for the maps together and for each map. A
  tile made of the source's own texels (refined, lattice-cut, or a window used as its tile, with or
  without a blended band at its joins) is judged by the continuation error at its joins
  (:mod:`.copies`), and by its broad steps of tone against the source's strongest (:mod:`.tone`: copies of a
  photo lit unevenly); any other tile (the GAN's own, a crossfade) by a
  classifier fitted on the source's own juxtapositions (:mod:`.classifier`): a run of 64
  working-resolution px scoring more than :data:`SEAM_MARGIN` above the strongest run of the source's
  own lines is a seam;
* **faithful**: every map's feature-scale ratio and patch distance against its source lie inside
  tolerances set by the source's own spread (:mod:`.tolerance`). A figure that could not be measured
  (a tile too small) is not inside its tolerance.

A texture with no separate source (``seamless-usd check`` on a picture or a stack, and the scan deciding
whether a stack is already tileable, both reading its files through :mod:`seamless_usd.discover.alone`) is
judged against itself, by three rules whose seams are added: the classifier fitted on its own interior lines,
with its own 4th-strongest line (:data:`SELF_RANK`) as the reference; and each line's breaks at every lag
against all the texture's parallel lines (:mod:`.breaks`), and the line across which the rows predict each other
least against the next such line (:mod:`.across`), reported on the same scale (a seam above
:data:`SELF_MARGIN`). There is no fidelity to judge.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..memo import ContentMemo
from .across import unrelated_lines
from .breaks import line_breaks, working
from .classifier import SeamClassifier, fit
from .ghosts import ghost_bands
from .copies import (COPY_SHARE, COPY_THRESHOLD, EXACT_SHARE, INFER, MAP_THRESHOLD, SourceIndex, copy_origins,
                     copy_seams, sampled_share)
from .lines import Seam, runs, seams_from_scores
from .prepare import WORK_SIDE, joint, map_weights, to_working
from .visibility import visible
from .reference import Reading, Reference
from .tolerance import faithfulness
from .tone import tone_steps

__all__ = ["SEAM_MARGIN", "SELF_MARGIN", "LENGTH", "STEP", "Verdict", "judge", "judge_reading"]

#: A stack whose maps together are found in their source on at least this share of their texels, but not on
#: :data:`.copies.EXACT_SHARE`, is looked up map by map (:func:`_copied_each`); a tile of new pixels finds almost
#: none, and looking each map up costs 1.6 s at 2K.
SOME_COPIES = 0.05
#: Run (texels at full resolution) over which a copied tile's continuation error is averaged.
COPY_RUN = 32
#: Length (px at the working resolution) of a line stretch, and the step between stretches.
LENGTH = 16
STEP = 4
#: A run scoring more than this above the source's strongest run is a seam (classifier units).
SEAM_MARGIN = 0.5
#: Judged against itself: a run more than this above the texture's own :data:`SELF_RANK`-th strongest line is
#: a seam. A texture's own lines (mortar joints, plank edges) come many alike, so the reference sits among
#: them; a join is one line (a wrap) or two (a spliced strip), which stand above it.
SELF_MARGIN = 1.0
SELF_RANK = 4


@dataclass
class Verdict:
    """Whether a tile is seamless and faithful, with where its seams are and its figures."""

    seamless: bool
    faithful: bool
    seams: list[Seam] = field(default_factory=list)  # strongest first; map "stack" is the maps together
    strongest: float = 0.0  # the strongest run above the reference (seams exceed ``margin``)
    margin: float = SEAM_MARGIN
    reference: str = "source"  # "source", or "itself" for a texture judged on its own
    method: str = "classifier"  # "copies": a tile of source texels, judged by continuation error; else "classifier"
    size: tuple[int, int] = (0, 0)  # (h, w) of the tile judged
    figures: dict[str, dict[str, float | None]] = field(default_factory=dict)  # map -> figure -> value
    tolerances: dict[str, dict[str, list]] = field(default_factory=dict)  # map -> figure -> [low, high]
    failing: list[str] = field(default_factory=list)  # "map: figure value (tolerance ...)"

    @property
    def passed(self) -> bool:
        """Seamless and faithful: the one meaning of ``passed``."""
        return self.seamless and self.faithful

    def reasons(self, most: int = 3) -> list[str]:
        """Why the tile did not pass: its ``most`` strongest seams, then each figure outside its tolerance."""
        out = [f"seam in {'the maps together' if s.map == 'stack' else s.map}: {s.where(self.size)} "
               f"({s.above})" for s in self.seams[:most]]
        if len(self.seams) > most:
            out.append(f"and {len(self.seams) - most} more seam{'s' if len(self.seams) - most > 1 else ''}")
        return out + [f"not faithful: {f}" for f in self.failing]

    def as_dict(self) -> dict:
        return {"passed": self.passed, "seamless": self.seamless, "faithful": self.faithful,
                "reference": self.reference, "method": self.method, "strongest": round(self.strongest, 3), "margin": self.margin,
                "size": list(self.size), "seams": [s.as_dict() for s in self.seams],
                "figures": self.figures, "tolerances": self.tolerances, "failing": list(self.failing)}

    @classmethod
    def from_dict(cls, d: dict) -> "Verdict":
        return cls(bool(d["seamless"]), bool(d["faithful"]), [Seam(**s) for s in d.get("seams", [])],
                   float(d.get("strongest", 0.0)), float(d.get("margin", SEAM_MARGIN)), d.get("reference", "source"),
                   d.get("method", "classifier"), tuple(d.get("size", (0, 0))), dict(d.get("figures", {})),
                   dict(d.get("tolerances", {})), list(d.get("failing", [])))


def _copied(reading: Reading) -> tuple[list[Seam], float] | None:
    """Seams of a tile made of the source's own texels (:mod:`.copies`), for the maps together and each map;
    None when fewer than :data:`.copies.EXACT_SHARE` of its texels are found in the source, or fewer than
    :data:`.copies.COPY_SHARE` found or inferred beside found ones (a blended band)."""
    ref = reading.reference
    origin, share = reading.origins
    if share < EXACT_SHARE or (origin[..., 0] >= 0).mean() < COPY_SHARE:
        # some copies of the stack's places, not enough: maps cut again one by one? (the GAN's pixels: none found)
        return _copied_each(reading) if share >= SOME_COPIES else None
    seams, strongest = copy_seams(reading.joint, ref.joint, origin, "stack", COPY_RUN, units=ref.units())
    if len(reading.maps) > 1:
        for k, (tile, source, name) in enumerate(zip(reading.maps, ref.maps, reading.names)):
            # one map's own copy at a time: gathers from it are faster
            found, _ = copy_seams(np.ascontiguousarray(tile), np.ascontiguousarray(source), origin, name, COPY_RUN,
                                  MAP_THRESHOLD, units=ref.units(k))
            seams += found
    seams.sort(key=lambda x: -x.figure)
    return seams, strongest


def _copied_each(reading: Reading) -> tuple[list[Seam], float] | None:
    """Seams of a stack whose maps are each made of their source's texels but not from the same places (one map of a
    written stack cut or moved again on its own): each map judged as copies of its own source, its seams named by
    map; None when any map is not made of copies (:func:`_copied`'s shares), or the stack has one map. Such a stack
    used to fall to the classifier, which passed an albedo whose right half had been slid down 50 rows (its mortar
    broken at 1x)."""
    if len(reading.maps) < 2:
        return None
    ref = reading.reference
    placed = []
    for tile, source in zip(reading.maps, ref.maps):
        tile, source = np.ascontiguousarray(tile), np.ascontiguousarray(source)
        index = SourceIndex(source)
        if sampled_share(tile, index) < EXACT_SHARE / 2:  # new pixels (the GAN's): 0.1 s at 2K, not 9
            return None
        origin, share = copy_origins(tile, source, INFER, index)
        if share < EXACT_SHARE or (origin[..., 0] >= 0).mean() < COPY_SHARE:
            return None
        placed.append((tile, source, origin))
    seams: list[Seam] = []
    strongest = 0.0
    for k, ((tile, source, origin), name) in enumerate(zip(placed, reading.names)):
        found, top = copy_seams(tile, source, origin, name, COPY_RUN, MAP_THRESHOLD, units=ref.units(k))
        seams += found
        strongest = max(strongest, top * COPY_THRESHOLD / MAP_THRESHOLD)  # on the maps-together scale
    seams.sort(key=lambda x: -x.figure)
    return seams, strongest


def _tone_seams(reading: Reading) -> list[Seam]:
    """Broad tone steps of a tile made of its source's copies (:mod:`.tone`), the maps together. Only there: away
    from its joins such a tile's strip steps are the source's own, so the source's strongest is a tight
    reference; a tile of new pixels (noise drawn again, the GAN's) has strip steps of its own, whose strongest
    reads 1.1-1.75 times the source's on seamless noise (``docs/decisions.md``, "A broad tone step rule")."""
    factor = min(1.0, WORK_SIDE / max(reading.size))
    weights, reference = reading.reference.tone(factor)
    tile = joint(to_working(reading.maps, factor, periodic=True), weights)
    return tone_steps(tile, reference, factor, reading.size)


def _scores(clf, img: np.ndarray, periodic: bool) -> dict[str, np.ndarray]:
    return {axis: clf.scores(img, axis, periodic) for axis in ("x", "y")}


def _strongest_run(scores: dict[str, np.ndarray], periodic: bool, rank: int = 1) -> float:
    """The ``rank``-th strongest line's best run, lines within 4 px of a stronger one left out."""
    ranked = []
    for z in scores.values():
        peak = runs(z, periodic=periodic).max(axis=0)
        taken: list[int] = []
        for line in np.argsort(-peak):
            if len(taken) >= rank:
                break
            if all(min(abs(line - t), len(peak) - abs(line - t)) > 4 for t in taken):
                taken.append(int(line))
        ranked += [float(peak[t]) for t in taken]
    ranked.sort(reverse=True)
    return ranked[min(rank, len(ranked)) - 1]


#: Calibrations (fitted classifier, reference run) kept by the content of the image they were fitted on:
#: a batch judges the same source many times, and the fit is the verdict's dearest part on small maps. A fit is a
#: few kilobytes; 512 of them cover ``check`` on a library stage after its scan judged every stack once.
_CALIBRATIONS: ContentMemo[tuple[SeamClassifier, float]] = ContentMemo(keep=512)


def _calibration(image: np.ndarray, itself: bool, seed: int) -> tuple[SeamClassifier, float]:
    """The classifier fitted on ``image`` (its lines read without wrapping) and the reference run: for a
    texture judged on itself, its :data:`SELF_RANK`-th strongest line read as it repeats; else the source's
    strongest run."""
    def compute() -> tuple[SeamClassifier, float]:
        clf = fit(image, LENGTH, STEP, seed=seed)
        if itself:
            return clf, _strongest_run(_scores(clf, image, True), True, SELF_RANK)
        return clf, _strongest_run(_scores(clf, image, False), False)

    return _CALIBRATIONS.get((image,), (itself, seed, LENGTH, STEP), compute)


def _find(tile: np.ndarray, source: np.ndarray | None, factor: float, size: tuple[int, int], name: str, seed: int
          ) -> tuple[list[Seam], float]:
    clf, reference = _calibration(tile if source is None else source, source is None, seed)
    margin = SELF_MARGIN if source is None else SEAM_MARGIN
    return seams_from_scores(_scores(clf, tile, True), reference, margin, factor=factor, tile_shape=size,
                             length=LENGTH, step=STEP, map_name=name)


def _near(seam: Seam, others: list[Seam]) -> bool:
    """Whether one of ``others`` in the same map runs along the same line (within 4 texels) as ``seam``."""
    return any(o.map == seam.map and o.axis == seam.axis and abs(o.position - seam.position) <= 4 for o in others)


def judge(tiles: list[np.ndarray], sources: list[np.ndarray] | None, normals: list[bool], names: list[str],
          *, fidelity: bool = True, seed: int = 0, codes: list[float] | None = None) -> Verdict:
    """The verdict on a periodic tile (one or more maps, network domain ``[-1, 1]``) against ``sources``
    (the same maps at the tile's texel scale; None: judged against itself). To judge several tiles against
    one source, or to read the same tile's join figures too, prepare them once and use :func:`judge_reading`.
    ``codes``: each map's code value in network units (:attr:`.reference.Reading.codes`; 8-bit where not given).

    >>> rng = np.random.default_rng(0)
    >>> noise = rng.normal(size=(96, 96, 1))
    >>> judge([noise], None, [False], ["noise"]).seamless
    True
    """
    reference = None if sources is None else Reference(sources, normals, names, keep_index=False)
    return judge_reading(Reading(tiles, normals, names, reference, codes), fidelity=fidelity, seed=seed)


def _seen(seams: list[Seam], strongest: float, margin: float, reading: Reading, work: list[np.ndarray] | None
          ) -> tuple[list[Seam], float]:
    """The seams whose step can be seen (:mod:`.visibility`), strongest first, and the strongest figure: where every
    line found is too faint to see (a nearly flat map), at most the margin. ``work``: the maps at the working size,
    when at hand."""
    if not seams:
        return seams, strongest
    factor = min(1.0, WORK_SIDE / max(reading.size))
    maps = work if work is not None else to_working(reading.maps, factor, periodic=True)
    kept = sorted(visible(seams, maps, reading.names, factor, reading.codes), key=lambda x: -x.figure)
    if not kept:
        strongest = min(strongest, margin)
    return kept, strongest


def judge_reading(reading: Reading, *, fidelity: bool = True, seed: int = 0) -> Verdict:
    """:func:`judge` on a tile already prepared (:class:`.reference.Reading`), against its reference if it has one."""
    ref = reading.reference
    t, size = reading.maps, reading.size
    if ref is not None:
        copied = _copied(reading)
        if copied is not None:
            seams, strongest = copied
            seams, strongest = _seen(seams + _tone_seams(reading), strongest, COPY_THRESHOLD, reading, None)
            verdict = Verdict(not seams, True, seams, strongest, COPY_THRESHOLD, "source", "copies", size)
            if fidelity:
                verdict.figures, verdict.tolerances, verdict.failing = faithfulness(
                    reading.tiles, ref.sources, reading.normals, reading.names)
                verdict.faithful = not verdict.failing
            return verdict
    factor = min(1.0, WORK_SIDE / max(size))
    tw = to_working(t, factor, periodic=True)
    sw = None if ref is None else to_working(ref.maps, factor, periodic=False)
    weights = map_weights(sw if sw is not None else tw)
    margin = SEAM_MARGIN if ref is not None else SELF_MARGIN
    tile_joint, source_joint = joint(tw, weights), None if sw is None else joint(sw, weights)
    seams, strongest = _find(tile_joint, source_joint, factor, size, "stack", seed)
    if source_joint is not None:  # against a source: bands where the tile's detail fades (a crossfade)
        found, top = ghost_bands(tile_joint, source_joint, factor, size, margin)
        seams += found
        strongest = max(strongest, top)
    if len(t) > 1:
        for k, name in enumerate(reading.names):
            found, top = _find(tw[k] * weights[k], None if sw is None else sw[k] * weights[k], factor, size, name,
                               seed)
            seams += found
            strongest = max(strongest, top)
    if ref is None:
        work = working(reading.maps)  # both rules read the maps at the line breaks' working size
        found, top = line_breaks(reading.maps, reading.names, SELF_MARGIN, work)
        unrelated, top_across = unrelated_lines(reading.maps, SELF_MARGIN, work)
        found += unrelated
        strongest = max(strongest, top, top_across)
        kept: list[Seam] = []
        for s in sorted(seams + found, key=lambda x: -x.figure):  # one line found by both: its stronger figure
            if not _near(s, kept):
                kept.append(s)
        seams = kept
    seams, strongest = _seen(seams, strongest, margin, reading, tw)
    verdict = Verdict(not seams, True, seams, strongest, margin, "source" if ref is not None else "itself",
                      "classifier", size)
    if fidelity and ref is not None:
        verdict.figures, verdict.tolerances, verdict.failing = faithfulness(reading.tiles, ref.sources,
                                                                            reading.normals, reading.names)
        verdict.faithful = not verdict.failing
    return verdict
