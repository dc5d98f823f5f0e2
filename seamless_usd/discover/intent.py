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
  and UVs read under the variant selection they are authored in, see ``bound.py``); or one of them does while
  another repeats it: the material's edits would change the atlas too;
- ``uv-atlas (pixels)``: nothing binds it, but its pixels show an atlas's layout (islands on a
  flat background; see ``atlas.py``): flagged for review, processed only when forced;
- ``already-tileable``: a would-be *tiling* stack in which the verdict (:mod:`seamless_usd.verdict`),
  judging its maps against themselves, finds no seam at the wrap or inside: the same files read the
  same way (:mod:`seamless_usd.verdict.alone`) and the same rule as ``seamless-usd check``, so the two
  always agree. A stack whose files are not on disk, too large (over ``measure_max_pixels``) or
  unreadable is left *tiling*, its reason saying why.

The verdict's figures on labelled textures it was not tuned on are in ``docs/verdict.md``
(``benchmarks/texture_verdict.py``).
"""
from __future__ import annotations

import os
from pathlib import Path
from collections.abc import Sequence
from dataclasses import dataclass, replace
from enum import Enum

from seamless_usd.discover.atlas import atlas_evidence
from seamless_usd.discover.triagememo import TriageMemo
from seamless_usd.findings import asset_ref
from seamless_usd.textures import TextureStack
from seamless_usd.verdict import Verdict

__all__ = ["Intent", "IntentDecision", "Thresholds", "classify_stacks", "judged_alone", "THRESHOLDS"]


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
    measure_max_pixels: int = 1 << 26  # larger files are not decoded before processing (left "tiling")


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


def judged_alone(stack: TextureStack, thresholds: Thresholds = THRESHOLDS) -> dict:
    """The verdict on the stack's files judged against themselves, exactly as ``check`` judges them
    (:func:`seamless_usd.verdict.alone.judge_alone`): ``{"verdict": Verdict.as_dict()}``, or ``{"error": why}``
    when they are not judged (a file not on disk, too large to decode before processing, unreadable, too small)."""
    from seamless_usd.errors import InputError, UndecodableImage
    from seamless_usd.verdict.alone import file_map, judge_alone, normal_doubts

    for m in stack.maps:
        if m.in_package:
            return {"error": f"@{m.asset}@ is inside a .usdz package, whose pixels are not judged in place (unpack the "
                             "package to judge or process it)"}
        if not m.resolved or m.image is None:
            return {"error": f"@{m.asset}@ is not a file on disk"}
        if m.image.width * m.image.height > thresholds.measure_max_pixels:
            return {"error": f"@{m.asset}@ is {m.image.width}x{m.image.height} px, too large to judge before "
                             "processing"}
    try:
        files = [file_map(m) for m in stack.maps]
        verdict, _ = judge_alone(files)
    except (InputError, ValueError, RuntimeError, OSError) as exc:
        # a file whose header reads but whose pixels do not decode (truncated, corrupt): named, as a header that
        # does not read is (its material's stack cannot be made)
        broken = [m.asset for m in stack.maps if isinstance(exc, UndecodableImage)
                  and os.path.realpath(m.resolved) == os.path.realpath(exc.path)]
        return {"error": str(exc), **({"unreadable": broken[0]} if broken else {})}
    return {"verdict": verdict.as_dict(), "doubts": normal_doubts(files)}


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
    def periods(s) -> float:
        return max(s.span[0] * factor[0], s.span[1] * factor[1])

    widest = max(stats, key=periods)
    span = (widest.span[0] * factor[0], widest.span[1] * factor[1])
    where = f"<{widest.mesh}>{_in(widest)}" + (f" and {len(stats) - 1} more" if len(stats) > 1 else "")
    rng = f"UVs {widest.lo[0]:.2f}-{widest.hi[0]:.2f} x {widest.lo[1]:.2f}-{widest.hi[1]:.2f}"
    if max(span) > THRESHOLDS.repeat_span:
        # a material that also textures an unwrapped atlas: a tile (and its UV scale) would change the atlas too
        atlas = [s for s in stats if s.islands != s.full_islands and periods(s) <= THRESHOLDS.repeat_span]
        if atlas:
            worst = max(atlas, key=lambda s: s.islands)
            return IntentDecision(
                Intent.UV_ATLAS,
                f"bound to an unwrapped UV atlas ({worst.islands} island{'' if worst.islands == 1 else 's'} on "
                f"<{worst.mesh}>{_in(worst)}) as well as repeating ({rng} on <{widest.mesh}>{_in(widest)}: "
                f"{span[0]:.2f} x {span[1]:.2f} periods): a tile would change the atlas too; give the repeating "
                "mesh a material of its own to make it tileable")
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
        f"UVs {worst.lo[0]:.2f}-{worst.hi[0]:.2f} x {worst.lo[1]:.2f}-{worst.hi[1]:.2f}, "
        f"{worst.islands} island{'' if worst.islands == 1 else 's'} "
        f"on <{worst.mesh}>{_in(worst)}" + (f" (+{len(atlas) - 1} more mesh use(s))" if len(atlas) > 1 else "")
        + ": an unwrapped UV atlas",
    )


def _changed_sources(stack: TextureStack) -> list[str]:
    """The recorded sources of a stack's tiles that differ from the files the tiles record they were made from."""
    from seamless_usd.imaging.tag import source_changed

    return [m.recorded_source.resolved for m in stack.maps if m.recorded_source and m.recorded_source.resolved
            and source_changed(m.resolved, m.recorded_source.resolved)]


def hand_set(stack: TextureStack) -> list:
    """The maps of ``stack`` whose node records a tile this tool wrote (its ``seamless:`` provenance) but reads a file
    that is no tile of this tool's (not tagged as one, not named ``*.tile.*``): set by hand since, in the layer the
    run edited in place. Their provenance says nothing of the file they read."""
    from seamless_usd.imaging.tag import read_tag

    return [m for m in stack.maps if m.recorded_source and m.resolved and not m.tile_missing
            and ".tile." not in Path(m.resolved).name and read_tag(m.resolved) is None]


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
    recorded = [m.recorded_passed for m in stack.maps]
    hand = hand_set(stack) if all(r is not None for r in recorded) else []
    if hand:  # the provenance is of a tile the node no longer reads: its pixels are judged, as check judges them
        decision = IntentDecision(decision.intent, f"{decision.reason}; {asset_ref(hand[0].asset)} is not the tile "
                                                   "seamless-usd wrote there (set by hand since)")
    elif all(r is not None for r in recorded):  # tiles this tool wrote: the verdict against their recorded source
        missing = [m for m in stack.maps if m.tile_missing]
        if missing:
            return IntentDecision(Intent.TILING, f"{decision.reason}; made by seamless-usd, and its tile "
                                                 f"{asset_ref(missing[0].asset)} is not there: made again from its "
                                                 "recorded source")
        changed = _changed_sources(stack)
        if changed:
            return IntentDecision(Intent.TILING, f"{decision.reason}; made by seamless-usd, and its source "
                                                 f"{asset_ref(changed[0])} has changed since: made again from it")
        if all(recorded):
            return IntentDecision(Intent.ALREADY_TILEABLE,
                                  "made tileable by seamless-usd and passed by the verdict against its recorded source "
                                  "when written (seamless:passed; check judges it again against that source); "
                                  f"{decision.reason}")
        return IntentDecision(Intent.TILING, f"{decision.reason}; made by seamless-usd and not passed by the verdict "
                                             "against its recorded source when written (seamless:passed)")
    judged = memo.get("verdict", stack.maps, lambda: judged_alone(stack))
    if "verdict" not in judged:
        return IntentDecision(Intent.TILING, f"{decision.reason}; its pixels were not judged ({judged['error']})")
    v = Verdict.from_dict(judged["verdict"])
    if judged.get("doubts"):  # a normal map that does not read as one: said with the intent, as check says it
        decision = IntentDecision(decision.intent, f"{decision.reason}; {'; '.join(judged['doubts'])}")
    if v.seamless:
        return IntentDecision(Intent.ALREADY_TILEABLE,
                              f"already seamless: the verdict, judging its maps against themselves, finds no seam "
                              f"(strongest line {v.strongest:+.2f}, a seam above {v.margin:g}); {decision.reason}")
    s = v.seams[0]
    where = "the maps together" if s.map == "stack" else f"@{s.map}@"
    more = f" and {len(v.seams) - 1} more" if len(v.seams) > 1 else ""
    return IntentDecision(Intent.TILING, f"{decision.reason}; not seamless: a seam in {where}, {s.where(v.size)} "
                                         f"({s.above}){more}")


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
