"""The UV edits of a MaterialX ``image`` node (:mod:`.mtlx`): a ``place2d`` that scales its texture coordinates
after the existing chain and, for a straightened tile turned back in the UVs, a ``place2d`` that turns them before
it (:func:`.uvmath.turn_inputs`).

``image.texcoord <- seamless_uv (scale) <- seamless_uv_turn (turn, only for a turned tile) <- the existing chain``.
A later run finds both by their ``seamless_uvtransform`` attribute ("true" on the scale, "turn" on the turn) and
updates them (a turn no longer wanted is set to the identity).
"""
from __future__ import annotations

import MaterialX as mx

from seamless_usd.authoring.mtlxinputs import MtlxNames, fmt, set_vector2, vector2
from seamless_usd.authoring.types import UVTurn
from seamless_usd.authoring.uvmath import composed_turn, scale_node_value, total_from_node, turn_inputs, turn_of_inputs
from seamless_usd.findings import prim_ref

__all__ = []


def _pair(node: mx.Node, name: str, default: tuple[float, float]) -> tuple[float, float]:
    inp = node.getInput(name)
    return vector2(inp.getValueString()) if inp is not None and inp.getValueString() else default


def _number(node: mx.Node, name: str) -> float:
    inp = node.getInput(name)
    return float(inp.getValueString()) if inp is not None and inp.getValueString() else 0.0


class _PlaceUV:
    """The place2d part of :class:`.mtlx._MtlxAuthor` (which holds the document and the plan)."""

    def _place2d(self, node: mx.Node, scale, from_source: bool, turn: UVTurn | None
                 ) -> tuple[tuple[float, float], float]:
        """Scale (and turn) ``node``'s texture coordinates; (the total UV scale, the degrees the UVs turn the tile
        back)."""
        tex_in = node.getInput(MtlxNames.TEXCOORD)
        upstream = tex_in.getConnectedNode() if tex_in is not None else None
        if upstream is not None and upstream.getAttribute(MtlxNames.MARK_UV) == "true":
            return self._update_place2d(upstream, scale, from_source, turn)
        parent = node.getParent()
        connection = tuple(
            (a, tex_in.getAttribute(a)) for a in MtlxNames.CONNECTION_ATTRS
            if tex_in is not None and tex_in.hasAttribute(a))
        key = (parent.getNamePath(), connection, scale, turn)
        name = self._uv_nodes.get(key)
        if name is None:
            aspect = 1.0
            if not connection:  # the image read its default UVs (UV0); a place2d's own default is a constant (0, 0)
                connection = (("nodename", self._uv0(parent).getName()),)
            if turn is not None:
                turned = self._new_turn(parent, connection, turn.degrees, turn.aspect)
                connection, aspect = (("nodename", turned.getName()),), turn.aspect
            name = parent.createValidChildName(MtlxNames.UV_NODE)
            place = parent.addNode(MtlxNames.PLACE_2D, name, MtlxNames.VECTOR2)
            place.setAttribute(MtlxNames.MARK_UV, "true")
            _feed(place, connection)
            set_vector2(place.addInput(MtlxNames.SCALE, MtlxNames.VECTOR2), scale_node_value(scale, aspect, True))
            self._uv_nodes[key] = name
            self._plan(f"add place2d {prim_ref(place.getNamePath())} scale = "
                       f"{place.getInput(MtlxNames.SCALE).getValueString()}")
        if tex_in is not None:
            node.removeInput(MtlxNames.TEXCOORD)
        coords = node.addInput(MtlxNames.TEXCOORD, MtlxNames.VECTOR2)
        coords.setNodeName(name)
        self._plan(f"connect {prim_ref(coords.getNamePath())} -> {prim_ref(name)}")
        return scale, (turn.degrees if turn else 0.0)

    def _update_place2d(self, place: mx.Node, scale, from_source: bool, turn: UVTurn | None):
        """Update the scale place2d a run before inserted (and the turn before it, adding one where a turn is wanted
        now); the maps of one stack share it and update it once."""
        key = place.getNamePath()
        if key in self._uv_updates:
            return self._uv_updates[key]
        tex_in = place.getInput(MtlxNames.TEXCOORD)
        upstream = tex_in.getConnectedNode() if tex_in is not None else None
        turn_node = upstream if upstream is not None and \
            upstream.getAttribute(MtlxNames.MARK_UV) == MtlxNames.MARK_TURN else None
        prior_degrees, prior_aspect = (turn_of_inputs(_pair(turn_node, MtlxNames.SCALE, (1.0, 1.0)),
                                                      _number(turn_node, MtlxNames.ROTATE), True)
                                       if turn_node is not None else (0.0, 1.0))
        prior = total_from_node(_pair(place, MtlxNames.SCALE, (1.0, 1.0)), prior_aspect, True)
        total, degrees, aspect = composed_turn((*prior, prior_degrees, prior_aspect), scale, turn, from_source)
        if turn_node is not None:
            self._set_turn(turn_node, degrees, aspect)
        elif degrees:
            connection = tuple((a, tex_in.getAttribute(a)) for a in MtlxNames.CONNECTION_ATTRS
                               if tex_in is not None and tex_in.hasAttribute(a))
            turned = self._new_turn(place.getParent(), connection, degrees, aspect)
            place.removeInput(MtlxNames.TEXCOORD)
            place.addInput(MtlxNames.TEXCOORD, MtlxNames.VECTOR2).setNodeName(turned.getName())
            self._plan(f"connect {prim_ref(place.getNamePath())}.texcoord -> {prim_ref(turned.getName())}")
        new = scale_node_value(total, aspect, True)
        current = _pair(place, MtlxNames.SCALE, (1.0, 1.0))
        if any(abs(new[i] - current[i]) > 1e-9 for i in range(2)):
            set_vector2(place.getInput(MtlxNames.SCALE) or place.addInput(MtlxNames.SCALE, MtlxNames.VECTOR2), new)
            self._plan(f"set {prim_ref(place.getNamePath())}.scale = {fmt(new)}")
        self._uv_updates[key] = (total, degrees)
        return total, degrees

    def _uv0(self, parent: mx.Element) -> mx.Node:
        """The ``texcoord`` node (index 0) in ``parent`` the inserted place2d nodes read, made once per scope: an image
        with no ``texcoord`` input reads UV0, but a place2d with none reads a constant (0, 0)."""
        reader = parent.getNode(MtlxNames.UV_READER)
        if reader is None or reader.getCategory() != MtlxNames.TEXCOORD:
            reader = parent.addNode(MtlxNames.TEXCOORD, parent.createValidChildName(MtlxNames.UV_READER),
                                    MtlxNames.VECTOR2)
            reader.addInput("index", "integer").setValueString("0")
            self._plan(f"add texcoord {prim_ref(reader.getNamePath())} (UV0) for the inserted place2d")
        return reader

    def _scale_connected(self, inp: mx.Input, name: str, total) -> None:
        """A ``tiledimage``'s ``uvtiling`` / ``uvoffset`` fed by another node (a constant, a graph): a ``multiply``
        node after that connection by the total UV scale (a value beside the connection would be a second binding,
        which MaterialX refuses); a run before's multiply node gets the new total."""
        upstream = inp.getConnectedNode()
        if upstream is not None and upstream.getAttribute(MtlxNames.MARK_UV) == MtlxNames.MARK_TILING:
            factor = upstream.getInput("in2") or upstream.addInput("in2", MtlxNames.VECTOR2)
            if _pair(upstream, "in2", (1.0, 1.0)) != tuple(total):
                set_vector2(factor, tuple(total))
                self._plan(f"set {prim_ref(factor.getNamePath())} = {fmt(tuple(total))}")
            return
        scope = inp.getParent().getParent()
        product = scope.addNode("multiply", scope.createValidChildName(f"seamless_{name}"), MtlxNames.VECTOR2)
        product.setAttribute(MtlxNames.MARK_UV, MtlxNames.MARK_TILING)
        first = product.addInput("in1", MtlxNames.VECTOR2)
        for attr in MtlxNames.CONNECTION_ATTRS:
            if inp.hasAttribute(attr) and attr != "value":
                first.setAttribute(attr, inp.getAttribute(attr))
                inp.removeAttribute(attr)
        set_vector2(product.addInput("in2", MtlxNames.VECTOR2), tuple(total))
        inp.setNodeName(product.getName())
        self._plan(f"add multiply {prim_ref(product.getNamePath())} = {name} x {fmt(tuple(total))}")

    def _new_turn(self, parent: mx.Element, connection: tuple, degrees: float, aspect: float) -> mx.Node:
        """A turn place2d in ``parent`` fed as ``connection`` says."""
        turned = parent.addNode(MtlxNames.PLACE_2D, parent.createValidChildName(MtlxNames.UV_TURN_NODE),
                                MtlxNames.VECTOR2)
        turned.setAttribute(MtlxNames.MARK_UV, MtlxNames.MARK_TURN)
        _feed(turned, connection)
        self._set_turn(turned, degrees, aspect)
        return turned

    def _set_turn(self, turned: mx.Node, degrees: float, aspect: float) -> None:
        turn_scale, rotate = turn_inputs(degrees, aspect, True)
        if _pair(turned, MtlxNames.SCALE, (1.0, 1.0)) != turn_scale or _number(turned, MtlxNames.ROTATE) != rotate:
            set_vector2(turned.getInput(MtlxNames.SCALE) or turned.addInput(MtlxNames.SCALE, MtlxNames.VECTOR2),
                        turn_scale)
            (turned.getInput(MtlxNames.ROTATE) or turned.addInput(MtlxNames.ROTATE, MtlxNames.FLOAT)
             ).setValueString(repr(float(rotate)))
            self._plan(f"set {prim_ref(turned.getNamePath())} rotate = {rotate:g}, scale = {fmt(turn_scale)}")


def _feed(place: mx.Node, connection: tuple) -> None:
    """Connect ``place``'s texcoord as ``connection`` ((attribute, value) pairs of an input) says."""
    if connection:
        coords = place.addInput(MtlxNames.TEXCOORD, MtlxNames.VECTOR2)
        for attr, value in connection:
            coords.setAttribute(attr, value)
