"""In place, a layer that several stages of one run compose (a material library they reference) is edited once per
texture, and never under a use that is not made tileable (another stage's, or another material of the same stage
that references the same asset).

Each stage is edited on its own, one after another. Without this, a library's texture read by a stage that tiles it
and by another that leaves it alone (a UV atlas's prop) was edited all the same, the prop's report saying it was left
alone; and two stages tiling the same material each set the library's file value to the tiles in their own folder,
the last one winning, so every run again wrote the library twice.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

from pxr import Sdf, Usd

from seamless_usd.findings import Finding, Severity, asset_ref
from seamless_usd.authoring.types import AuthoringResult, Codes, StackResult, node_key

__all__ = ["SharedEdits", "file_sites", "node_sites"]

#: Where a texture's file value is authored: (layer identifier, spec path of the attribute in that layer).
Site = tuple[str, str]


@dataclass
class SharedEdits:
    """What one in-place run knows of the layers its stages share. ``kept``: site -> (the stage, and why its use
    there is not made tileable); ``made``: site -> (file value set, the content key of the stack that set it, who)."""

    kept: dict[Site, tuple[str, str, str]] = field(default_factory=dict)
    made: dict[Site, tuple[str, str, str]] = field(default_factory=dict)

    def keep(self, sites, stage: str, material: str, why: str) -> None:
        """Sites ``material`` of ``stage`` reads whose stack is not made tileable (left alone, set aside, failed, not
        selected)."""
        for site in sites:
            self.kept.setdefault(site, (stage, material, why))

    def refusal(self, sites, stage: str) -> str | None:
        """Why a stack of ``stage`` whose file values are authored at ``sites`` must not be edited in place: one of
        them is read by a use that is not made tileable (of this stage, another material that references the same
        asset; or another stage's); None when none is."""
        for site in sorted(sites):
            kept = self.kept.get(site)
            if kept is not None:
                other, material, why = kept
                where = "" if other == stage else f" of {asset_ref(other)}"
                return (f"edited in place, {asset_ref(site[0])} would change {material}{where} too, which reads the "
                        f"same texture there and is not made tileable ({why}): leave out --in-place (a new layer "
                        "edits this material alone), or give that use a texture of its own")
        return None


def file_sites(stage: Usd.Stage, maps) -> set[Site]:
    """Where the file values of ``maps`` (``TextureMap``\\ s of the composed ``stage``) are authored."""
    out = set()
    for m in maps:
        at = m.file_at
        prim = stage.GetPrimAtPath(at.prim) if at and at.prim.startswith("/") else None
        attr = prim.GetAttribute(at.attribute) if prim else None
        specs = attr.GetPropertyStack(Usd.TimeCode.Default()) if attr else []
        if specs:
            out.add((specs[0].layer.identifier, str(specs[0].path)))
    return out


def node_sites(stage: Usd.Stage, maps) -> set[Site]:
    """Where in-place edits of the texture nodes of ``maps`` land: each node's spec in the layer holding its file
    value (two materials that reference one asset, or inherit one class, share it; a decal reading the same
    material input as a tiled node does not, since the tile is set on the tiled node's own input)."""
    out = set()
    for m in maps:
        path = m.node.strip("<>")
        prim = stage.GetPrimAtPath(path) if path.startswith("/") else None  # a MaterialX node: not a prim
        specs = list(prim.GetPrimStack()) if prim else []
        if not specs:
            continue
        layer = m.file_at.layer if m.file_at else ""
        spec = next((p for p in specs if p.layer.identifier == layer or p.layer.realPath == layer), specs[0])
        out.add((spec.layer.identifier, str(spec.path)))
    return out


def respect_other_stages(author, results: Sequence[StackResult], result: AuthoringResult, shared: SharedEdits
                         ) -> None:
    """Drop the planned edits of a stage's stacks whose file values a stage before it in the run set to other tiles:
    that value is kept when the two stacks are made from the same maps (the same tiles, in that stage's folder; a
    finding says so), and the stack fails when they are not (one value cannot show both). (A stack that would change
    a use that is not made tileable failed before its tiles were made: :meth:`SharedEdits.refusal`.)"""
    by_id = {r.stack.id: r for r in results}
    refused: dict[str, str] = {}
    followed: dict[str, str] = {}
    for edit, owner in zip(author.edits, author.owners):
        if owner not in by_id or not isinstance(edit.value, Sdf.AssetPath):
            continue
        layer = edit.target.GetLayer()
        site = (layer.identifier, str(edit.target.MapToSpecPath(edit.path)))
        made = shared.made.get(site)
        if made is not None and made[0] != edit.value.path:
            if made[1] == by_id[owner].stack.content_key:
                followed.setdefault(owner, made[2])
            else:
                refused.setdefault(owner, (
                    f"edited in place, {asset_ref(layer.realPath or layer.identifier)} already shows the tile of "
                    f"{made[2]}, made from other maps: one file value cannot show both; leave out --in-place (each "
                    "stage gets a layer of its own)"))
    dropped = set(refused) | set(followed)
    if dropped:
        author.edits = [e for e, owner in zip(author.edits, author.owners) if owner not in dropped]
        author.owners = [o for o in author.owners if o not in dropped]
    for owner, why in refused.items():
        for m in by_id[owner].maps:
            result.not_written.append((node_key(m.map), why))
    for owner, who in followed.items():
        if owner in refused:
            continue
        result.findings.append(Finding(
            Severity.WARNING, Codes.SHARED_LAYER_EDITED, by_id[owner].stack.material,
            f"its texture's file value, in a layer another stage of this run composes too, already shows the tiles "
            f"of {who}, made from the same maps: kept (this stage's tiles are the same)", by_id[owner].stack.material))


def record_made(author, results: Sequence[StackResult], shared: SharedEdits, stage: str) -> None:
    """Note the file values this stage's stacks leave in its layers, for the stages after it: those its edits set
    (planned, in a dry run), and those its layers already held (a run again, whose edits are there already)."""
    planned = {}
    for edit in author.edits:
        if isinstance(edit.value, Sdf.AssetPath):
            planned[(edit.target.GetLayer().identifier, str(edit.target.MapToSpecPath(edit.path)))] = edit.value.path
    for r in results:
        for site in file_sites(author.stage, [m.map for m in r.maps]):
            value = planned.get(site)
            if value is None:
                layer = Sdf.Layer.Find(site[0])
                spec = layer.GetAttributeAtPath(site[1]) if layer else None
                held = spec.default if spec else None
                value = held.path if isinstance(held, Sdf.AssetPath) else None
            if value is not None:
                shared.made.setdefault(site, (value, r.stack.content_key, f"{r.stack.material} of {asset_ref(stage)}"))
