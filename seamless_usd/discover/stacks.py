"""Group maps into texture stacks (one material, one UV chain, one variant selection) and mark
identical stacks."""
from __future__ import annotations

import json
from dataclasses import replace

from seamless_usd.textures import TextureMap, TextureStack, UVChain

__all__ = ["build_stacks", "chain_key"]


def chain_key(uv: UVChain, texture_node: str) -> str:
    """Maps sharing this key share a UV chain. Like ``UVChain.key``, except that a transform held
    by the texture node itself (``tiledimage`` uvtiling/uvoffset, a glTF image's place2d) counts by
    value, so tiled images with the same tiling over the same texcoord form one stack."""
    transforms = [
        [t.kind, list(t.scale), t.rotation, list(t.translation), list(t.pivot), t.operation_order]
        if t.node == texture_node else t.node
        for t in uv.transforms
    ]
    return json.dumps([uv.primvar, uv.reader, transforms, uv.connected_from])


def build_stacks(maps: list[TextureMap]) -> list[TextureStack]:
    """Stacks in first-seen order; a stack with the same content as an earlier one gets
    ``duplicate_of`` set to that stack's id (same files, channels, colour spaces, scale/bias).

    Two texture nodes of one material reading the same file over the same UV chain stay two maps
    (each node is edited by authoring); they are one map for training only if imaging merges them.
    """
    grouped: dict[tuple, list[TextureMap]] = {}
    chains = {}
    for m in maps:
        key = (m.material, chain_key(m.uv, m.node), m.selection)
        grouped.setdefault(key, []).append(m)
        chains.setdefault(key, m.uv)
    stacks: list[TextureStack] = []
    first_by_content: dict[str, str] = {}
    for key, members in grouped.items():
        stack = TextureStack(material=key[0], uv=chains[key], maps=tuple(members))
        earlier = first_by_content.get(stack.content_key)
        if earlier is not None and earlier != stack.id:
            stack = replace(stack, duplicate_of=earlier)
        else:
            first_by_content.setdefault(stack.content_key, stack.id)
        stacks.append(stack)
    return stacks
