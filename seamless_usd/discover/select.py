"""Which stacks of a scan a run works on: selected by material, not blocked by a skipped
texture of their material, and meant to tile (unless forced)."""
from __future__ import annotations

import fnmatch
from collections.abc import Sequence

from seamless_usd.discover.intent import Intent, hand_set
from seamless_usd.discover.tokens import Codes
from seamless_usd.textures import ScanResult, TextureStack, describe_selection
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["BLOCKING_SKIPS", "UNREAD_SKIPS", "select_stacks", "unmatched_patterns", "blocked_stacks", "set_aside_stacks",
           "instanced_stacks", "hand_set_stacks", "left_alone_stacks", "from_recorded_sources", "matches_any",
           "unread_findings", "unread_materials", "unread_files"]

# A texture of a material skipped for one of these reasons blocks the material's stacks: making
# the other maps tileable (and rescaling their UVs) would misalign them with the skipped one.
BLOCKING_SKIPS = frozenset({"missing-file", "unreadable-file", "udim", "too-small", "animated-file",
                            "file-node-not-read"})
#: Of those, the skips that are a broken asset rather than a texture this tool does not handle.
UNREAD_SKIPS = frozenset({"missing-file", "unreadable-file"})
_SET_ASIDE = BLOCKING_SKIPS - UNREAD_SKIPS  # a texture this tool does not handle: its material is left alone


def _matches(stack: TextureStack | str, patterns: Sequence[str]) -> bool:
    path = (stack if isinstance(stack, str) else stack.material).strip("<>")
    name = path.rsplit("/", 1)[-1]
    return any(fnmatch.fnmatchcase(path, p) or fnmatch.fnmatchcase(name, p) for p in patterns)


def select_stacks(scan: ScanResult, patterns: Sequence[str]) -> list[TextureStack]:
    """Stacks whose material path or name matches one of ``patterns`` (all when empty)."""
    if not patterns:
        return list(scan.stacks)
    return [stack for stack in scan.stacks if _matches(stack, patterns)]


def matches_any(material: str, patterns: Sequence[str]) -> bool:
    """Whether ``material`` (a path) matches one of ``patterns`` (by path or name, case-sensitive)."""
    return _matches(material, patterns)


def unmatched_patterns(materials: Sequence[str], patterns: Sequence[str]) -> list[str]:
    """The ``patterns`` that match none of ``materials`` (by path or name, case-sensitive)."""
    return [p for p in patterns if not any(_matches(m, [p]) for m in materials)]


def left_alone_stacks(stacks: Sequence[TextureStack], source: str, force: bool = False,
                      force_materials: Sequence[str] = ()) -> set[tuple[str, str]]:
    """Stacks not meant to tile (uv-atlas, already-tileable, other) that are not forced: they are
    reported with their intent and not trained (already-tileable ones only get wrap = repeat)."""
    if force:
        return set()
    return {
        (source, s.id) for s in stacks
        if s.intent and s.intent != Intent.TILING.value and not _matches(s, force_materials)
    }


def _skipped(scan: ScanResult, stack: TextureStack, codes) -> list[str]:
    return [f"{f.where} ({f.code})" for f in scan.findings
            if f.severity is Severity.SKIPPED and f.code in codes and f.material == stack.material]


def blocked_stacks(scan: ScanResult, stacks: Sequence[TextureStack], source: str) -> dict[tuple[str, str], str]:
    """Stacks that fail because a texture of their material is missing or unreadable (:data:`UNREAD_SKIPS`): a
    broken asset, named."""
    out = {}
    for stack in stacks:
        reasons = _skipped(scan, stack, UNREAD_SKIPS)
        if reasons:
            out[(source, stack.id)] = (
                f"not processed: {', '.join(reasons)} of this material cannot be read, and tiling the other "
                "maps would misalign them; fix or remove that texture and run again"
            )
    return out


def set_aside_reasons(scan: ScanResult, stack: TextureStack) -> list[str]:
    """The textures of ``stack``'s material this tool does not make tileable (a UDIM set, a picture too small, an
    animated file), each ``@file@ (code)``: while there is one, the stack is left alone (:func:`set_aside_stacks`) and
    ``check`` does not judge it either."""
    return _skipped(scan, stack, _SET_ASIDE)


def set_aside_stacks(scan: ScanResult, stacks: Sequence[TextureStack], source: str) -> dict[tuple[str, str], str]:
    """Stacks left alone because a texture of their material is one this tool does not make tileable (a UDIM
    set, a picture too small): tiling the other maps would misalign them. Not a failure; a broken texture of the
    same material (:func:`blocked_stacks`) comes first."""
    out = {}
    for stack in stacks:
        reasons = set_aside_reasons(scan, stack)
        if reasons and not _skipped(scan, stack, UNREAD_SKIPS):
            out[(source, stack.id)] = (
                f"left alone: {', '.join(reasons)} of this material is not made tileable, and tiling the other "
                "maps would misalign them")
        elif packed := [m for m in stack.maps if m.in_package]:
            out[(source, stack.id)] = (
                f"left alone: {asset_ref(packed[0].resolved)} is inside a .usdz package, and its maps are not read "
                "from inside one; unpack the package (it is a zip file) and process the unpacked stage")
    return out


def hand_set_stacks(stacks: Sequence[TextureStack], source: str) -> dict[tuple[str, str], str]:
    """Stacks with a node whose ``seamless:`` provenance records a tile this tool wrote while the node reads another
    file (:func:`.intent.hand_set`: set by hand since, in a layer a run edited in place): they fail, the file left as
    it is, as a file set by hand in a run's new layer is. A run again took the provenance's word, called the stack
    already tileable and left the photo under the tile's UV scale."""
    out = {}
    for stack in stacks:
        hand = hand_set(stack)
        if hand:
            m = hand[0]
            out[(source, stack.id)] = (
                f"not processed: {prim_ref(m.node.strip('<>'))} reads {asset_ref(m.asset)}, set by hand since this tool "
                f"wrote its tile there (the node's seamless: attributes record the source "
                f"{asset_ref(m.recorded_source.asset)}): it is left as it is; set the file back to the tile, or remove "
                "the node's seamless: attributes (seamless_* in MaterialX) to have it made again")
    return out


def instanced_stacks(stage, stacks: Sequence[TextureStack], source: str, open_stage: bool = False
                     ) -> dict[tuple[str, str], str]:
    """Stacks of the open USD ``stage`` with a texture node inside an instance (an instance proxy, which no layer
    over the stage can edit), with why: they fail before any tile is made for them, unless edited in place (the
    advice; ``open_stage``: a stage handed over open, which has no in-place mode)."""
    out = {}
    for stack in stacks:
        nodes = [m.node for m in stack.maps if m.origin.value == "usd" and not stack.selection]
        inside = [m for m in stack.maps if m.origin.value == "usd" and not stack.selection
                  and (prim := stage.GetPrimAtPath(m.node.strip("<>"))) and prim.IsInstanceProxy()]
        if inside:
            node, layer = prim_ref(inside[0].node.strip("<>")), inside[0].file_at and inside[0].file_at.layer
            where = f" ({asset_ref(layer)}, where its prototype is made)" if layer else ""
            out[(source, stack.id)] = (f"its texture node {node} is inside an instance, which a layer over the stage "
                                       f"cannot change: {'edit' if open_stage else 'run with --in-place to edit'} "
                                       f"its prototype's source{where}, which every instance shows, or make it "
                                       "non-instanceable")
    return out


def unread_findings(scan: ScanResult) -> dict[str, list[Finding]]:
    """Material -> the scan's findings that skipped a texture of it as missing or unreadable."""
    out: dict[str, list[Finding]] = {}
    for f in scan.findings:
        if f.severity is Severity.SKIPPED and f.code in UNREAD_SKIPS and f.material:
            out.setdefault(f.material, []).append(f)
    return out


def unread_materials(scan: ScanResult, patterns: Sequence[str] = ()) -> dict[str, list[Finding]]:
    """Of :func:`unread_findings`, the materials (matching ``patterns``, all when empty) none of whose textures
    could be read, so the scan has no stack for them. A material with a readable map too has a stack, which
    :func:`blocked_stacks` names."""
    have = {s.material for s in scan.stacks}
    return {m: found for m, found in unread_findings(scan).items()
            if m not in have and (not patterns or _matches(m, patterns))}


def set_aside_materials(scan: ScanResult, patterns: Sequence[str] = ()) -> dict[str, list[Finding]]:
    """The materials (matching ``patterns``, all when empty) with no stack because every texture of theirs is one
    this tool does not make tileable (a UDIM set, a picture too small, an animated file), none missing or
    unreadable: left alone, with why (:func:`set_aside_stacks` names those with a stack)."""
    have = {s.material for s in scan.stacks}
    unread = unread_findings(scan)
    out: dict[str, list[Finding]] = {}
    for f in scan.findings:
        if (f.severity is Severity.SKIPPED and f.code in _SET_ASIDE and f.material
                and f.material not in have and f.material not in unread
                and (not patterns or _matches(f.material, patterns))):
            out.setdefault(f.material, []).append(f)
    return out


def unread_files(skipped: Sequence[Finding]) -> str:
    """The files of :func:`unread_findings`' findings, each with why, for a message: ``@a.png@ (missing-file), ...``."""
    return ", ".join(f"{f.where.split(' ')[-1]} ({f.code})" for f in skipped)


def from_recorded_sources(stacks: Sequence[TextureStack], source: str, left_alone: set[tuple[str, str]]
                          ) -> tuple[list[TextureStack], list[Finding]]:
    """The stacks a run works on, each tile this tool wrote replaced by the source it records, so that a stack is
    made again from its source (a run again after ``--in-place``, or on the layer a run wrote), never from its
    own tile: a tile of a tile, judged against the tile, passed what was never judged against the photo.
    Stacks left alone stay as they are. A tile whose source is gone is made from the tile, with a warning."""
    from dataclasses import replace

    from seamless_usd.discover.images import ImageReadError, read_image_info

    out, findings = [], []
    for stack in stacks:
        if (source, stack.id) in left_alone or not any(m.recorded_source for m in stack.maps):
            out.append(stack)
            continue
        maps = []
        for m in stack.maps:
            recorded = m.recorded_source
            if recorded is None or m.tile_missing:  # no tile of ours, or one the scan already read as its source
                maps.append(m if recorded is None else replace(m, asset=recorded.asset))
                continue
            why = "is not there"
            if recorded.resolved:
                try:
                    info = read_image_info(recorded.resolved)
                except (OSError, ImageReadError) as exc:
                    why = f"cannot be read ({exc})"
                else:
                    maps.append(replace(m, asset=recorded.asset, resolved=recorded.resolved, image=info))
                    continue
            findings.append(Finding(
                Severity.WARNING, Codes.SOURCE_NOT_FOUND, f"{prim_ref(m.node.strip('<>'))} {asset_ref(m.asset)}",
                f"the source this tile records, {asset_ref(recorded.asset)}, {why}: made tileable from the tile "
                "itself", material=stack.material))
            maps.append(m)
        out.append(replace(stack, maps=tuple(maps)))
    return out, findings


def shared_node_stacks(scan: ScanResult, stacks: Sequence[TextureStack], source: str,
                       kept: dict[tuple[str, str], str]) -> dict[tuple[str, str], str]:
    """Stacks that would change another use of their texture nodes: a node (one ``UsdUVTexture`` prim, or MaterialX
    node) read by a material, or a variant selection of it, whose stack is not made (``kept``: (source, id) -> why: its
    intent when left alone, else the message of the reason it is not made) or not selected (``stacks``: the selected
    ones). Its edits (the
    tile's path, repeat, the UV scale) are made on the node, so the other use would show the tile too: such a stack
    fails, naming that use, and is not made."""
    users: dict[tuple, list[TextureStack]] = {}
    for stack in scan.stacks:
        for key in {_use(m) for m in stack.maps}:
            users.setdefault(key, []).append(stack)
    selected = {s.id for s in stacks}
    out = {}
    for stack in stacks:
        if (source, stack.id) in kept:
            continue
        for m in stack.maps:
            users_here = [o for o in users.get(_use(m), []) if o.id != stack.id
                          and not _in_own_variants(m, stack, o)]
            others = [o for o in users_here if (source, o.id) in kept or o.id not in selected]
            # a use made tileable too, from other maps (a variant's own albedo beside a roughness authored outside the
            # variants): one edit of the node cannot line up with both stacks' tiles
            differing = [o for o in users_here if o not in others and o.content_key != stack.content_key]
            if others or differing:
                other = (others or differing)[0]
                where = f" in {describe_selection(other.selection)}" if other.selection else ""
                same = other.material == stack.material
                fix = ("author the texture's file inside each variant (its edits then stay in the variant)" if same
                       else "give each material a texture node of its own"
                       + (", or process both (--force-materials)" if others else ""))
                if others:
                    why = kept.get((source, other.id)) or "not selected (--materials)"
                    said = f"which is not made tileable ({_first_clause(why)})"
                else:
                    said = "whose tile is made from other maps, so one edit of the node cannot line up with both"
                out[(source, stack.id)] = (
                    f"not processed: its texture node {prim_ref(m.node)} is also read by {other.material}{where}, "
                    f"{said}; editing the node would change that use too: {fix}")
                break
    return out


def _in_own_variants(m, stack, other) -> bool:
    """Whether ``other``'s use of ``m``'s node is edited apart from ``stack``'s: both are selections of one material
    whose node's file value comes from inside a variant under each (two look variants that name the same normal map,
    each in its own variant): each one's edits go inside its own variant."""
    theirs = next((o for o in other.maps if o.node == m.node), None)
    return (other.material == stack.material and other.selection != stack.selection and m.file_in_variant
            and theirs is not None and theirs.file_in_variant)


def _use(m) -> tuple:
    """What an edit of a map's node changes: the node, with the file value it reads and where that is authored (a
    variant that authors a file of its own is edited inside the variant)."""
    return m.node, m.asset, m.file_at


def _first_clause(reason: str) -> str:
    """The reason a stack is not made, shortened to its first clause (a message's "not processed: " or "left alone: "
    left out)."""
    return reason.split(";")[0].split(": ", 1)[-1].strip() or reason
