"""Group maps into texture stacks (one material, one UV chain) and mark identical stacks."""
from __future__ import annotations

from dataclasses import replace

from seamless_usd.discover.types import TextureMap, TextureStack

__all__ = ["build_stacks"]


def build_stacks(maps: list[TextureMap]) -> list[TextureStack]:
    """Stacks in first-seen order; a stack with the same content as an earlier one gets
    ``duplicate_of`` set to that stack's id (same files, channels, colour spaces, scale/bias).

    Two texture nodes of one material reading the same file over the same UV chain stay two maps
    (each node is edited by authoring); they are one map for training only if imaging merges them.
    """
    grouped: dict[tuple[str, str], list[TextureMap]] = {}
    chains = {}
    for m in maps:
        key = (m.material, m.uv.key)
        grouped.setdefault(key, []).append(m)
        chains.setdefault(key, m.uv)
    stacks: list[TextureStack] = []
    first_by_content: dict[str, str] = {}
    for (material, _), members in grouped.items():
        stack = TextureStack(material=material, uv=chains[(material, _)], maps=tuple(members))
        earlier = first_by_content.get(stack.content_key)
        if earlier is not None and earlier != stack.id:
            stack = replace(stack, duplicate_of=earlier)
        else:
            first_by_content.setdefault(stack.content_key, stack.id)
        stacks.append(stack)
    return stacks
