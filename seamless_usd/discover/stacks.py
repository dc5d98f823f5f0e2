"""Group maps into texture stacks (one material, one UV chain, one variant selection) and mark
identical stacks."""
from __future__ import annotations

import json
from dataclasses import replace

from seamless_usd.discover.tokens import Recorded
from seamless_usd.textures import TextureMap, TextureStack, UVChain

__all__ = ["build_stacks", "chain_key"]


def chain_key(uv: UVChain, texture_node: str) -> str:
    """Maps sharing this key share a UV chain. Like ``UVChain.key``, except that a transform held
    by the texture node itself (``tiledimage`` uvtiling/uvoffset, a glTF image's place2d) counts by
    value, so tiled images with the same tiling over the same texcoord form one stack; so does the place2d this
    tool inserts in a MaterialX document, one per nodegraph scope (a node inside a nodegraph cannot read one
    outside it), so a stack it wrote across scopes is read back as one stack."""
    def ours(node: str) -> bool:
        return node.rsplit("/", 1)[-1] == Recorded.MTLX_UV_NODE

    inserted = any(t.ours for t in uv.transforms) and not any(ours(t.node) for t in uv.transforms)
    if uv.before_ours is not None and inserted:
        # a USD chain through the UV transform this tool inserted: grouped as it read before the run, so a map added
        # to the material since, reading the texture coordinates directly, joins its stack (the two were one stack
        # under one id, and the new map's stack took the processed one's left-alone status)
        primvar, reader, connected = uv.before_ours
        transforms = [[t.kind, list(t.scale), t.rotation, list(t.translation), list(t.pivot), t.operation_order]
                      if t.node == texture_node else t.node for t in uv.transforms if not t.ours]
        return json.dumps([primvar, reader, transforms, connected])
    transforms = [
        [t.kind, list(t.scale), t.rotation, list(t.translation), list(t.pivot), t.operation_order]
        if t.node == texture_node or ours(t.node) else t.node
        for t in uv.transforms
    ]
    connected = uv.connected_from
    if connected and ours(connected.rsplit(".", 1)[0]):
        connected = Recorded.MTLX_UV_NODE  # read through its values above, whichever scope holds it
    reader, primvar = uv.reader, uv.primvar
    if reader and reader.rsplit("/", 1)[-1] == Recorded.MTLX_UV_READER:
        reader = primvar = None  # the UV0 reader it inserted, in whichever scope: the image's default UVs, as before
    return json.dumps([primvar, reader, transforms, connected])


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
