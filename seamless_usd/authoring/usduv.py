"""Planning a texture's UV edits on a USD stage: the UV scale node after its existing chain and, for a
straightened tile turned back in the UVs, the turn node before it (see :mod:`.uvmath`, :func:`.uvmath.turn_inputs`).

``texture <- SeamlessUV (scale) <- SeamlessUVTurn (turn, only for a turned tile) <- the existing chain``. A later
run finds both by ``SeamlessUVTransformAPI`` and updates them (a turn no longer wanted is set to the identity).
"""
from __future__ import annotations

from pxr import Gf, Sdf, Usd, UsdShade

from seamless_usd.authoring.schema import Schema, is_seamless_uv_transform
from seamless_usd.authoring.types import Codes, UVTurn
from seamless_usd.authoring.usdedits import _Edit, _EditKind, variant_edit_target
from seamless_usd.authoring.usdnodes import (
    Names,
    _connected,
    _connection_source_attr,
    _gltf_transform_is_identity,
    _Kind,
    _uv_input_name,
    _value,
)
from seamless_usd.authoring.uvmath import composed_turn, scale_node_value, total_from_node, turn_inputs, turn_of_inputs
from seamless_usd.findings import Severity, prim_ref

__all__ = []

#: The name of the inserted turn node (the scale node is ``Names.UV_NODE``).
UV_TURN_NODE = "SeamlessUVTurn"


class _UVPlanner:
    """The UV part of :class:`.usdplan._Author` (which holds the stage, the edits and the targets)."""

    def _plan_uv(self, prim, shader, kind, scale, recorded, from_source, turn: UVTurn | None
                 ) -> tuple[tuple[float, float], float] | None:
        """Plan the UV scale (and turn); return (the total scale now applied after the original chain, the degrees
        the UVs turn the tile back), or None when the UV edit cannot be made."""
        prior = recorded.uv_scale if recorded else None
        if kind == _Kind.MX_TILED:
            total = scale if from_source or prior is None else (prior[0] * scale[0], prior[1] * scale[1])
            undo = prior or (1.0, 1.0)
            tiling = _value(shader.GetInput(Names.UV_TILING), (1.0, 1.0))
            offset = _value(shader.GetInput(Names.UV_OFFSET), (0.0, 0.0))
            base_t = (tiling[0] / undo[0], tiling[1] / undo[1])
            base_o = (offset[0] / undo[0], offset[1] / undo[1])
            f32 = Sdf.ValueTypeNames.Float2
            self._plan_input_value(prim, shader, Names.UV_TILING, f32,
                                   (base_t[0] * total[0], base_t[1] * total[1]))
            self._plan_input_value(prim, shader, Names.UV_OFFSET, f32,
                                   (base_o[0] * total[0], base_o[1] * total[1]))
            return total, 0.0  # a tiledimage's UVs cannot turn
        if kind == _Kind.OTHER:
            self._find(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(prim.GetPath()),
                       f"unknown texture node {shader.GetShaderId()!r}; file replaced, UVs not scaled")
            return (1.0, 1.0), 0.0
        if kind == _Kind.MX_GLTF and not _gltf_transform_is_identity(shader):
            self._find(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(prim.GetPath()),
                       "gltf image node with its own UV transform: scale it by hand")
            return (1.0, 1.0), 0.0
        uv_input = shader.GetInput(_uv_input_name(kind))
        source = _connected(uv_input)
        place = kind != _Kind.USD_UV_TEXTURE
        uv_path = prim.GetPath().AppendProperty(f"inputs:{_uv_input_name(kind)}")
        if source is None and not place:
            self._find(Severity.WARNING, Codes.NO_UV, prim_ref(prim.GetPath()),
                       "texture coordinates are not connected; UVs not scaled")
            return (1.0, 1.0), 0.0
        if source is not None and is_seamless_uv_transform(source.GetPrim()):
            return self._update_uv(UsdShade.Shader(source.GetPrim()), scale, from_source, turn, place)
        target = self._target(prim, uv_input.GetAttr() if uv_input else None)
        if target is None:
            return None
        # a MaterialX image with no texcoord reads UV0; the place2d inserted before it reads it through a texcoord
        # node (a place2d's own default is a constant (0, 0))
        source_attr = _connection_source_attr(uv_input) if source is not None else self._uv0_reader(prim, target)
        outside = self._outside_variant(prim, uv_input.GetAttr(), target) if source is not None and not turn else None
        if outside is not None:  # one node where the connection is; each variant's scale inside that variant
            key = (str(prim.GetPath().GetParentPath()), str(source_attr), None, None, place, "outside")
        else:
            key = (str(prim.GetPath().GetParentPath()), str(source_attr), scale, turn, place, self._selection)
        node_path = self._uv_nodes.get(key)
        value = {Names.SCALE: scale_node_value(scale, turn.aspect if turn else 1.0, place)}
        if node_path is None:
            if turn is not None:
                source_attr = self._new_turn_node(prim, target, source_attr, turn.degrees, turn.aspect, place)
            node_path = self._new_uv_node(prim, outside or target, source_attr, Names.UV_NODE, place,
                                          {} if outside else value)
            self._uv_nodes[key] = node_path
        if outside is not None:
            self.edits.append(_Edit(_sibling_in_variant(prim, target), _EditKind.VALUE,
                                    node_path.AppendProperty(f"inputs:{Names.SCALE}"), Sdf.ValueTypeNames.Float2,
                                    Gf.Vec2f(*value[Names.SCALE])))
        out_name = Names.OUT if place else Names.RESULT
        self.edits.append(_Edit(outside or target, _EditKind.CONNECT, uv_path, Sdf.ValueTypeNames.Float2,
                                node_path.AppendProperty(f"outputs:{out_name}")))
        return scale, (turn.degrees if turn else 0.0)

    def _outside_variant(self, prim, uv_attr: Usd.Attribute, target: Usd.EditTarget) -> Usd.EditTarget | None:
        """Where the texture-coordinate connection ``uv_attr`` is authored, when the texture's edits go inside a
        variant (its file is set there) and the connection outside it: an ``st`` connected once for every variant.
        A connection made inside the variant would lose to it, so the UV scale node goes where the connection is, and
        each variant's scale inside that variant (the node holds no scale of its own: a variant that does not set
        one reads the identity). None when the connection is edited with the rest."""
        def in_variant(t) -> bool:
            return t.MapToSpecPath(prim.GetPath()).ContainsPrimVariantSelection()

        if not in_variant(target) or not uv_attr or not uv_attr.GetPropertyStack(Usd.TimeCode.Default()):
            return None
        if self.variant_layer is not None:
            outside = variant_edit_target(self.variant_layer, prim, uv_attr)
        elif self.one_layer:
            outside = self.target_for(prim, uv_attr)
        else:
            return None
        return outside if isinstance(outside, Usd.EditTarget) and not in_variant(outside) else None

    def _uv0_reader(self, prim, target) -> Sdf.Path:
        """The output of a MaterialX ``texcoord`` node (index 0) beside ``prim``, made once per material and
        selection: what a MaterialX image with no texcoord input reads."""
        parent = prim.GetPath().GetParentPath()
        key = (str(parent), "uv0", self._selection)
        if key not in self._uv_nodes:
            path = self._free_sibling(prim, Names.UV_READER)
            target = self._sibling_target(prim, target)
            self.edits += [
                *_defined(target, path, Names.MX_TEXCOORD),
                _Edit(target, _EditKind.VALUE, path.AppendProperty("inputs:index"), Sdf.ValueTypeNames.Int, 0),
                _Edit(target, _EditKind.VALUE, path.AppendProperty(f"outputs:{Names.OUT}"), Sdf.ValueTypeNames.Float2,
                      None),
            ]
            self._uv_nodes[key] = path.AppendProperty(f"outputs:{Names.OUT}")
        return self._uv_nodes[key]

    def _update_uv(self, node: UsdShade.Shader, scale, from_source: bool, turn: UVTurn | None, place: bool):
        """Update the UV scale node a run before inserted (and the turn before it, adding one where a turn is
        wanted now); the maps of one stack share it and update it once."""
        key = (node.GetPath(), self._selection)
        if key in self._uv_updates:
            return self._uv_updates[key]
        in_name = Names.TEXCOORD if place else Names.IN
        upstream = _connected(node.GetInput(in_name))
        turn_node = (UsdShade.Shader(upstream.GetPrim()) if upstream is not None
                     and is_seamless_uv_transform(upstream.GetPrim()) else None)
        prior_degrees, prior_aspect = (turn_of_inputs(_value(turn_node.GetInput(Names.SCALE), (1.0, 1.0)),
                                                      _value(turn_node.GetInput(_rotation(place)), 0.0), place)
                                       if turn_node is not None else (0.0, 1.0))
        prior = total_from_node(_value(node.GetInput(Names.SCALE), (1.0, 1.0)), prior_aspect, place)
        total, degrees, aspect = composed_turn((*prior, prior_degrees, prior_aspect), scale, turn, from_source)
        if turn_node is None and upstream is None:  # nothing feeds the scale node (edited by hand): no turn to insert
            degrees, aspect = 0.0, 1.0
        if turn_node is not None:
            turn_scale, rotation = turn_inputs(degrees, aspect, place)
            self._plan_input_value(turn_node.GetPrim(), turn_node, Names.SCALE, Sdf.ValueTypeNames.Float2, turn_scale)
            self._plan_input_value(turn_node.GetPrim(), turn_node, _rotation(place), Sdf.ValueTypeNames.Float,
                                   rotation)
        elif degrees:
            target = self._target(node.GetPrim(), node.GetInput(in_name).GetAttr())
            if target is None:
                return None
            source_attr = self._new_turn_node(node.GetPrim(), target, _connection_source_attr(node.GetInput(in_name)),
                                              degrees, aspect, place)
            self.edits.append(_Edit(target, _EditKind.CONNECT, node.GetInput(in_name).GetAttr().GetPath(),
                                    Sdf.ValueTypeNames.Float2, source_attr))
        self._plan_input_value(node.GetPrim(), node, Names.SCALE, Sdf.ValueTypeNames.Float2,
                               scale_node_value(total, aspect, place))
        self._uv_updates[key] = (total, degrees)
        return total, degrees

    def _new_turn_node(self, prim, target, source_attr: Sdf.Path, degrees: float, aspect: float, place: bool
                       ) -> Sdf.Path:
        """A turn node fed by ``source_attr``, beside ``prim``; its output's path."""
        turn_scale, rotation = turn_inputs(degrees, aspect, place)
        path = self._new_uv_node(prim, target, source_attr, UV_TURN_NODE, place,
                                 {Names.SCALE: turn_scale, _rotation(place): rotation})
        return path.AppendProperty(f"outputs:{Names.OUT if place else Names.RESULT}")

    def _new_uv_node(self, prim, target, source_attr: Sdf.Path, base: str, place: bool, inputs: dict
                     ) -> Sdf.Path:
        """A new UsdTransform2d (``place``: MaterialX place2d) named ``base`` (or ``base_N``) beside ``prim``,
        fed by ``source_attr``, holding ``inputs`` (name -> a float or a pair), marked as this tool's."""
        path = self._free_sibling(prim, base)
        target = self._sibling_target(prim, target)
        f2 = Sdf.ValueTypeNames.Float2
        if place:
            node_id, in_name, out_name = Names.MX_PLACE_2D, Names.TEXCOORD, Names.OUT
        else:
            node_id, in_name, out_name = Names.USD_TRANSFORM_2D, Names.IN, Names.RESULT
        self.edits += [
            *_defined(target, path, node_id),
            _Edit(target, _EditKind.CONNECT, path.AppendProperty(f"inputs:{in_name}"), f2, source_attr),
        ]
        for input_name, value in inputs.items():
            pair = isinstance(value, tuple)
            self.edits.append(_Edit(target, _EditKind.VALUE, path.AppendProperty(f"inputs:{input_name}"),
                                    f2 if pair else Sdf.ValueTypeNames.Float,
                                    Gf.Vec2f(*value) if pair else float(value)))
        self.edits += [
            _Edit(target, _EditKind.VALUE, path.AppendProperty(f"outputs:{out_name}"), f2, None),
            _Edit(target, _EditKind.SCHEMA, path, value=Schema.UV_TRANSFORM_API),
        ]
        return path

    def _free_sibling(self, prim, base: str) -> Sdf.Path:
        """A path beside ``prim`` named ``base`` (or ``base_N``) that no prim of the stage, nor a node planned under
        this selection, holds; reserved."""
        parent = prim.GetPath().GetParentPath()
        path, n = parent.AppendChild(base), 0
        while self.stage.GetPrimAtPath(path) or (path, self._selection) in self._reserved:
            n += 1
            path = parent.AppendChild(f"{base}_{n}")
        self._reserved.add((path, self._selection))
        return path

    def _sibling_target(self, prim, target: Usd.EditTarget) -> Usd.EditTarget:
        """Where a new sibling of ``prim`` is defined: ``target``'s layer, mapped through the
        parent's own prim-index node. A node's mapping may cover only its own prim (a material
        authored inside a variant: ``/Set/Floor{floorVariant=Tiled}Looks/M``), so a sibling
        mapped through the texture's node would land outside that variant."""
        if self._context is not None:
            return target
        parent_target = self.target_for(prim.GetParent(), None)
        if isinstance(parent_target, Usd.EditTarget) and parent_target.GetLayer() == target.GetLayer():
            return parent_target
        return target


def _sibling_in_variant(prim: Usd.Prim, target: Usd.EditTarget) -> Usd.EditTarget:
    """An edit target for a sibling of ``prim`` inside the variant ``target`` edits ``prim`` in: mapped through the
    parent's prim-index node at the same site (a target mapped through ``prim``'s own node may not reach its
    siblings), or ``target`` itself."""
    site = target.MapToSpecPath(prim.GetPath()).GetParentPath()
    index = prim.GetParent().GetPrimIndex() if prim.GetParent() else None
    nodes = [index.rootNode] if index and index.IsValid() else []
    while nodes:
        node = nodes.pop()
        if node.path == site and target.GetLayer() in node.layerStack.layers:
            return Usd.EditTarget(target.GetLayer(), node)
        nodes += list(node.children)
    return target


def _defined(target: Usd.EditTarget, path: Sdf.Path, node_id: str) -> list[_Edit]:
    """The edits that define a shader node of ``node_id`` at ``path``."""
    return [_Edit(target, _EditKind.DEFINE, path, value=f"{node_id} node"),
            _Edit(target, _EditKind.VALUE, path.AppendProperty(Names.INFO_ID), Sdf.ValueTypeNames.Token, node_id,
                  Sdf.VariabilityUniform)]


def _rotation(place: bool) -> str:
    """The turn's input: a place2d's ``rotate`` (clockwise), a UsdTransform2d's ``rotation`` (counter-clockwise)."""
    return Names.ROTATE if place else Names.ROTATION
