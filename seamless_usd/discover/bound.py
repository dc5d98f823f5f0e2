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
from seamless_usd.textures import Selection, TextureStack, describe_selection

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
