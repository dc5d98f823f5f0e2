"""Write tileable maps back into a USD stage: asset paths, wrap modes, UV scale, provenance.

Edits are planned with the Usd API on the composed stage (reading values where they are
authored), then applied with the Sdf API inside one ``Sdf.ChangeBlock``. Each planned edit names
its layer and the namespace mapping into it (a ``Usd.EditTarget``), so in-place edits land in the
layer holding the opinion even when it is reached through a reference.

The UV scale is a node of its own (``SeamlessUV``, a ``UsdTransform2d``, or an
``ND_place2d_vector2`` for MaterialX image nodes) inserted between the last node of the
existing UV chain and the texture's coordinate input, marked with ``SeamlessUVTransformAPI``.
Composition with the existing chain is exact for any rotation / translation / non-uniform scale
because nothing in the existing chain changes; a later run finds the marked node and updates its
scale instead of inserting another one. A texture node shared by several materials is edited
once; if the materials' results disagree the first is kept and a finding explains it.
"""
from __future__ import annotations

import contextlib
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Iterable, Sequence

from pxr import Ar, Gf, Sdf, Tf, Usd, UsdShade

from seamless_usd.authoring.files import backup_once, check_layer, layer_lock, relative_asset_path, write_atomically
from seamless_usd.authoring.schema import (
    PROPERTIES,
    Schema,
    has_applied,
    is_seamless_uv_transform,
    read_provenance,
    schemas_known,
)
from seamless_usd.authoring.types import AuthoringResult, Codes, Provenance, StackResult, WriteMode
from seamless_usd.authoring.uvmath import Affine2, place2d, transform2d
from seamless_usd.discover.types import Origin
from seamless_usd.errors import InputError, UsageError
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = [
    "Names",
    "author_usd",
    "author_usd_stage",
    "default_output_layer",
    "uv_affine",
]


class Names:
    """Node ids, input names and values, named once."""

    OUTPUT_SUFFIX = ".seamless"  # scene.usda -> scene.seamless.usda
    UV_NODE = "SeamlessUV"
    SHADER_TYPE = "Shader"
    INFO_ID = "info:id"
    USD_UV_TEXTURE = "UsdUVTexture"
    USD_TRANSFORM_2D = "UsdTransform2d"
    MX_PLACE_2D = "ND_place2d_vector2"
    MX_IMAGE_PREFIX = "ND_image_"
    MX_TILED_PREFIX = "ND_tiledimage_"
    MX_GLTF_IMAGE_PREFIX = "ND_gltf_"
    FILE = "file"
    ST = "st"
    TEXCOORD = "texcoord"
    IN = "in"
    RESULT = "result"
    OUT = "out"
    SCALE = "scale"
    ROTATION = "rotation"
    TRANSLATION = "translation"
    PIVOT = "pivot"
    ROTATE = "rotate"
    OFFSET = "offset"
    OPERATION_ORDER = "operationorder"
    WRAP_S = "wrapS"
    WRAP_T = "wrapT"
    REPEAT = "repeat"
    U_ADDRESS = "uaddressmode"
    V_ADDRESS = "vaddressmode"
    PERIODIC = "periodic"
    UV_TILING = "uvtiling"
    UV_OFFSET = "uvoffset"


# ---------------------------------------------------------------------------------------------
# Public entry points


def default_output_layer(stage_path: Path) -> Path:
    """``scene.usda`` -> ``scene.seamless.usda`` beside it (``.usdz`` / ``.usdc`` -> ``.usda``)."""
    stage_path = Path(stage_path)
    return stage_path.with_name(f"{stage_path.stem}{Names.OUTPUT_SUFFIX}.usda")


def author_usd(
    stage_path: Path | str,
    results: Sequence[StackResult],
    mode: WriteMode = WriteMode.NEW_LAYER,
    output_layer: Path | str | None = None,
    plan_mode: WriteMode = WriteMode.NEW_LAYER,
) -> AuthoringResult:
    """Open the stage at ``stage_path`` and write ``results`` into it.

    ``NEW_LAYER`` writes ``output_layer`` (default :func:`default_output_layer`) that sublayers
    the original root layer and holds every override, with asset paths relative to it; no input
    file changes. ``IN_PLACE`` edits the layers holding the opinions, saving only changed layers
    after ``.bak`` copies (kept from the first edit). ``DRY_RUN`` lists in ``plan`` the edits
    ``plan_mode`` (``NEW_LAYER`` or ``IN_PLACE``) would make and writes nothing. Maps of
    MaterialX documents the stage references (``Origin.MTLX``) are written by
    :func:`author_mtlx` in the same mode; with a new layer, the stage's references to such a
    document are pointed at the new document in that layer. Maps whose output file is missing
    are skipped with an error finding. An existing output layer is replaced.

    Raises :class:`~seamless_usd.errors.UsageError` when the output layer is the input stage and
    :class:`~seamless_usd.errors.InputError` when the stage cannot be opened or a layer to edit
    in place has unsaved changes in this process.
    """
    stage_path = Path(stage_path).resolve()
    mode = WriteMode(mode)
    if not stage_path.is_file():
        raise InputError(f"{asset_ref(stage_path)}: no such stage")
    in_place = mode is WriteMode.IN_PLACE or (
        mode is WriteMode.DRY_RUN and WriteMode(plan_mode) is WriteMode.IN_PLACE)
    out = Path(output_layer).resolve() if output_layer else default_output_layer(stage_path)
    if out == stage_path and not in_place:
        raise UsageError(f"{asset_ref(out)}: the output layer must not be the input stage")
    # One writer of this stage's layers at a time (two runs on one library): see layer_lock
    with layer_lock(stage_path) if mode is not WriteMode.DRY_RUN else contextlib.nullcontext():
        # MaterialX documents the stage references: written by author_mtlx in the same mode
        from seamless_usd.authoring.mtlx import author_mtlx

        documents = list(dict.fromkeys(
            m.map.document for r in results for m in r.maps if m.map.origin is Origin.MTLX and m.map.document))
        doc_results = [author_mtlx(doc, results, mode=mode, plan_mode=plan_mode) for doc in documents]
        if in_place:
            result = _author_in_place(stage_path, results, dry_run=mode is WriteMode.DRY_RUN)
        else:
            retarget = {Path(doc).resolve(): r.output for doc, r in zip(documents, doc_results)
                        if r.output and (r.layers_written or (r.dry_run and r.plan))}
            result = _author_new_layer(stage_path, results, out, mode is WriteMode.DRY_RUN, retarget)
        for doc_result in doc_results:
            result.layers_written += doc_result.layers_written
            result.backups += doc_result.backups
            result.edited_prims += doc_result.edited_prims
            result.findings += doc_result.findings
            result.plan += doc_result.plan
    return result


def _author_new_layer(stage_path: Path, results: Sequence[StackResult], out: Path, dry_run: bool,
                      retarget: dict[Path, Path]) -> AuthoringResult:
    source = _open_layer(stage_path)  # held while authoring: the sublayer below is this one
    overrides = Sdf.Layer.CreateAnonymous(".usda")
    overrides.subLayerPaths.append(str(stage_path))
    stage = Usd.Stage.Open(overrides, Usd.Stage.LoadNone)
    result = AuthoringResult(dry_run=dry_run, output=out)
    author = _Author(stage, result, anchor_dir=out.parent, layer_names={overrides: out.name})
    author.plan_all(results, lambda prim, prop=None: Usd.EditTarget(overrides))
    for document, new_document in retarget.items():
        author.plan_retarget(document, new_document, Usd.EditTarget(overrides))
    if not author.edits:
        if author.planned_maps and not result.findings:
            result.findings.append(
                Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(stage_path),
                        "every texture already has these edits; no layer written")
            )
        return result
    author.apply()
    if result.dry_run:
        return result
    del author, stage, source  # the relative sublayer path below would not resolve from memory
    saved = Sdf.Layer.CreateAnonymous(".usda")
    saved.TransferContent(overrides)
    saved.subLayerPaths[0] = relative_asset_path(stage_path, out.parent)
    write_atomically(out, lambda tmp: saved.Export(str(tmp)), check=check_layer)
    stale = Sdf.Layer.Find(str(out))
    if stale:  # a previous version is open in this process: show it the new content
        stale.Reload(force=True)
    result.layers_written.append(out)
    return result


def author_usd_stage(
    stage: Usd.Stage,
    results: Sequence[StackResult],
    edit_target_layer: Sdf.Layer | None = None,
    anchor_dir: Path | str | None = None,
) -> AuthoringResult:
    """Author ``results`` into an open stage (as a DCC export hook holds it); save nothing.

    Edits go to ``edit_target_layer`` (a layer of the stage's layer stack) or the stage's
    current edit target. Asset paths are relative to that layer's folder, or to ``anchor_dir``
    (the folder the caller will save the layer to); an anonymous layer with no ``anchor_dir``
    gets absolute paths and a finding.
    """
    target = Usd.EditTarget(edit_target_layer) if edit_target_layer else stage.GetEditTarget()
    layer = target.GetLayer()
    if anchor_dir is None and not layer.anonymous:  # a layer about to be saved may have no file yet
        anchor_dir = Path(layer.realPath or layer.identifier).parent
    result = AuthoringResult()
    author = _Author(stage, result, anchor_dir=Path(anchor_dir) if anchor_dir else None)
    author.plan_all(results, lambda prim, prop=None: target)
    author.apply()
    return result


def uv_affine(stage: Usd.Stage, texture: str | Sdf.Path) -> Affine2:
    """The composed affine map from the primvar read to the UVs ``texture`` samples with.

    Follows the texture's ``st`` / ``texcoord`` connection through ``UsdTransform2d`` and
    MaterialX ``place2d`` nodes (input values read where they are authored, e.g. on Material
    interface inputs) down to the primvar reader, and includes a ``tiledimage``'s own
    ``uvtiling`` / ``uvoffset``.
    """
    prim = stage.GetPrimAtPath(str(texture))
    shader = UsdShade.Shader(prim)
    kind = _kind(shader)
    total = Affine2()
    if kind == _Kind.MX_TILED:
        tiling = _value(shader.GetInput(Names.UV_TILING), (1.0, 1.0))
        offset = _value(shader.GetInput(Names.UV_OFFSET), (0.0, 0.0))
        total = Affine2(a=tiling[0], d=tiling[1], tx=-offset[0], ty=-offset[1])
    source = _uv_source(shader, kind)
    steps = []
    seen = set()
    while source is not None and source.GetPrim().GetPath() not in seen:
        node = UsdShade.Shader(source.GetPrim())
        seen.add(node.GetPath())
        node_id = node.GetShaderId() or ""
        if node_id == Names.USD_TRANSFORM_2D:
            steps.append(transform2d(
                _value(node.GetInput(Names.SCALE), (1.0, 1.0)),
                _value(node.GetInput(Names.ROTATION), 0.0),
                _value(node.GetInput(Names.TRANSLATION), (0.0, 0.0)),
            ))
            source = _connected(node.GetInput(Names.IN))
        elif node_id == Names.MX_PLACE_2D:
            steps.append(place2d(
                _value(node.GetInput(Names.PIVOT), (0.0, 0.0)),
                _value(node.GetInput(Names.SCALE), (1.0, 1.0)),
                _value(node.GetInput(Names.ROTATE), 0.0),
                _value(node.GetInput(Names.OFFSET), (0.0, 0.0)),
                int(_value(node.GetInput(Names.OPERATION_ORDER), 0)),
            ))
            source = _connected(node.GetInput(Names.TEXCOORD))
        else:
            break  # primvar reader / geomprop: the chain starts here
    chain = Affine2()
    for step in reversed(steps):  # collected texture-first; apply reader-first
        chain = chain.then(step)
    return chain.then(total)


# ---------------------------------------------------------------------------------------------
# Planning


class _Kind:
    USD_UV_TEXTURE = "UsdUVTexture"
    MX_IMAGE = "mx-image"
    MX_TILED = "mx-tiledimage"
    MX_GLTF = "mx-gltf-image"
    OTHER = "other"


def _kind(shader: UsdShade.Shader) -> str:
    node_id = shader.GetShaderId() or ""
    if node_id == Names.USD_UV_TEXTURE:
        return _Kind.USD_UV_TEXTURE
    if node_id.startswith(Names.MX_TILED_PREFIX):
        return _Kind.MX_TILED
    if node_id.startswith(Names.MX_IMAGE_PREFIX):
        return _Kind.MX_IMAGE
    if node_id.startswith(Names.MX_GLTF_IMAGE_PREFIX) and "image" in node_id:
        return _Kind.MX_GLTF
    return _Kind.OTHER


def _uv_input_name(kind: str) -> str:
    return Names.ST if kind == _Kind.USD_UV_TEXTURE else Names.TEXCOORD


def _uv_source(shader: UsdShade.Shader, kind: str) -> UsdShade.ConnectableAPI | None:
    uv_input = shader.GetInput(_uv_input_name(kind))
    return _connected(uv_input) if uv_input else None


def _connected(shade_input: UsdShade.Input | None) -> UsdShade.ConnectableAPI | None:
    """The node (or Material / NodeGraph) ``shade_input`` is connected to, if any."""
    if not shade_input:
        return None
    sources, _invalid = shade_input.GetConnectedSources()
    return sources[0].source if sources else None


def _producing_attr(shade_input: UsdShade.Input | None) -> Usd.Attribute | None:
    """The attribute whose authored value ``shade_input`` gets (itself when nothing is authored)."""
    if not shade_input:
        return None
    attrs = shade_input.GetValueProducingAttributes(shaderOutputsOnly=False)
    for attr in attrs:
        if UsdShade.Input.IsInput(attr):
            return attr
    return None if attrs else shade_input.GetAttr()


def _value(shade_input: UsdShade.Input | None, default):
    attr = _producing_attr(shade_input)
    value = attr.Get() if attr else None
    if value is None:
        return default
    return tuple(float(v) for v in value) if isinstance(default, tuple) else value


def _close(a, b, tol: float = 1e-6) -> bool:
    if a is None or b is None:
        return False
    return all(abs(float(x) - float(y)) <= tol * max(1.0, abs(float(x))) for x, y in zip(a, b))


class _EditKind:
    VALUE = "value"  # set an attribute's default value (None: declare the attribute only)
    CONNECT = "connect"  # replace an input's connections with one source
    DEFINE = "define"  # define a Shader prim
    SCHEMA = "schema"  # prepend an applied API schema
    RETARGET = "retarget"  # delete a reference and prepend one to another file (value: (old, new))


@dataclass
class _Edit:
    """One spec-level edit: a value, a connection, a new node or an applied schema."""

    target: Usd.EditTarget
    kind: str  # an _EditKind
    path: Sdf.Path  # stage namespace: property path, or prim path for define / schema
    type_name: Sdf.ValueTypeName | None = None
    value: object = None
    variability: object = Sdf.VariabilityVarying

    def describe(self, layer_name: str) -> str:
        where = f"in {asset_ref(layer_name)}"
        if self.kind == _EditKind.VALUE and self.value is None:
            return f"declare {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.VALUE:
            shown = asset_ref(self.value.path) if isinstance(self.value, Sdf.AssetPath) else self.value
            return f"set {prim_ref(self.path)} = {shown} {where}"
        if self.kind == _EditKind.CONNECT:
            return f"connect {prim_ref(self.path)} -> {prim_ref(self.value)} {where}"
        if self.kind == _EditKind.DEFINE:
            return f"define {self.value} {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.RETARGET:
            old, new = self.value
            return (f"reference {prim_ref(self.path)}: {asset_ref(old.assetPath)} -> "
                    f"{asset_ref(new.assetPath)} {where}")
        return f"apply {self.value} to {prim_ref(self.path)} {where}"

    def apply(self) -> None:
        layer = self.target.GetLayer()
        spec_path = self.target.MapToSpecPath(self.path)
        if self.kind == _EditKind.RETARGET:
            old, new = self.value
            references = Sdf.CreatePrimInLayer(layer, spec_path).referenceList
            references.deletedItems.append(old)
            references.prependedItems.append(new)
            return
        if self.kind in (_EditKind.DEFINE, _EditKind.SCHEMA):
            prim_spec = Sdf.CreatePrimInLayer(layer, spec_path)
            if self.kind == _EditKind.DEFINE:
                prim_spec.specifier = Sdf.SpecifierDef
                prim_spec.typeName = Names.SHADER_TYPE
            else:
                _prepend_api_schema(prim_spec, self.value)
            return
        prim_spec = Sdf.CreatePrimInLayer(layer, spec_path.GetPrimPath())
        attr_spec = layer.GetAttributeAtPath(spec_path)
        if not attr_spec:
            attr_spec = Sdf.AttributeSpec(prim_spec, spec_path.name, self.type_name, self.variability)
        if self.kind == _EditKind.VALUE:
            if self.value is not None:
                attr_spec.default = self.value
        else:
            attr_spec.connectionPathList.explicitItems = [self.target.MapToSpecPath(self.value)]


def _prepend_api_schema(prim_spec: Sdf.PrimSpec, name: str) -> None:
    ops = prim_spec.GetInfo("apiSchemas") if prim_spec.HasInfo("apiSchemas") else Sdf.TokenListOp()
    if ops.isExplicit:
        if name not in ops.explicitItems:
            ops.explicitItems = list(ops.explicitItems) + [name]
    elif name not in ops.prependedItems and name not in ops.appendedItems:
        ops.prependedItems = list(ops.prependedItems) + [name]
    prim_spec.SetInfo("apiSchemas", ops)


class _Author:
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
        self._uv_updates: dict[Sdf.Path, tuple[float, float]] = {}  # marked node -> total scale
        self.target_for = None
        self.planned_maps = 0

    # -- planning ------------------------------------------------------------------------

    def plan_all(self, results: Iterable[StackResult], target_for) -> None:
        """``target_for(prim, attr_or_None) -> Usd.EditTarget | Finding`` picks where edits go."""
        self.target_for = target_for
        if not schemas_known():
            self._find(Severity.WARNING, Codes.SCHEMA_NOT_REGISTERED, asset_ref(Schema.TILE_API),
                       "USD's schema registry was built before seamless_usd.authoring was "
                       "imported: provenance is written, but this process does not know the schema")
        for stack_result in results:
            for map_result in stack_result.maps:
                if map_result.map.origin is Origin.USD:  # MaterialX documents: author_mtlx
                    self.planned_maps += 1
                    self._plan_map(map_result, stack_result.uv_scale, stack_result.provenance)

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
        target = self.target_for(prim, attr)
        if isinstance(target, Finding):
            self.result.findings.append(target)
            return None
        return target

    def _plan_map(self, map_result, uv_scale, provenance: Provenance) -> None:
        tex_map = map_result.map
        node_path = tex_map.node.strip("<>")
        prim = self.stage.GetPrimAtPath(node_path)
        if not prim:
            self._find(Severity.ERROR, Codes.MISSING_PRIM, prim_ref(node_path),
                       "texture node not found on the stage; nothing written for it")
            return
        if prim.IsInstanceProxy():
            self._find(Severity.SKIPPED, Codes.INSTANCE_PROXY, prim_ref(node_path),
                       "texture inside an instance: edit its prototype's source or make it "
                       "non-instanceable")
            return
        out = str(Path(map_result.output_path).resolve())
        if not Path(out).is_file() and not self.result.dry_run:  # a dry run plans unwritten tiles
            self._find(Severity.ERROR, Codes.MISSING_OUTPUT, asset_ref(out),
                       f"tileable file for {prim_ref(node_path)} not found; nothing written for it")
            return
        scale = (float(uv_scale[0]), float(uv_scale[1]))
        done = self._done.get(node_path)
        if done is not None:
            if done[0] != out or not _close(done[1], scale):
                self._find(
                    Severity.WARNING, Codes.SHARED_CONFLICT, prim_ref(node_path),
                    f"texture node shared by {done[2]} and {tex_map.material} with different "
                    f"results; kept {done[2]}'s. Give each material its own texture node to "
                    "process them separately",
                )
            return
        self._done[node_path] = (out, scale, tex_map.material)
        first_edit = len(self.edits)
        shader = UsdShade.Shader(prim)
        kind = _kind(shader)
        recorded = read_provenance(prim)
        from_source = recorded is None or _same_file(
            prim.GetAttribute(Schema.SOURCE_ASSET).Get(), tex_map.resolved)
        if not self._plan_file(prim, shader, tex_map, out):
            return
        self._plan_wrap(prim, shader, kind)
        applied = self._plan_uv(prim, shader, kind, scale, recorded, from_source)
        if applied is None:  # the UV edit cannot be made: leave this map untouched
            del self.edits[first_edit:]
            return
        if recorded and not from_source:  # made from an earlier tile: keep the origin
            origin = prim.GetAttribute(Schema.SOURCE_ASSET).Get()
            source = origin.resolvedPath or origin.path
        else:
            source = tex_map.resolved
        self._plan_provenance(prim, provenance, applied, source)
        if len(self.edits) > first_edit and prim_ref(node_path) not in self.result.edited_prims:
            self.result.edited_prims.append(prim_ref(node_path))

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
            self._find(Severity.WARNING, Codes.ANONYMOUS_ANCHOR, asset_ref(out),
                       "the edit layer has no folder yet; wrote an absolute asset path "
                       "(pass anchor_dir to get relative ones)")
            return Path(out).as_posix()
        return relative_asset_path(Path(out), anchor)

    def _plan_input_value(self, prim, shader, name: str, type_name, value) -> None:
        """Set input ``name`` where its value is authored (interface input) or on the node."""
        shade_input = shader.GetInput(name)
        attr = _producing_attr(shade_input) if shade_input else None
        if attr is None:
            attr = prim.GetAttribute(f"inputs:{name}")
        current = attr.Get() if attr else None
        if current == value or (isinstance(value, tuple) and _close(current, value, 1e-9)):
            return
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

    def _plan_uv(self, prim, shader, kind, scale, recorded, from_source) -> tuple[float, float] | None:
        """Plan the UV scale; return the total scale now applied after the original chain."""
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
            return total
        if kind == _Kind.OTHER:
            self._find(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(prim.GetPath()),
                       f"unknown texture node {shader.GetShaderId()!r}; file replaced, UVs not scaled")
            return (1.0, 1.0)
        if kind == _Kind.MX_GLTF and not _gltf_transform_is_identity(shader):
            self._find(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(prim.GetPath()),
                       "gltf image node with its own UV transform: scale it by hand")
            return (1.0, 1.0)
        uv_input = shader.GetInput(_uv_input_name(kind))
        source = _connected(uv_input)
        if source is None:
            self._find(Severity.WARNING, Codes.NO_UV, prim_ref(prim.GetPath()),
                       "texture coordinates are not connected; UVs not scaled")
            return (1.0, 1.0)
        use_place2d = kind != _Kind.USD_UV_TEXTURE
        if is_seamless_uv_transform(source.GetPrim()):
            node = UsdShade.Shader(source.GetPrim())
            if node.GetPath() in self._uv_updates:  # shared by maps of this run: updated once
                return self._uv_updates[node.GetPath()]
            current = _value(node.GetInput(Names.SCALE), (1.0, 1.0))
            prior_node = (1.0 / current[0], 1.0 / current[1]) if use_place2d else current
            total = scale if from_source else (prior_node[0] * scale[0], prior_node[1] * scale[1])
            value = (1.0 / total[0], 1.0 / total[1]) if use_place2d else total
            self._plan_input_value(node.GetPrim(), node, Names.SCALE, Sdf.ValueTypeNames.Float2, value)
            self._uv_updates[node.GetPath()] = total
            return total
        source_attr = _connection_source_attr(uv_input)
        key = (str(prim.GetPath().GetParentPath()), str(source_attr), scale, use_place2d)
        node_path = self._uv_nodes.get(key)
        target = self._target(prim, uv_input.GetAttr())
        if target is None:
            return None
        if node_path is None:
            node_path = self._new_uv_node(prim, target, source_attr, scale, use_place2d)
            self._uv_nodes[key] = node_path
        out_name = Names.OUT if use_place2d else Names.RESULT
        self.edits.append(_Edit(target, _EditKind.CONNECT, uv_input.GetAttr().GetPath(),
                                Sdf.ValueTypeNames.Float2,
                                node_path.AppendProperty(f"outputs:{out_name}")))
        return scale

    def _new_uv_node(self, prim, target, source_attr: Sdf.Path, scale, use_place2d: bool) -> Sdf.Path:
        parent = prim.GetPath().GetParentPath()
        name, n = Names.UV_NODE, 0
        while self.stage.GetPrimAtPath(parent.AppendChild(name)) or parent.AppendChild(name) in self._reserved:
            n += 1
            name = f"{Names.UV_NODE}_{n}"
        path = parent.AppendChild(name)
        self._reserved.add(path)
        f2 = Sdf.ValueTypeNames.Float2
        if use_place2d:
            node_id, in_name, out_name = Names.MX_PLACE_2D, Names.TEXCOORD, Names.OUT
            value = Gf.Vec2f(1.0 / scale[0], 1.0 / scale[1])
        else:
            node_id, in_name, out_name = Names.USD_TRANSFORM_2D, Names.IN, Names.RESULT
            value = Gf.Vec2f(*scale)
        self.edits += [
            _Edit(target, _EditKind.DEFINE, path, value=f"{node_id} node"),
            _Edit(target, _EditKind.VALUE, path.AppendProperty(Names.INFO_ID), Sdf.ValueTypeNames.Token,
                  node_id, Sdf.VariabilityUniform),
            _Edit(target, _EditKind.CONNECT, path.AppendProperty(f"inputs:{in_name}"), f2, source_attr),
            _Edit(target, _EditKind.VALUE, path.AppendProperty(f"inputs:{Names.SCALE}"), f2, value),
            _Edit(target, _EditKind.VALUE, path.AppendProperty(f"outputs:{out_name}"), f2, None),
            _Edit(target, _EditKind.SCHEMA, path, value=Schema.UV_TRANSFORM_API),
        ]
        return path

    def _plan_provenance(self, prim, provenance: Provenance, applied, source_file: str) -> None:
        """Record provenance; the source is this map's own file, relative to the edit layer."""
        target = self._target(prim, None)
        if target is None:
            return
        source = self._asset_path(source_file, target) if source_file else provenance.source_asset
        p = replace(provenance, uv_scale=tuple(applied), source_asset=source)
        if read_provenance(prim) == p:
            return
        if not has_applied(prim, Schema.TILE_API):
            self.edits.append(_Edit(target, _EditKind.SCHEMA, prim.GetPath(), value=Schema.TILE_API))
        for name, (type_name, convert) in PROPERTIES.items():
            self.edits.append(_Edit(target, _EditKind.VALUE, prim.GetPath().AppendProperty(name), type_name,
                                    convert(p)))

    # -- applying ------------------------------------------------------------------------

    def apply(self) -> None:
        """Record the plan and, unless dry-running, apply it in one change block."""
        for edit in self.edits:
            layer = edit.target.GetLayer()
            name = self.layer_names.get(layer) or _layer_name(layer)
            self.result.plan.append(edit.describe(name))
        if self.result.dry_run:
            return
        with Sdf.ChangeBlock():
            for edit in self.edits:
                edit.apply()


def _layer_name(layer: Sdf.Layer) -> str:
    return layer.realPath or layer.identifier


def _connection_source_attr(shade_input: UsdShade.Input) -> Sdf.Path:
    sources, _invalid = shade_input.GetConnectedSources()
    info = sources[0]
    prefix = "outputs:" if info.sourceType == UsdShade.AttributeType.Output else "inputs:"
    return info.source.GetPath().AppendProperty(prefix + info.sourceName)


def _gltf_transform_is_identity(shader: UsdShade.Shader) -> bool:
    affine = place2d(
        _value(shader.GetInput(Names.PIVOT), (0.0, 0.0)),
        _value(shader.GetInput(Names.SCALE), (1.0, 1.0)),
        _value(shader.GetInput(Names.ROTATE), 0.0),
        _value(shader.GetInput(Names.OFFSET), (0.0, 0.0)),
        int(_value(shader.GetInput(Names.OPERATION_ORDER), 0)),
    )
    return affine.close_to(Affine2())


def _same_file(asset: Sdf.AssetPath | None, path: str) -> bool:
    if not asset or not path:
        return False
    resolved = asset.resolvedPath if isinstance(asset, Sdf.AssetPath) else str(asset)
    if not resolved:
        return False
    try:
        return os.path.samefile(resolved, path)
    except OSError:
        return os.path.normcase(os.path.abspath(resolved)) == os.path.normcase(os.path.abspath(path))


# ---------------------------------------------------------------------------------------------
# In place


def _is_packaged(layer: Sdf.Layer) -> bool:
    return Ar.IsPackageRelativePath(layer.identifier) or layer.GetFileFormat().IsPackage()


def _editable(layer: Sdf.Layer) -> Finding | None:
    where = asset_ref(layer.identifier)
    if _is_packaged(layer):
        return Finding(Severity.SKIPPED, Codes.IN_PACKAGE, where,
                       "opinion is inside a package; in-place edits skipped (use the default "
                       "new-layer mode)")
    if layer.anonymous or not layer.realPath or not os.access(layer.realPath, os.W_OK):
        return Finding(Severity.SKIPPED, Codes.READ_ONLY, where,
                       "layer is not a writable file; in-place edits skipped")
    return None


def _prim_nodes(prim: Usd.Prim):
    stack = [prim.GetPrimIndex().rootNode]
    while stack:
        node = stack.pop(0)
        yield node
        stack.extend(node.children)


def _in_place_target(prim: Usd.Prim, attr: Usd.Attribute | None):
    """Where an in-place edit goes: the strongest layer holding the opinion, mapped."""
    if attr:
        specs = attr.GetPropertyStack(Usd.TimeCode.Default())
        layers = [s.layer for s in specs]
    else:
        layers = []
    layers += [s.layer for s in prim.GetPrimStack()]
    if not layers:
        return Finding(Severity.ERROR, Codes.MISSING_PRIM, prim_ref(prim.GetPath()), "no layer holds it")
    layer = layers[0]
    problem = _editable(layer)
    if problem is not None:
        return problem
    for node in _prim_nodes(prim):
        if layer in node.layerStack.layers and layer.GetPrimAtPath(node.path):
            return Usd.EditTarget(layer, node)
    return Usd.EditTarget(layer)


def _author_in_place(stage_path: Path, results: Sequence[StackResult], dry_run: bool = False) -> AuthoringResult:
    result = AuthoringResult(dry_run=dry_run)
    if _is_packaged_path(stage_path):
        result.findings.append(Finding(
            Severity.SKIPPED, Codes.IN_PACKAGE, asset_ref(stage_path),
            "a .usdz cannot be edited in place; use the default new-layer mode"))
        return result
    _open_layer(stage_path)
    stage = Usd.Stage.Open(str(stage_path), Usd.Stage.LoadNone)
    layers = {layer: layer.dirty for layer in stage.GetUsedLayers()}
    author = _Author(stage, result, anchor_dir=None)
    author.plan_all(results, _in_place_target)
    if not author.edits:
        if author.planned_maps and not result.findings:
            result.findings.append(Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(stage_path),
                                           "every texture already has these edits; nothing saved"))
        return result
    if dry_run:
        author.apply()  # records the plan only
        return result
    changed = {edit.target.GetLayer() for edit in author.edits}
    for layer in changed:
        if layers.get(layer):
            raise InputError(f"{asset_ref(layer.identifier)} has unsaved changes in this process; "
                             "save or reload it first")
    try:
        author.apply()
        for layer in sorted(changed, key=lambda lay: lay.realPath):
            path = Path(layer.realPath)
            result.backups.append(backup_once(path))
            args = _format_args(layer)
            write_atomically(path, lambda tmp, layer=layer: layer.Export(str(tmp), args=args), check=check_layer)
            result.layers_written.append(path)
    finally:
        for layer in changed:
            layer.Reload(force=True)  # drop in-memory edits; saved ones come back from disk
    return result


def _open_layer(path: Path) -> Sdf.Layer:
    try:
        layer = Sdf.Layer.FindOrOpen(str(path))
    except Tf.ErrorException as exc:
        raise InputError(f"{asset_ref(path)}: cannot be read as a USD layer ({exc})") from None
    if not layer:
        raise InputError(f"{asset_ref(path)}: cannot be read as a USD layer")
    return layer


def _format_args(layer: Sdf.Layer) -> dict:
    fmt = layer.GetFileFormat()
    if fmt.formatId == "usd":
        underlying = Sdf.UsdFileFormat.GetUnderlyingFormatForLayer(layer)
        return {"format": underlying} if underlying else {}
    return {}


def _is_packaged_path(path: Path) -> bool:
    fmt = Sdf.FileFormat.FindByExtension(path.suffix.lstrip("."))
    return bool(fmt and fmt.IsPackage())
