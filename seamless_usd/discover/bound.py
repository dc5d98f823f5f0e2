"""The geometry bound to each stack's material, under the variant selections it was found in.

A material found (or bound) only under a variant selection that is not the stage's own is
judged under that selection: the bindings of every explored selection are recorded while the
scan walks it, and the UVs of the meshes bound to a stack are read from the stage composed under
each selection the stack was seen in. Each :class:`~seamless_usd.discover.uvgeom.UVStats` names
its selection, so a reason can say "on </King/Geom/Render> in shadingVariant=White".
"""
from __future__ import annotations

from dataclasses import replace

from seamless_usd.discover import uvgeom
from seamless_usd.discover.stacks import chain_key
from seamless_usd.textures import Selection, TextureMap, TextureStack, describe_selection

__all__ = ["Geometry"]


class Geometry:
    """Bound mesh uses and their UV stats per stack, over every explored variant selection."""

    def __init__(self) -> None:
        self.leaves: list[tuple[object, Selection, dict]] = []  # (VariantSpace, selection, bindings)
        self._seen: dict[tuple, set[int]] = {}  # (material, node, selection) -> leaves it was walked in
        self._found: dict[str, tuple[int, list[uvgeom.UVStats]]] = {}

    def explored_for(self, stack: TextureStack) -> int:
        """Variant selections explored on the stage ``stack`` was found on (0: not on a stage)."""
        leaves = self._leaves_of(stack)
        if not leaves:
            return 0
        space = self.leaves[leaves[0]][0]
        return sum(1 for leaf in self.leaves if leaf[0] is space)

    def add(self, space, selection: Selection, bindings: dict) -> int:
        """Record the bindings of ``space`` composed under ``selection``; the leaf's index."""
        self.leaves.append((space, selection, bindings))
        return len(self.leaves) - 1

    def seen(self, use, index: int) -> None:
        """A texture use (first seen under ``use.selection``) was walked again in leaf ``index``."""
        self._seen.setdefault((use.material, use.node, use.selection), set()).add(index)

    def complete(self, maps: list[TextureMap]) -> list[TextureMap]:
        """``maps`` (each found first under its ``selection``), with every map a material reads under a variant
        selection where its maps differ from the stack found first, added under that selection.

        A use is kept once, under the selection it was first found in, so a material whose shading variant sets
        its albedo inside the variant and reads a roughness authored outside the variants was a stack of one map
        (the albedo) under that variant: judged without its roughness, and the roughness node edited for the
        other variant's stack changed this one's look. Here each walk of a selection (leaf) gives, per material and
        UV chain, the maps it read; where those are not one stack's maps, the stack of that selection gets them all
        (the maps found first elsewhere added under the leaf's selection), and leaves that read the same maps share
        one such stack. A map's leaves are then only those where its material read its own stack's maps, so each
        stack's bound geometry is measured where it is the material's stack."""
        by_key = {(m.material, m.node, m.selection): m for m in maps}
        walked: dict[int, list[tuple]] = {}
        for key, leaves in self._seen.items():
            if key in by_key:
                for leaf in leaves:
                    walked.setdefault(leaf, []).append(key)
        homes: dict[tuple, frozenset] = {}  # (material, chain, selection) -> the keys of the maps found first there
        for key, m in by_key.items():
            homes.setdefault((m.material, chain_key(m.uv, m.node), m.selection), frozenset())
            homes[(m.material, chain_key(m.uv, m.node), m.selection)] |= {key}
        added: dict[tuple, Selection] = {}  # (material, chain, keys read) -> the selection of their stack
        out = list(maps)
        for leaf in sorted(walked):
            selection = self.leaves[leaf][1]
            groups: dict[tuple, set] = {}
            for key in walked[leaf]:
                m = by_key[key]
                groups.setdefault((m.material, chain_key(m.uv, m.node)), set()).add(key)
            for (material, chain), keys in groups.items():
                keys = frozenset(keys)
                if any(homes.get((material, chain, k[2])) == keys for k in keys):
                    continue  # the leaf read exactly one stack's maps
                home = added.setdefault((material, chain, keys), selection)
                for key in keys:
                    self._seen[key].discard(leaf)
                    if key[2] == home:
                        self._seen[key].add(leaf)
                        continue
                    own = (key[0], key[1], home)
                    if own not in self._seen:
                        out.append(replace(by_key[key], selection=home))
                    self._seen.setdefault(own, set()).add(leaf)
        return out

    def _leaves_of(self, stack: TextureStack) -> list[int]:
        found: set[int] = set()
        for m in stack.maps:
            found |= self._seen.get((m.material, m.node, m.selection), set())
        return sorted(found)

    def measure(self, stacks: list[TextureStack]) -> None:
        """Read the UVs bound to every stack, composing each selection once."""
        needs: dict[int, list[tuple[TextureStack, uvgeom.MeshUse]]] = {}
        for stack in stacks:
            self._found[stack.id] = (0, [])
            for index in self._leaves_of(stack):
                for use in self.leaves[index][2].get(stack.material, []):
                    needs.setdefault(index, []).append((stack, use))
        done: dict[str, set] = {}
        for index in sorted(needs):
            space, selection, _ = self.leaves[index]
            stage = space.compose(selection)
            label = describe_selection(selection)
            for stack, use in needs[index]:
                bound, stats = self._found[stack.id]
                seen = done.setdefault(stack.id, set())
                if (use.mesh, use.faces) not in seen:
                    bound += 1
                try:
                    found = uvgeom.uv_stats(stage, use, stack.uv.primvar)
                except Exception:  # noqa: BLE001 - malformed geometry: no UVs to measure
                    found = None
                if found is not None and (use.mesh, use.faces, found) not in seen:
                    seen.add((use.mesh, use.faces, found))
                    stats = [*stats, replace(found, selection=label)]
                seen.add((use.mesh, use.faces))
                self._found[stack.id] = (bound, stats)
        for space, _, _ in self.leaves:
            space.compose(())

    def __call__(self, stack: TextureStack) -> tuple[int, list[uvgeom.UVStats]]:
        return self._found.get(stack.id, (0, []))
