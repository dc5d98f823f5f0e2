"""Tiling intent of a texture stack, decided before any training: is the texture meant to repeat?

Most textures of a real scene are not meant to tile (UV atlases of props and characters, decals),
and some that are already tile. Each stack gets one class, with the measured reason:

- ``other``: a clamped / decal / mirrored use (``wrapS``/``wrapT`` ``clamp``, ``black``,
  ``mirror``; MaterialX ``clamp``, ``constant``, ``mirror``);
- ``tiling``: an existing UV transform or ``uvtiling`` repeats the texture; or the UVs of the
  bound geometry span more than one period; or every UV island shows the whole texture once
  (a swatch quad, box faces); or no geometry binds it under any explored variant selection (a
  library material) and its pixels do not look like an atlas;
- ``uv-atlas``: the bound meshes keep their UVs inside one period, as unwrapped islands (bindings
  and UVs read under the variant selection they are authored in, see ``bound.py``);
- ``uv-atlas (pixels)``: nothing binds it, but its pixels show an atlas's layout (islands on a
  flat background; see ``atlas.py``): flagged for review, processed only when forced;
- ``already-tileable``: a would-be *tiling* stack whose every map is already seamless across its
  wrap-around, measured on the pixels (decoded at most 512 px, reduced with bins that keep the
  wrap-around exact), *and* has no seam anywhere inside: the verdict (:mod:`seamless_usd.verdict`),
  judging the maps against themselves, finds no line unlike the texture's own (a spliced strip or
  a clone-stamped near-tile is processed, its reason naming where the seam is).

Thresholds come from measurements on real files, recorded in ``tests/test_intent_classify.py``:
periodic-plus-smooth score (Moisan) of the MaterialX example maps that tile (wood colour 0.044,
wood roughness 0.049, brick mask 0.037, brick roughness 0.019 at 512 px) against off-grid
windows of the same images and the bundled non-tiling samples (0.105 .. 0.808, the lowest a
brick normal window). Brick colour and brick normal, though periodic, score 0.127 and 0.346
at 512 px (a low-frequency shading gradient): they are classed *tiling*, the safe side.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import Enum

import numpy as np

from seamless_usd.discover.atlas import atlas_evidence
from seamless_usd.discover.triagememo import TriageMemo
from seamless_usd.textures import TextureMap, TextureStack

__all__ = ["Intent", "IntentDecision", "Thresholds", "classify_stacks", "measure_map", "THRESHOLDS"]


class Intent(str, Enum):
    TILING = "tiling"
    UV_ATLAS = "uv-atlas"
    UV_ATLAS_PIXELS = "uv-atlas (pixels)"  # nothing binds it, but its pixels are an unwrapped atlas's
    ALREADY_TILEABLE = "already-tileable"
    OTHER = "other"


@dataclass(frozen=True)
class IntentDecision:
    intent: Intent
    reason: str


@dataclass(frozen=True)
class Thresholds:
    """Decision limits, each chosen from measured figures (see the module notes)."""

    repeat_span: float = 1.02  # UVs (after existing transforms) spanning more than this many periods repeat
    repeat_factor: float = 1.01  # an existing transform scaling UVs by more than this repeats the texture
    ps_max: float = 0.075  # periodic-plus-smooth score at most this: seamless (tiling 0.019-0.049, not 0.105+)
    seam_max: float = 2.0  # and worst wrap-around seam ratio at most this (tiling 0.48-1.45, windows 1.36-74)
    measure_size: int = 512  # longest side the pixels are reduced to before measuring
    measure_max_pixels: int = 1 << 26  # larger files are not decoded for the measure (left "tiling")


THRESHOLDS = Thresholds()

_CLAMPED = frozenset({"clamp", "black", "mirror", "constant"})


def _repeat_factor(stack: TextureStack) -> tuple[tuple[float, float], list[str]]:
    """How many times existing UV transforms repeat the texture per axis, and their description."""
    fu = fv = 1.0
    parts = []
    for t in stack.uv.transforms:
        su, sv = abs(t.scale[0]) or 1.0, abs(t.scale[1]) or 1.0
        if t.kind == "place2d":  # MaterialX place2d divides texture coordinates by its scale
            su, sv = 1.0 / su, 1.0 / sv
        fu, fv = fu * su, fv * sv
        parts.append(f"{t.kind} {t.scale[0]:g}x{t.scale[1]:g}")
    return (fu, fv), parts


def _reduce(a: np.ndarray, size: int) -> np.ndarray:
    """Mean over near-equal bins covering the whole image: a periodic image stays periodic."""
    for axis in (0, 1):
        n = a.shape[axis]
        k = min(size, n)
        edges = np.round(np.linspace(0, n, k + 1)).astype(int)
        counts = np.diff(edges)
        shape = [1] * a.ndim
        shape[axis] = -1
        a = np.add.reduceat(a, edges[:-1], axis=axis) / counts.reshape(shape)
    return a


def measure_map(m: TextureMap, thresholds: Thresholds = THRESHOLDS) -> tuple[float, float] | None:
    """(periodic-plus-smooth score, worst wrap-around seam ratio) of the channels ``m`` uses,
    or None when the file is not measured (in a package, too large, unreadable, non-finite)."""
    if not m.resolved or m.in_package or m.image is None:
        return None
    if m.image.width * m.image.height > thresholds.measure_max_pixels:
        return None
    try:
        return _measure(m, thresholds)
    except (ValueError, RuntimeError, OSError):  # a file imaging will report on: not measured here
        return None


def _measure(m: TextureMap, thresholds: Thresholds) -> tuple[float, float] | None:
    from seamless_usd.metrics import ps_score, seam_ratios

    pixels = measured_pixels(m, thresholds)
    if pixels is None:
        return None
    if float(np.ptp(pixels)) == 0.0:
        return 0.0, 1.0  # a constant map repeats seamlessly
    seams = seam_ratios(pixels)
    seam = max(seams["seam_ratio_x"], seams["seam_ratio_y"])
    return float(ps_score(pixels)), float(seam if np.isfinite(seam) else 0.0)


def measured_pixels(m: TextureMap, thresholds: Thresholds = THRESHOLDS) -> np.ndarray | None:
    """The channels ``m`` uses, reduced to at most ``measure_size`` px with bins that keep the wrap exact
    (file values, float64), or None when the file cannot be decoded or has non-finite texels."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(m.resolved)
    if inp is None:
        return None
    try:
        level = 0
        while inp.seek_subimage(0, level + 1) and max(inp.spec().width, inp.spec().height) >= thresholds.measure_size:
            level += 1  # a MIP level still at least the measuring size: cheaper to decode
        inp.seek_subimage(0, level)
        pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, oiio.FLOAT)
    finally:
        inp.close()
    if pixels is None:
        return None
    pixels = np.asarray(pixels, dtype=np.float64)
    pixels = pixels.reshape(pixels.shape[0], pixels.shape[1], -1)
    if not np.isfinite(pixels).all():
        return None  # NaN / inf texels: no wrap-around measure (imaging reports them)
    channels = [i for i, c in enumerate("rgba") if c in m.channels_used and i < pixels.shape[2]]
    return _reduce(pixels[..., channels or [0]], thresholds.measure_size)


def interior_seam(stack: TextureStack, thresholds: Thresholds = THRESHOLDS) -> str | None:
    """Where the verdict, judging the stack's maps against themselves, finds a seam (None: none found,
    or the pixels could not be read, in which case the wrap figures alone decide)."""
    from seamless_usd.verdict import judge

    maps, shapes = [], set()
    for m in stack.maps:
        px = measured_pixels(m, thresholds) if m.resolved and not m.in_package and m.image is not None else None
        if px is None or min(px.shape[:2]) < 32:
            return None
        maps.append(px)
        shapes.add(px.shape[:2])
    if len(shapes) > 1:  # maps of different sizes: judge each alone
        verdicts = [judge([p], None, [False], [m.asset], fidelity=False) for p, m in zip(maps, stack.maps)]
    else:
        verdicts = [judge(maps, None, [False] * len(maps), [m.asset for m in stack.maps], fidelity=False)]
    for v in verdicts:
        if v.seams:
            s = v.seams[0]
            return f"{'@' + s.map + '@' if s.map != 'stack' else 'the maps together'}: {s.where(v.size)}"
    return None


def _in(stats) -> str:
    """`` in shadingVariant=White`` when the binding was found under another variant selection."""
    return f" in {stats.selection}" if getattr(stats, "selection", "") else ""


def _unbound(explored: int) -> str:
    if explored > 1:
        return f"no bound geometry in any of the {explored} variant selections explored (a library material)"
    if explored == 1:
        return "no bound geometry on the stage, which has no variants to explore (a library material)"
    return "no bound geometry: a MaterialX document scanned on its own (a library material)"


def _geometry_decision(stack: TextureStack, factor, stats, bound: int, explored: int = 1) -> IntentDecision:
    """Tiling or uv-atlas from the bound meshes' UVs (``stats``: UVStats of each mesh use)."""
    if not bound:
        return IntentDecision(Intent.TILING, _unbound(explored))
    if not stats:
        return IntentDecision(Intent.TILING, f"bound geometry ({bound} mesh use(s)) has no UVs to measure")
    widest = max(stats, key=lambda s: max(s.span[0] * factor[0], s.span[1] * factor[1]))
    span = (widest.span[0] * factor[0], widest.span[1] * factor[1])
    where = f"<{widest.mesh}>{_in(widest)}" + (f" and {len(stats) - 1} more" if len(stats) > 1 else "")
    rng = f"UVs {widest.lo[0]:.2f}-{widest.hi[0]:.2f} x {widest.lo[1]:.2f}-{widest.hi[1]:.2f}"
    if max(span) > THRESHOLDS.repeat_span:
        return IntentDecision(Intent.TILING, f"{rng} on {where}: {span[0]:.2f} x {span[1]:.2f} periods")
    if all(s.islands == s.full_islands for s in stats):
        islands = sum(s.islands for s in stats)
        kind = "a single swatch quad" if islands == 1 and sum(s.faces for s in stats) == 1 else (
            f"{islands} island(s), each showing the whole texture once")
        return IntentDecision(Intent.TILING, f"{rng} on {where}: {kind}")
    atlas = [s for s in stats if s.islands != s.full_islands]
    worst = max(atlas, key=lambda s: s.islands)
    return IntentDecision(
        Intent.UV_ATLAS,
        f"UVs {worst.lo[0]:.2f}-{worst.hi[0]:.2f} x {worst.lo[1]:.2f}-{worst.hi[1]:.2f}, {worst.islands} islands "
        f"on <{worst.mesh}>{_in(worst)}" + (f" (+{len(atlas) - 1} more mesh use(s))" if len(atlas) > 1 else "")
        + ": an unwrapped UV atlas",
    )


def classify(stack: TextureStack, bound: int, stats: Sequence, memo: TriageMemo, explored: int = 1) -> IntentDecision:
    """Class of one stack from its maps, its bound geometry's UV stats and the pixel measures (kept in ``memo``)."""
    clamped = [m for m in stack.maps if m.wrap_s in _CLAMPED or m.wrap_t in _CLAMPED]
    if clamped:
        m = clamped[0]
        return IntentDecision(Intent.OTHER, f"wrap {m.wrap_s}/{m.wrap_t} on @{m.asset}@: a clamped or decal use")
    factor, parts = _repeat_factor(stack)
    if max(factor) > THRESHOLDS.repeat_factor:
        decision = IntentDecision(Intent.TILING, f"{' > '.join(parts)} repeats the texture "
                                                 f"{factor[0]:g} x {factor[1]:g} times")
    else:
        decision = _geometry_decision(stack, factor, stats, bound, explored)
        if decision.intent is not Intent.TILING:
            return decision
    figures = [memo.get("measure", [m], lambda m=m: measure_map(m)) for m in stack.maps]
    if figures and all(f is not None for f in figures):
        ps = max(f[0] for f in figures)
        seam = max(f[1] for f in figures)
        measured = f"periodic-plus-smooth {ps:.3f}, seam ratio {seam:.2f}"
        if ps <= THRESHOLDS.ps_max and seam <= THRESHOLDS.seam_max:
            inside = memo.get("inside", stack.maps, lambda: interior_seam(stack))
            if inside is not None:
                return IntentDecision(Intent.TILING, f"{decision.reason}; seamless at the wrap ({measured}) but "
                                                     f"with a seam inside, {inside}")
            return IntentDecision(Intent.ALREADY_TILEABLE,
                                  f"{measured} (at most {THRESHOLDS.ps_max:g}, {THRESHOLDS.seam_max:g}): "
                                  f"already seamless; {decision.reason}")
        return IntentDecision(Intent.TILING, f"{decision.reason}; not seamless ({measured})")
    return decision


def classify_stacks(stacks: list[TextureStack], geometry, explored=lambda stack: 0,
                    memo: TriageMemo | None = None) -> list[TextureStack]:
    """Stacks with ``intent`` / ``intent_reason`` set. ``geometry(stack) -> (bound, stats)`` gives
    the number of mesh uses bound to the stack's material and their UV stats (0, [] when none),
    over the ``explored(stack)`` variant selections of its stage (0: not on a stage). ``memo`` keeps the
    pixel figures (on disk when it has a folder: see :mod:`.triagememo`)."""
    memo = memo if memo is not None else TriageMemo(None, repr(THRESHOLDS))
    measures: dict = {}
    out = []
    for stack in stacks:
        bound, stats = geometry(stack)
        decision = classify(stack, bound, stats, memo, explored(stack))
        # nothing binds it: do its pixels say atlas? (a flat border also wraps around seamlessly)
        if not bound and decision.intent in (Intent.TILING, Intent.ALREADY_TILEABLE):
            evidence = memo.get("atlas", stack.maps, lambda: atlas_evidence(stack, measures))
            if evidence is not None:
                border = " (its flat border is what wraps around)" if decision.intent is Intent.ALREADY_TILEABLE else ""
                decision = IntentDecision(Intent.UV_ATLAS_PIXELS, f"{evidence}; {decision.reason}{border}")
        out.append(replace(stack, intent=decision.intent.value, intent_reason=decision.reason))
    return out
