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
import uuid
from pathlib import Path
from typing import Sequence

from pxr import Ar, Sdf, Tf, Usd

from seamless_usd.authoring.files import backup_once, check_layer, layer_lock, relative_asset_path, write_atomically
from seamless_usd.authoring.usdforeign import not_ours, not_ours_words
from seamless_usd.fileio import source_sha256
from seamless_usd.authoring.types import AuthoringResult, Codes, StackResult, WriteMode, node_key
from seamless_usd.authoring.usdedits import check_uv_composed, keep_whole_stacks, not_composed, strongest_layer
from seamless_usd.authoring.usdinplace import _author_in_place, _open_layer
from seamless_usd.authoring.mtlx import default_output_document
from seamless_usd.authoring.usdnodes import Names, uv_affine
from seamless_usd.authoring.usdplan import _Author, _layer_name
from seamless_usd.textures import Origin
from seamless_usd.errors import InputError, UsageError
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = [
    "Names",
    "author_usd",
    "author_usd_stage",
    "default_output_layer",
    "uv_affine",
]


# ---------------------------------------------------------------------------------------------
# Public entry points


def referenced_output(document: Path, layer: Path) -> Path:
    """The new document of a MaterialX document a stage references, for the stage's new layer ``layer``: beside the
    document when it is in the layer's folder (``look.seamless.mtlx``), else beside the layer and named for it
    (``look.scene.seamless.mtlx``), so that two stages referencing one library document each get their own (the
    second rewrote the first's, and the first stage's layer showed the second's tiles)."""
    if document.resolve().parent == layer.resolve().parent:
        return default_output_document(document)
    return layer.with_name(f"{document.stem}.{layer.stem}.mtlx")


#: The extensions of USD layers: two stages of one name and two of these in one folder get layers named apart.
USD_EXTENSIONS = (".usd", ".usda", ".usdc", ".usdz")


def default_output_layer(stage_path: Path) -> Path:
    """``scene.usda`` -> ``scene.seamless.usda`` beside it (``.usdz`` / ``.usdc`` -> ``.usda``); where a stage of the
    same name with another extension is beside it (``scene.usda`` and ``scene.usdc``), each keeps its extension in
    the name (``scene.usdc.seamless.usda``): they wrote one layer, the second replacing the first's edits."""
    stage_path = Path(stage_path)
    twins = [stage_path.with_suffix(ext) for ext in USD_EXTENSIONS if ext != stage_path.suffix.lower()]
    stem = stage_path.name if any(t.is_file() for t in twins) else stage_path.stem
    return stage_path.with_name(f"{stem}{Names.OUTPUT_SUFFIX}.usda")


def author_usd(
    stage_path: Path | str,
    results: Sequence[StackResult],
    mode: WriteMode = WriteMode.NEW_LAYER,
    output_layer: Path | str | None = None,
    plan_mode: WriteMode = WriteMode.NEW_LAYER,
    shared=None,
) -> AuthoringResult:
    """Open the stage at ``stage_path`` and write ``results`` into it (``shared``: in place, a run's
    :class:`.usdshared.SharedEdits` of the layers its stages share).

    ``NEW_LAYER`` writes ``output_layer`` (default :func:`default_output_layer`) that sublayers
    the original root layer and holds every override, with asset paths relative to it; no input
    file changes. ``IN_PLACE`` edits the layers holding the opinions, saving only changed layers
    after ``.bak`` copies (kept from the first edit). ``DRY_RUN`` lists in ``plan`` the edits
    ``plan_mode`` (``NEW_LAYER`` or ``IN_PLACE``) would make and writes nothing. Maps of
    MaterialX documents the stage references (``Origin.MTLX``) are written by
    :func:`author_mtlx` in the same mode; with a new layer, the stage's references to such a
    document are pointed at the new document in that layer. Maps whose output file is missing
    are skipped with an error finding. An existing output layer made over the stage as it is now (its
    ``seamlessMadeFrom``) is added to, so the edits of materials another run processed are kept; any other is
    replaced, the edits it loses named.

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
        doc_results = [author_mtlx(doc, results, mode=mode, plan_mode=plan_mode,
                                   output_path=None if in_place else referenced_output(Path(doc), out))
                       for doc in documents]
        with Tf.DiagnosticTrap() as trap:
            if in_place:
                result = _author_in_place(stage_path, results, dry_run=mode is WriteMode.DRY_RUN, shared=shared)
            else:
                retarget = {Path(doc).resolve(): r.output for doc, r in zip(documents, doc_results)
                            if r.output and (r.layers_written or (r.dry_run and r.plan))}
                result = _author_new_layer(stage_path, results, out, mode is WriteMode.DRY_RUN, retarget)
            # usd-core cannot compose .mtlx references (discovery reads them itself): USD's
            # warnings about them are noise; every other diagnostic is passed on.
            trap.EraseMatching(lambda d: ".mtlx" in str(d.commentary).lower())
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
    made_from = composed_sha256(stage_path)
    overrides, earlier, foreign = _earlier_layer(out, stage_path, made_from)
    data = dict(overrides.customLayerData)
    data[Names.MADE_FROM] = made_from  # a later run over the same stage adds its edits to these
    overrides.customLayerData = data
    # Payloads loaded: materials inside them are edited like any other (a new layer's overrides
    # reach into payloads, references and variants; a stack found under another variant
    # selection is planned under that selection, its edits inside that variant).
    stage = Usd.Stage.Open(overrides, Usd.Stage.LoadAll)
    result = AuthoringResult(dry_run=dry_run, output=out)
    author = _Author(stage, result, anchor_dir=out.parent, layer_names={overrides: out.name})
    author.plan_all(results, lambda prim, prop=None: Usd.EditTarget(overrides), variant_layer=overrides,
                    selections=True)
    for document, new_document in retarget.items():
        author.plan_retarget(document, new_document, Usd.EditTarget(overrides))
    done = {prim_ref(m.map.node.strip("<>")) for r in results for m in r.maps}
    lost = [p for p in earlier if p not in done]
    if lost:
        result.findings.append(Finding(
            Severity.WARNING, Codes.EDITS_REPLACED, asset_ref(out),
            f"was made over another version of {asset_ref(stage_path)}, so it is made again over the stage as it is "
            f"now and the earlier edits of {', '.join(lost)} are not kept: process those materials again"))
    # a layer made over another version of the stage is replaced even with no edit of this run: its file values
    # would hide what changed (a texture set anew in a sublayer, kept as it is)
    if not author.edits and not earlier:
        if author.planned_maps and not result.refusals() and not result.not_written:
            result.findings.append(
                Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(stage_path),
                        "every texture already has these edits; no layer written")
            )
        return result
    author.owners += [""] * (len(author.edits) - len(author.owners))  # the retargeted references: no stack's
    before, planned = ({} if result.dry_run else {overrides: overrides.ExportToString()}), len(result.plan)
    author.apply()
    if result.dry_run:
        if foreign:
            result.findings.append(Finding(Severity.WARNING, Codes.EDITS_REPLACED, asset_ref(out), not_ours_words(
                foreign, "a run would make it again over the stage as it is now, without them, keeping the file as "
                f"it is in {asset_ref(out.name + '.bak')} (or the next free .N.bak)")))
        return result
    check_uv_composed(author, results, result)
    keep_whole_stacks(author, results, result, before, planned)
    if overrides.ExportToString() == before[overrides] and not earlier:  # every stack's edits refused
        return result
    del author, stage, source  # the relative sublayer path below would not resolve from memory
    saved = Sdf.Layer.CreateAnonymous(".usda")
    saved.TransferContent(overrides)
    saved.subLayerPaths[0] = relative_asset_path(stage_path, out.parent)
    if _holds(out, saved.ExportToString()):  # an unchanged rerun: the layer on disk is this one, left untouched
        result.findings.append(Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(out),
                                       "the layer on disk already holds these edits; not written again"))
        return result
    if foreign:  # a TD's own opinions in this tool's layer: kept in a backup, and said
        kept = backup_once(out)
        result.backups.append(kept)
        result.findings.append(Finding(Severity.WARNING, Codes.EDITS_REPLACED, asset_ref(out), not_ours_words(
            foreign, f"made again over the stage as it is now, it no longer holds them: the file as it was is "
            f"{asset_ref(kept)}")))
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
    # a plain layer of the stage: a map whose file value is authored inside a variant is edited inside that
    # variant there, so the other variants keep their own textures (an edit target already mapped into a
    # variant or a reference is used as it is)
    plain = target.GetMapFunction().isIdentity
    author.plan_all(results, lambda prim, prop=None: target, variant_layer=layer if plain else None)
    _plan_documents(author, results, target, anchor_dir)
    author.owners += [""] * (len(author.edits) - len(author.owners))
    layers = {edit.target.GetLayer() for edit in author.edits}
    before = {lay: lay.ExportToString() for lay in layers} if not result.dry_run else {}
    planned = len(result.plan)
    with Tf.DiagnosticTrap() as trap:
        author.apply()
        # usd-core cannot compose the .mtlx references the stage now points at (discovery reads them itself)
        trap.EraseMatching(lambda d: ".mtlx" in str(d.commentary).lower())
    if not result.dry_run:
        _check_composed(stage, author.edits, results, result)
        keep_whole_stacks(author, results, result, before, planned)
    return result


def _plan_documents(author, results: Sequence[StackResult], target: Usd.EditTarget, anchor_dir) -> None:
    """For an open stage: each MaterialX document it references gets a new document (written, as the tiles are),
    beside the layer the edits go to (``anchor_dir``), and the stage's references are pointed at it there. A layer
    with no folder yet cannot anchor one: those maps are not written, saying why."""
    from seamless_usd.authoring.mtlx import author_mtlx
    from seamless_usd.authoring.mtlxinputs import MtlxNames

    result = author.result
    documents = list(dict.fromkeys(
        m.map.document for r in results for m in r.maps if m.map.origin is Origin.MTLX and m.map.document))
    for document in map(Path, documents):
        nodes = [node_key(m.map) for r in results for m in r.maps if m.map.document == str(document)]
        if anchor_dir is None:
            result.not_written += [(node, f"its MaterialX document {asset_ref(document)} gets a new document beside "
                                          "the layer the edits go to, which has no folder yet: save that layer first")
                                   for node in nodes]
            continue
        folder = Path(anchor_dir)
        stem = Path(target.GetLayer().identifier).stem
        out = (default_output_document(document) if document.resolve().parent == folder.resolve()
               else folder / f"{document.stem}.{stem}{MtlxNames.OUTPUT_SUFFIX}.mtlx")
        made = author_mtlx(document, results, mode=WriteMode.NEW_LAYER, output_path=out)
        for name in ("layers_written", "findings", "plan", "not_written", "not_written_for", "edited_prims"):
            getattr(result, name).extend(getattr(made, name))
        if out.is_file():
            author.plan_retarget(document, out, target)


def composed_sha256(stage_path: Path) -> str:
    """The SHA-256 of the stage at ``stage_path`` as its layers compose it: of every layer file it uses (sublayers,
    references, payloads, loaded), by name and content. A new layer records it (``seamlessMadeFrom``): made over a
    stage one of whose layers changed since (a texture set in a sublayer), it is made again, not added to (its
    earlier file values would hide the change)."""
    import hashlib

    stage = Usd.Stage.Open(str(stage_path), Usd.Stage.LoadAll)
    digest = hashlib.sha256()
    files = sorted({Ar.SplitPackageRelativePathOuter(layer.realPath)[0]  # a package's layers: the package file
                    if Ar.IsPackageRelativePath(layer.realPath) else layer.realPath
                    for layer in stage.GetUsedLayers(includeClipLayers=False) if layer.realPath and not layer.anonymous})
    for path in files:
        try:
            content = source_sha256(path)
        except OSError:  # gone since it was composed: named, not read
            content = ""
        digest.update(f"{os.path.relpath(path, stage_path.parent)}\0{content}\n".encode())
    return digest.hexdigest()


def _earlier_layer(out: Path, stage_path: Path, made_from: str) -> tuple[Sdf.Layer, list[str], list[str]]:
    """The layer to author into, over ``stage_path``: the new layer written before (``out``) when it was made over the
    stage as it is now (its ``seamlessMadeFrom`` is ``made_from``), so the edits of materials this run does not
    process (another ``--materials`` selection) are kept; else an empty one, the texture nodes the earlier
    layer had edited (``SeamlessTileAPI``), whose edits are then not kept, and the opinions in it this tool did not
    write (:func:`.usdforeign.not_ours`), which the new one does not hold."""
    from seamless_usd.authoring.schema import Schema

    # never saved under this name: a layer beside ``out``, so the asset paths it holds resolve as they will there
    name = out.parent / f".{out.name}.{uuid.uuid4().hex}.usda"
    fresh = Sdf.Layer.New(Sdf.FileFormat.FindByExtension("usda"), str(name))
    fresh.subLayerPaths.append(str(stage_path))
    earlier = Sdf.Layer.CreateAnonymous(".usda")
    try:
        if not out.is_file() or not earlier.ImportFromString(out.read_text(encoding="utf-8")):
            return fresh, [], []
    except (OSError, UnicodeDecodeError, Tf.ErrorException):  # not a layer (any more): it is replaced
        return fresh, [], []
    if earlier.customLayerData.get(Names.MADE_FROM) == made_from:
        fresh.TransferContent(earlier)
        fresh.subLayerPaths.clear()
        fresh.subLayerPaths.append(str(stage_path))
        return fresh, [], []
    edited: list[str] = []

    def visit(path: Sdf.Path) -> None:
        spec = earlier.GetPrimAtPath(path) if path.IsPrimPath() else None
        if spec is not None and Schema.TILE_API in list(spec.GetInfo("apiSchemas").GetAddedOrExplicitItems()):
            edited.append(prim_ref(path.StripAllVariantSelections()))

    earlier.Traverse(Sdf.Path.absoluteRootPath, visit)
    return fresh, edited, not_ours(earlier)


def _holds(path: Path, text: str) -> bool:
    """Whether the file at ``path`` holds exactly ``text``."""
    try:
        return path.read_text(encoding="utf-8") == text
    except (OSError, UnicodeDecodeError):
        return False


def _check_composed(stage: Usd.Stage, edits, results: Sequence[StackResult], result: AuthoringResult) -> None:
    """Every file value authored is the one the stage composes; a texture node whose new file loses to a stronger
    opinion (an edit target weaker than the layer that holds the value, such as a sublayer of a root layer that
    sets it) is recorded as not written, with a finding naming that layer."""
    from seamless_usd.authoring.usdedits import _EditKind

    nodes = {Sdf.Path(m.map.file_at.prim).AppendProperty(m.map.file_at.attribute): node_key(m.map)
             for r in results for m in r.maps}  # where each map's file value is authored -> its texture node
    for edit in edits:
        if edit.kind != _EditKind.VALUE or not isinstance(edit.value, Sdf.AssetPath):
            continue
        attr = stage.GetAttributeAtPath(edit.path)
        got = attr.Get() if attr else None
        if got is not None and got.path == edit.value.path:
            continue
        node = nodes.get(edit.path) or prim_ref(edit.path.GetPrimPath())
        not_composed(result, node, (
            f"its new file is authored in {asset_ref(_layer_name(edit.target.GetLayer()))} but "
            f"{asset_ref(strongest_layer(attr))} holds a stronger value, which the stage keeps; author into that "
            "layer or a stronger one (for edits in a layer of their own, open a new root layer that sublayers the "
            "scene)"))


