"""In-place authoring: edits land in the layers holding the opinions, after ``.bak`` copies."""
from __future__ import annotations

from pathlib import Path
from typing import Sequence

from pxr import Ar, Sdf, Tf, Usd

from seamless_usd.authoring.files import backup_once, check_layer, linked_target, write_atomically
from seamless_usd.authoring.types import AuthoringResult, Codes, StackResult
from seamless_usd.authoring.usdedits import check_uv_composed, keep_whole_stacks
from seamless_usd.authoring.usdplan import _Author
from seamless_usd.authoring.usdshared import SharedEdits, record_made, respect_other_stages
from seamless_usd.errors import InputError
from seamless_usd.fileio import marked_writable
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = []




def _is_packaged(layer: Sdf.Layer) -> bool:
    return Ar.IsPackageRelativePath(layer.identifier) or layer.GetFileFormat().IsPackage()


def _editable(layer: Sdf.Layer) -> Finding | None:
    where = asset_ref(layer.identifier)
    if _is_packaged(layer):
        return Finding(Severity.SKIPPED, Codes.IN_PACKAGE, where,
                       "opinion is inside a package; in-place edits skipped (use the default "
                       "new-layer mode)")
    if layer.anonymous or not layer.realPath or not marked_writable(layer.realPath):
        return Finding(Severity.SKIPPED, Codes.READ_ONLY, where,
                       "layer is not a writable file; in-place edits skipped")
    return None


def _prim_nodes(prim: Usd.Prim):
    stack = [prim.GetPrimIndex().rootNode]
    while stack:
        node = stack.pop(0)
        yield node
        stack.extend(node.children)


def _in_place_target(prim: Usd.Prim, attr: Usd.Attribute | None, layer: Sdf.Layer | None = None, node=None):
    """Where an in-place edit goes: ``layer`` (the layer of the texture's file value, which gets all of that
    texture's edits) through ``node`` (the composition node holding that value: inside a variant, every edit of
    the texture stays inside that variant, or it would replace the other variants' textures), else the strongest
    layer holding the opinion; mapped into it."""
    if layer is None:
        layers = [s.layer for s in attr.GetPropertyStack(Usd.TimeCode.Default())] if attr else []
        layers += [s.layer for s in prim.GetPrimStack()]
        if not layers:
            return Finding(Severity.ERROR, Codes.MISSING_PRIM, prim_ref(prim.GetPath()), "no layer holds it")
        layer = layers[0]
    problem = _editable(layer)
    if problem is not None:
        return problem
    if prim.IsInstanceProxy():  # mapped through its own instance's arcs: the prototype's index is another instance's
        return _instance_target(prim, layer)
    if node and layer in node.layerStack.layers and layer.GetPrimAtPath(node.path):
        return Usd.EditTarget(layer, node)
    for node in _prim_nodes(prim):
        if layer in node.layerStack.layers and layer.GetPrimAtPath(node.path):
            return Usd.EditTarget(layer, node)
    return Usd.EditTarget(layer)


def _instance_target(prim: Usd.Prim, layer: Sdf.Layer):
    """The edit target into ``layer`` for ``prim``, a prim inside an instance: through the instance's own
    composition arcs, which map its namespace onto the spec the prototype is made from (edited there, every
    instance of that prototype shows the edit)."""
    instance = prim
    while instance and not instance.IsInstance():
        instance = instance.GetParent()
    for node in _prim_nodes(instance):
        if layer in node.layerStack.layers:
            target = Usd.EditTarget(layer, node)
            spec = target.MapToSpecPath(prim.GetPath())
            if not spec.isEmpty and layer.GetPrimAtPath(spec.StripAllVariantSelections()):
                return target
    return Finding(Severity.SKIPPED, Codes.INSTANCE_PROXY, prim_ref(prim.GetPath()),
                   f"inside an instance, and {asset_ref(layer.identifier)} holds none of its prototype: edit its "
                   "prototype's source, or make it non-instanceable")


def _author_in_place(stage_path: Path, results: Sequence[StackResult], dry_run: bool = False,
                     shared: SharedEdits | None = None) -> AuthoringResult:
    """``shared``: what the run's other stages keep or edited already in the layers they share with this one."""
    result = AuthoringResult(dry_run=dry_run)
    if _is_packaged_path(stage_path):
        result.findings.append(Finding(
            Severity.SKIPPED, Codes.IN_PACKAGE, asset_ref(stage_path),
            "a .usdz cannot be edited in place; use the default new-layer mode"))
        return result
    _open_layer(stage_path)
    stage = Usd.Stage.Open(str(stage_path), Usd.Stage.LoadAll)  # materials inside payloads too
    layers = {layer: layer.dirty for layer in stage.GetUsedLayers()}
    author = _Author(stage, result, anchor_dir=None)
    author.plan_all(results, _in_place_target, selections=True, one_layer=True)
    if shared is not None:
        respect_other_stages(author, results, result, shared)
    if not author.edits:
        if shared is not None:
            record_made(author, results, shared, str(stage_path))
        if author.planned_maps and not result.refusals() and not result.not_written:
            result.findings.append(Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(stage_path),
                                           "every texture already has these edits; nothing saved"))
        return result
    changed = {edit.target.GetLayer() for edit in author.edits}
    own = set(stage.GetLayerStack(includeSessionLayers=False))
    for layer in sorted(changed - own, key=lambda lay: lay.identifier):  # a library's: other stages change too
        result.findings.append(Finding(
            Severity.WARNING, Codes.SHARED_LAYER_EDITED, asset_ref(layer.realPath or layer.identifier),
            f"edited in place, though {asset_ref(stage_path)} only references or loads it: every stage that uses it "
            "shows the tiles now, from the tiles folder of this stage (leave out --in-place for a layer of its own)"))
    if dry_run:  # the plan, with the same warnings as the run
        author.apply()  # records the plan only
        if shared is not None:
            record_made(author, results, shared, str(stage_path))
        return result
    for layer in changed:
        if layers.get(layer):
            raise InputError(f"{asset_ref(layer.identifier)} has unsaved changes in this process; "
                             "save or reload it first")
    try:
        before, planned = {layer: layer.ExportToString() for layer in changed}, len(result.plan)
        author.apply()
        check_uv_composed(author, results, result)
        keep_whole_stacks(author, results, result, before, planned)
        for layer in sorted(changed, key=lambda lay: lay.realPath):
            if layer.ExportToString() == before[layer]:  # only a stack that kept none of its edits touched it
                continue
            path, linked = linked_target(Path(layer.realPath))
            if linked:
                result.findings.append(Finding(Severity.WARNING, Codes.SHARED_LAYER_EDITED,
                                               asset_ref(layer.realPath), linked))
            result.backups.append(backup_once(path))
            args = _format_args(layer)
            write_atomically(path, lambda tmp, layer=layer: layer.Export(str(tmp), args=args), check=check_layer)
            result.layers_written.append(path)
    finally:
        for layer in changed:
            layer.Reload(force=True)  # drop in-memory edits; saved ones come back from disk
    if shared is not None:
        record_made(author, results, shared, str(stage_path))
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
