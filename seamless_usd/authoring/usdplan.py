"""Planning the USD edits of a list of stack results on one stage (see ``usd.py``)."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Iterable

from pxr import Gf, Sdf, Usd, UsdShade

from seamless_usd.authoring.files import SET_BY_HAND, relative_asset_path, set_by_hand
from seamless_usd.authoring.schema import PROPERTIES, Q_PROPERTIES, Schema, has_applied, read_provenance, schemas_known
from seamless_usd.authoring.types import (TURN_NOT_AUTHORED, AuthoringResult, Codes, Provenance, StackResult,
                                          node_key, shared_with)
from seamless_usd.authoring.usdedits import _Edit, _EditKind, variant_edit_target, variant_not_composed
from seamless_usd.authoring.usduv import _UVPlanner
from seamless_usd.authoring.usdnodes import (
    Names,
    _close,
    _kind,
    _Kind,
    _producing_attr,
    _same_file,
)
from seamless_usd.textures import Origin
from seamless_usd.discover.variants import apply_selection
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = []


class _Author(_UVPlanner):
    """Plans the edits for a list of stack results on one stage, then applies them."""

    def __init__(self, stage: Usd.Stage, result: AuthoringResult, anchor_dir: Path | None,
                 layer_names: dict | None = None):
        self.stage = stage
        self.result = result
        self.anchor_dir = anchor_dir
        self.layer_names = layer_names or {}
        self.edits: list[_Edit] = []
        self._done: dict[str, tuple[str, tuple[float, float], str]] = {}  # node -> (out, scale, material)
        self._uv_nodes: dict[tuple, Sdf.Path] = {}  # (parent, source, scale) -> inserted node
        self._reserved: set[Sdf.Path] = set()
        self._uv_updates: dict[tuple, tuple[float, float]] = {}  # (marked node, selection) -> total scale
        self.target_for = None
        self.one_layer = False
        self.owners: list[str] = []  # the stack id of each planned edit, in order ("" for one of no map's)
        self._anchor: Sdf.Layer | None = None  # one_layer: the layer of the current texture's file value
        self._anchor_node = None  # ... and the composition node holding it (a variant's: the edits stay inside it)
        self.planned_maps = 0
        self.variant_layer: Sdf.Layer | None = None  # new-layer mode: edits follow the opinion's variant
        self._context: Usd.EditTarget | None = None  # the current map's edit target (variant_layer or one_layer)
        self._refused: str | None = None  # why an edit target of the current map was refused
        self._selection: tuple = ()  # the variant selection the stage is composed under

    # -- planning ------------------------------------------------------------------------

    def plan_all(self, results: Iterable[StackResult], target_for, variant_layer: Sdf.Layer | None = None,
                 selections: bool = False, one_layer: bool = False) -> None:
        """``target_for(prim, attr_or_None) -> Usd.EditTarget | Finding`` picks where edits go; with ``one_layer``
        (in place) every edit of one texture goes where its file value is (its UV link and transform too, which a
        weaker layer, a library's, may hold: edited there, every stage using it would change).

        With ``variant_layer`` (a new layer over the stage) a map whose file value is authored
        inside a variant gets its edits inside the same variant of that layer, so the other
        variants keep their own textures; ``target_for`` is then not used. With ``selections``
        (a stage of our own), a stack found under another variant selection is planned with the
        stage composed under that selection (authored in its session layer, which is then cleared).
        """
        self.target_for = target_for
        self.variant_layer = variant_layer
        self.one_layer = one_layer
        if not schemas_known():
            self._find(Severity.WARNING, Codes.SCHEMA_NOT_REGISTERED, asset_ref(Schema.TILE_API),
                       "USD's schema registry was built before seamless_usd.authoring was "
                       "imported: provenance is written, but this process does not know the schema")
        results = list(results)
        if selections:  # one composition per selection, the stage's own first
            results.sort(key=lambda r: r.stack.selection != ())
        composed = ()
        for stack_result in results:
            if stack_result.stack.selection and not selections:  # a DCC's open stage: not recomposed
                finding = variant_not_composed(stack_result.stack)
                self.result.findings.append(finding)
                self.result.not_written += [(node_key(m.map), finding.message)
                                            for m in stack_result.maps if m.map.origin is Origin.USD]
                continue
            selection = stack_result.stack.selection if selections else ()
            if selection != composed:
                apply_selection(self.stage.GetSessionLayer(), selection)
                composed = selection
            self._selection = selection
            for map_result in stack_result.maps:
                if map_result.map.origin is Origin.USD:  # MaterialX documents: author_mtlx
                    self.planned_maps += 1
                    why = self._plan_map(map_result, stack_result)
                    self.owners += [stack_result.stack.id] * (len(self.edits) - len(self.owners))
                    if why:
                        self.result.not_written.append((node_key(map_result.map), why))
        if composed:
            apply_selection(self.stage.GetSessionLayer(), ())
    def plan_retarget(self, document: Path, new_document: Path, target: Usd.EditTarget) -> None:
        """Point references to ``document`` at ``new_document`` (delete + prepend, so other
        references of the prim stay as they are; Pcp anchors both before matching)."""
        anchor = self.anchor_dir or document.parent
        seen = set()
        for prim in self.stage.TraverseAll():
            for spec in prim.GetPrimStack():
                for ref in spec.referenceList.GetAddedOrExplicitItems():
                    if not ref.assetPath or (prim.GetPath(), ref.primPath) in seen:
                        continue
                    if not _same_file(spec.layer.ComputeAbsolutePath(ref.assetPath), str(document)):
                        continue
                    seen.add((prim.GetPath(), ref.primPath))
                    old = Sdf.Reference(relative_asset_path(document, anchor), ref.primPath, ref.layerOffset)
                    new = Sdf.Reference(relative_asset_path(new_document, anchor), ref.primPath,
                                        ref.layerOffset)
                    self.edits.append(_Edit(target, _EditKind.RETARGET, prim.GetPath(), value=(old, new)))

    def _find(self, severity: Severity, code: str, where: str, message: str) -> None:
        self.result.findings.append(Finding(severity, code, where, message))

    def _target(self, prim: Usd.Prim, attr: Usd.Attribute | None = None) -> Usd.EditTarget | None:
        if self._context is not None:
            target = self._context
        else:
            target = (self.target_for(prim, attr, self._anchor, self._anchor_node) if self._anchor is not None
                      else self.target_for(prim, attr))
        if isinstance(target, Finding):
            self.result.findings.append(target)
            self._refused = self._refused or target.message
            return None
        return target

    def _plan_map(self, map_result, stack_result: StackResult) -> str | None:
        """Plan one map's edits; the reason when nothing can be written for it (else None)."""
        tex_map = map_result.map
        node_path = tex_map.node.strip("<>")
        prim = self.stage.GetPrimAtPath(node_path)
        if not prim:
            why = "texture node not found on the stage; nothing written for it"
            self._find(Severity.ERROR, Codes.MISSING_PRIM, prim_ref(node_path), why)
            return why
        if prim.IsInstanceProxy() and not self.one_layer:  # in place, edits go into the prototype's own layer
            why = ("texture inside an instance: edit its prototype's source (--in-place) or make it "
                   "non-instanceable")
            self._find(Severity.SKIPPED, Codes.INSTANCE_PROXY, prim_ref(node_path), why)
            return why
        out = str(Path(map_result.output_path).resolve())
        if not Path(out).is_file() and not self.result.dry_run:  # a dry run plans unwritten tiles
            why = f"tileable file {asset_ref(out)} not found; nothing written for it"
            self._find(Severity.ERROR, Codes.MISSING_OUTPUT, asset_ref(out),
                       f"tileable file for {prim_ref(node_path)} not found; nothing written for it")
            return why
        scale = (float(stack_result.uv_scale[0]), float(stack_result.uv_scale[1]))
        done_key = (node_path, tex_map.selection)  # one node under two selections: two sets of edits
        done = self._done.get(done_key)
        if done is not None:
            if done[0] != out or not _close(done[1], scale):
                self._find(
                    Severity.WARNING, Codes.SHARED_CONFLICT, prim_ref(node_path),
                    f"texture node shared by {done[2]} and {tex_map.material} with different "
                    f"results; kept {done[2]}'s. Give each material its own texture node to "
                    "process them separately",
                )
                self.result.not_written_for.append((tex_map.material, node_key(tex_map), shared_with(done[2])))
            return None
        self._done[done_key] = (out, scale, tex_map.material)
        first_edit = len(self.edits)
        self._refused = None
        self._context = self._anchor = self._anchor_node = None
        try:
            why = self._plan_texture(prim, tex_map, out, scale, stack_result)
        finally:
            self._context = self._anchor = self._anchor_node = None
        why = why or self._refused
        if why:
            del self.edits[first_edit:]  # all of a map's edits or none
            return why
        if len(self.edits) > first_edit and prim_ref(node_path) not in self.result.edited_prims:
            self.result.edited_prims.append(prim_ref(node_path))
        return None

    def _plan_texture(self, prim, tex_map, out: str, scale, stack_result: StackResult) -> str | None:
        shader = UsdShade.Shader(prim)
        kind = _kind(shader)
        if self.variant_layer is not None:
            file_attr = self._file_attr(prim, shader, tex_map)
            context = variant_edit_target(self.variant_layer, prim, file_attr)
            if isinstance(context, Finding):
                self.result.findings.append(context)
                return context.message
            self._context = context
        elif self.one_layer:  # the layer of the file value: every edit of this texture goes there
            file_attr = self._file_attr(prim, shader, tex_map)
            stack = file_attr.GetPropertyStack(Usd.TimeCode.Default()) if file_attr else []
            self._anchor = stack[0].layer if stack else None
            self._anchor_node = file_attr.GetResolveInfo(Usd.TimeCode.Default()).GetNode() if stack else None
        if stack_result.wrap_only:  # already tileable: the source stays, it only has to repeat
            self._plan_wrap(prim, shader, kind)
            return None
        recorded = read_provenance(prim)
        from_source = recorded is None or _same_file(
            prim.GetAttribute(Schema.SOURCE_ASSET).Get(), tex_map.resolved)
        if not self._plan_file(prim, shader, tex_map, out):
            return self._refused or "its file input cannot be edited"
        self._plan_wrap(prim, shader, kind)
        applied = self._plan_uv(prim, shader, kind, scale, recorded, from_source, stack_result.uv_turn)
        if applied is None:  # the UV edit cannot be made: leave this map untouched
            return self._refused or "its UV input cannot be edited"
        if stack_result.uv_turn and not applied[1] and from_source:
            self._find(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(prim.GetPath()),
                       TURN_NOT_AUTHORED)
        if recorded and not from_source:  # made from an earlier tile: keep the origin
            origin = prim.GetAttribute(Schema.SOURCE_ASSET).Get()
            source = origin.resolvedPath or origin.path
        else:
            source = tex_map.resolved
        self._plan_provenance(prim, stack_result.provenance, applied, source)
        return None

    def _file_attr(self, prim, shader, tex_map) -> Usd.Attribute | None:
        at = tex_map.file_at
        owner = self.stage.GetPrimAtPath(at.prim.strip("<>")) if at and at.prim else None
        attr = owner.GetAttribute(at.attribute) if owner else None
        return attr or _producing_attr(shader.GetInput(Names.FILE))

    def _plan_file(self, prim, shader, tex_map, out: str) -> bool:
        """Plan the new asset path where it is authored; False when it cannot be edited."""
        at = tex_map.file_at
        owner = self.stage.GetPrimAtPath(at.prim.strip("<>")) if at.prim else None
        attr = owner.GetAttribute(at.attribute) if owner else None
        if not attr:
            attr = _producing_attr(shader.GetInput(Names.FILE))
        if not attr:
            self._find(Severity.ERROR, Codes.MISSING_PRIM, prim_ref(prim.GetPath()),
                       "no file input found to edit")
            return False
        current = attr.Get()
        if isinstance(current, Sdf.AssetPath) and _same_file(current, out):
            return True
        by_hand = _set_by_hand(attr, current, tex_map.resolved, self.layer_names)
        if by_hand:
            self._refused = by_hand
            return False
        own = shader.GetInput(Names.FILE)
        reads = _producing_attr(own) if own else None
        if attr.GetPrim() != prim and own and (_other_readers(prim, attr) or reads is None
                                               or reads.GetPath() != attr.GetPath()):
            # an input of the material (or a node graph) that other textures read as well (a decal left alone, a
            # node reading another channel): this texture's own file is set, and its connection to it cut (an
            # earlier run cut it already when the node no longer reads that input)
            if reads is not None and reads.GetPrim() == prim and _same_file(own.GetAttr().Get(), out):
                return True
            target = self._target(prim, own.GetAttr())
            if target is None:
                return False
            self.edits += [_Edit(target, _EditKind.VALUE, own.GetAttr().GetPath(), own.GetAttr().GetTypeName(),
                                 Sdf.AssetPath(self._asset_path(out, target))),
                           _Edit(target, _EditKind.CONNECT, own.GetAttr().GetPath(), own.GetAttr().GetTypeName())]
            return True
        target = self._target(attr.GetPrim(), attr)
        if target is None:
            return False
        self.edits.append(_Edit(target, _EditKind.VALUE, attr.GetPath(), attr.GetTypeName(),
                                Sdf.AssetPath(self._asset_path(out, target)), attr.GetVariability()))
        return True

    def _asset_path(self, out: str, target: Usd.EditTarget) -> str:
        layer = target.GetLayer()
        anchor = self.anchor_dir
        if anchor is None and not layer.anonymous and layer.realPath:
            anchor = Path(layer.realPath).parent
        if anchor is None:
            if not any(f.code == Codes.ANONYMOUS_ANCHOR for f in self.result.findings):  # once, not for every map
                self._find(Severity.WARNING, Codes.ANONYMOUS_ANCHOR, asset_ref(layer.identifier),
                           "the layer the edits go to has no file yet, so the tiles' asset paths are absolute (save "
                           "it to a file first, or author into a layer that has one, for relative paths)")
            return Path(out).as_posix()
        return relative_asset_path(Path(out), anchor)

    def _plan_input_value(self, prim, shader, name: str, type_name, value) -> None:
        """Set input ``name`` where its value is authored (interface input) or on the node."""
        shade_input = shader.GetInput(name)
        attr = _producing_attr(shade_input) if shade_input else None
        if attr is None:
            attr = prim.GetAttribute(f"inputs:{name}")
        current = attr.Get() if attr else None
        if current == value or (isinstance(value, tuple) and _close(current, value, 1e-9)) or (
                isinstance(value, float) and current is not None and _close((current,), (value,), 1e-6)):
            return  # a float input holds float32: an angle read back is equal to 1e-6, not exactly
        path = attr.GetPath() if attr else prim.GetPath().AppendProperty(f"inputs:{name}")
        if attr:
            type_name = attr.GetTypeName()
        target = self._target(attr.GetPrim() if attr else prim, attr)
        if target is None:
            return
        if isinstance(value, tuple):
            value = Gf.Vec2f(*value)
        self.edits.append(_Edit(target, _EditKind.VALUE, path, type_name, value))

    def _plan_wrap(self, prim, shader, kind: str) -> None:
        if kind == _Kind.USD_UV_TEXTURE:
            for name in (Names.WRAP_S, Names.WRAP_T):
                self._plan_input_value(prim, shader, name, Sdf.ValueTypeNames.Token, Names.REPEAT)
        elif kind in (_Kind.MX_IMAGE, _Kind.MX_GLTF):
            for name in (Names.U_ADDRESS, Names.V_ADDRESS):
                self._plan_input_value(prim, shader, name, Sdf.ValueTypeNames.String, Names.PERIODIC)

    def _plan_provenance(self, prim, provenance: Provenance, applied, source_file: str) -> None:
        """Record provenance; the source is this map's own file, relative to the edit layer; ``applied``: the
        (UV scale, UV turn) the UV edits apply."""
        target = self._target(prim, None)
        if target is None:
            return
        source = self._asset_path(source_file, target) if source_file else provenance.source_asset
        p = replace(provenance, uv_scale=tuple(applied[0]), uv_turn=float(applied[1]), source_asset=source)
        if read_provenance(prim) == p:
            return
        if not has_applied(prim, Schema.TILE_API):
            self.edits.append(_Edit(target, _EditKind.SCHEMA, prim.GetPath(), value=Schema.TILE_API))
        for name, (type_name, convert) in PROPERTIES.items():
            if (name in Q_PROPERTIES and p.q_passed is None) or (name == Schema.MODEL_HASH and not p.model_hash):
                # Q never ran / no network made it: nothing recorded (an earlier run's value is blocked)
                earlier = prim.GetAttribute(name)
                if earlier and earlier.HasAuthoredValue() and earlier.Get() is not None:
                    self.edits.append(_Edit(target, _EditKind.VALUE, prim.GetPath().AppendProperty(name), type_name,
                                            Sdf.ValueBlock()))
                continue
            self.edits.append(_Edit(target, _EditKind.VALUE, prim.GetPath().AppendProperty(name), type_name,
                                    convert(p)))

    # -- applying ------------------------------------------------------------------------

    def apply(self) -> None:
        """Record the plan and, unless dry-running, apply it in one change block."""
        recorded: set = set()
        for edit in self.edits:
            layer = edit.target.GetLayer()
            name = self.layer_names.get(layer) or _layer_name(layer)
            if edit.kind == _EditKind.VALUE and edit.path.IsPropertyPath() and edit.path.name.startswith("seamless:"):
                prim = edit.path.GetPrimPath()  # provenance: one line per node, not its (planned) values
                if prim not in recorded:
                    recorded.add(prim)
                    self.result.plan.append(f"record the tile's provenance (seamless:* of {Schema.TILE_API}) on "
                                            f"{prim_ref(prim)} in {asset_ref(name)}")
                continue
            self.result.plan.append(edit.describe(name))
        if self.result.dry_run:
            return
        with Sdf.ChangeBlock():
            for edit in self.edits:
                edit.apply()



def _layer_name(layer: Sdf.Layer) -> str:
    return layer.realPath or layer.identifier


def _other_readers(prim: Usd.Prim, attr: Usd.Attribute) -> list[Usd.Prim]:
    """The texture nodes other than ``prim`` whose file value comes from ``attr`` (an input of the material or of a
    node graph), under the material that holds ``prim``."""
    material = prim.GetParent()
    while material and not material.IsA(UsdShade.Material):
        material = material.GetParent()
    if not material:
        return []
    return [p for p in Usd.PrimRange(material) if p != prim and p.IsA(UsdShade.Shader)
            and (reader := _producing_attr(UsdShade.Shader(p).GetInput(Names.FILE))) is not None
            and reader.GetPath() == attr.GetPath()]


def _set_by_hand(attr: Usd.Attribute, current, scanned: str, layer_names: dict) -> str | None:
    """Why the file value ``current`` the stage composes is left as it is, or None. It differs from the value the
    scan read (``scanned``, the stage without the layer being edited) only where that layer (a new layer an earlier
    run wrote) holds a value of its own: a tile of this tool's is replaced, any other file was set there by hand."""
    if not isinstance(current, Sdf.AssetPath) or not set_by_hand(current.resolvedPath, scanned):
        return None
    stack = attr.GetPropertyStack(Usd.TimeCode.Default())
    where = f" in {asset_ref(layer_names.get(stack[0].layer) or _layer_name(stack[0].layer))}" if stack else ""
    return SET_BY_HAND.format(where=where, asset=asset_ref(current.path), kind="layer")
