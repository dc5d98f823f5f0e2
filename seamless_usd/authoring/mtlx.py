"""Write tileable maps back into a MaterialX document: file paths, address modes, UV scale.

By default a new document ``<name>.seamless.mtlx`` is written next to the original; in place
on request (after a ``.bak`` copy). ``tiledimage`` nodes get their ``uvtiling`` / ``uvoffset``
multiplied by the UV scale (exact: the node computes ``texcoord * uvtiling - uvoffset``, scaled
component-wise afterwards). ``image`` nodes get a ``place2d`` named ``seamless_uv`` inserted
before their ``texcoord`` input (``scale`` = 1 / UV scale, since place2d divides), after the
existing chain, so any existing ``place2d`` is composed exactly. Provenance is recorded as
``seamless_*`` attributes on each edited image node (MaterialX keeps unknown attributes).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Sequence

import MaterialX as mx

from seamless_usd.authoring.mtlxinputs import (MtlxNames, UnauthoredInput, fmt, gltf_identity, own_file_input,
                                               own_input, set_vector2, vector2)
from seamless_usd.authoring.mtlxuv import _PlaceUV
from seamless_usd.authoring.files import (SET_BY_HAND, backup_once, layer_lock, linked_target, relative_asset_path,
                                          set_by_hand, write_atomically)
from seamless_usd.authoring.mtlxtext import read_options, stated_version, with_leading_comments
from seamless_usd.authoring.types import (TURN_NOT_AUTHORED, AuthoringResult, Codes, Provenance, StackResult, UVTurn,
                                          WriteMode, node_key, shared_with)
from seamless_usd.textures import Origin
from seamless_usd.errors import InputError
from seamless_usd.fileio import file_sha256
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["MtlxNames", "author_mtlx", "default_output_document", "read_mtlx_provenance"]


def default_output_document(document_path: Path) -> Path:
    """``look.mtlx`` -> ``look.seamless.mtlx`` beside it."""
    document_path = Path(document_path)
    return document_path.with_name(f"{document_path.stem}{MtlxNames.OUTPUT_SUFFIX}.mtlx")


def author_mtlx(
    document_path: Path | str,
    results: Sequence[StackResult],
    mode: WriteMode = WriteMode.NEW_LAYER,
    output_path: Path | str | None = None,
    plan_mode: WriteMode = WriteMode.NEW_LAYER,
) -> AuthoringResult:
    """Write the MaterialX maps of ``results`` into a copy of the document (or in place).

    Maps of other documents (or USD maps) in ``results`` are ignored. ``NEW_LAYER`` writes
    ``output_path`` (default :func:`default_output_document`), ``IN_PLACE`` rewrites the
    document after a ``.bak`` copy, ``DRY_RUN`` only fills ``plan`` (for ``plan_mode``).
    Raises :class:`~seamless_usd.errors.InputError` when the document cannot be read.
    """
    src = Path(document_path).resolve()
    mode = WriteMode(mode)
    in_place = mode is WriteMode.IN_PLACE or (
        mode is WriteMode.DRY_RUN and WriteMode(plan_mode) is WriteMode.IN_PLACE)
    out = src if in_place else (
        Path(output_path).resolve() if output_path else default_output_document(src))
    result = AuthoringResult(dry_run=mode is WriteMode.DRY_RUN, output=None if in_place else out)
    source_hash = "" if in_place or not src.is_file() else file_sha256(src)
    doc, earlier = (None, []) if in_place else _earlier_output(src, out, source_hash)
    from_source = doc is None
    if from_source:
        doc = mx.createDocument()
        try:
            mx.readFromXmlFile(doc, str(src), mx.FileSearchPath(), read_options())
        except Exception as exc:  # MaterialX raises its own ExceptionFileMissing / ExceptionParseError
            raise InputError(f"{asset_ref(src)}: cannot be read as a MaterialX document ({exc})") from None
    author = _MtlxAuthor(doc, src, out, result)
    author.read_from = src if from_source else out  # recorded source assets are relative to the document read
    if from_source and out.parent != src.parent:
        author.rebase_files()
    if not in_place:  # what the new document was made from: a later run adds its edits to this one
        author.set_source_hash(source_hash)
    checked = 0
    edited: set[str] = set()
    for stack_result in results:
        for map_result in stack_result.maps:
            tex_map = map_result.map
            if tex_map.origin is not Origin.MTLX or not _same_path(tex_map.document or tex_map.file_at.layer, src):
                continue
            author.edit_map(map_result, stack_result.uv_scale, stack_result.provenance, stack_result.wrap_only,
                            stack_result.uv_turn, stack_result.scale_known)
            checked += 1
            edited.add(tex_map.node.strip("<>").lstrip("/"))
    lost = [n for n in earlier if n not in edited]
    if lost:
        result.findings.append(Finding(
            Severity.WARNING, Codes.MTLX_EDITS_REPLACED, asset_ref(out),
            f"was made from another version of {asset_ref(src)}, so it is made again from the document as it is now "
            f"and the earlier edits of {', '.join(prim_ref(n) for n in lost)} are not kept: process the stages that "
            "use them again"))
    older = stated_version(src)
    if author.changed and older and older != doc.getVersionString():
        result.findings.append(Finding(
            Severity.WARNING, Codes.MTLX_VERSION_UPGRADED, asset_ref(out),
            f"written as a MaterialX {doc.getVersionString()} document: {asset_ref(src)} is a {older} one, which the "
            f"MaterialX library upgrades as it reads it; an application that reads {older} documents only may not "
            "read it"))
    if not author.changed:
        if checked and not result.refusals() and not result.not_written:
            result.findings.append(Finding(Severity.SKIPPED, Codes.NOTHING_TO_DO, asset_ref(src),
                                           "every texture already has these edits; nothing written"))
        return result
    if result.dry_run:
        return result
    # Written through Python: MaterialX's own file writer ignores write errors (a full disk gives
    # an empty document), Python raises them.
    text = with_leading_comments(mx.writeToXmlString(doc), src)
    if mode is WriteMode.IN_PLACE:
        out, linked = linked_target(out)
        if linked:
            result.findings.append(Finding(Severity.WARNING, Codes.SHARED_LAYER_EDITED, asset_ref(src), linked))
    with layer_lock(out):
        if mode is WriteMode.IN_PLACE:
            result.backups.append(backup_once(out))
        write_atomically(out, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    result.layers_written.append(out)
    return result


def _earlier_output(src: Path, out: Path, source_hash: str) -> tuple[mx.Document | None, list[str]]:
    """The new document written before (``out``), read, when it was made from the source as it is now: the new one
    starts from it, so that the edits of materials this run does not process (another stage's that uses the same
    document, an earlier run's) are kept. Else None (start from the source), and the image nodes it had edited,
    whose edits are then lost."""
    if not out.is_file() or out == src:
        return None, []
    earlier = mx.createDocument()
    try:
        mx.readFromXmlFile(earlier, str(out), mx.FileSearchPath(), read_options())
    except Exception:  # not a document any more: it is replaced
        return None, []
    if source_hash and earlier.getAttribute(MtlxNames.MADE_FROM) == source_hash:
        return earlier, []
    return None, [e.getNamePath() for e in earlier.traverseTree() if e.hasAttribute(MtlxNames.SOURCE_ASSET)]


def read_mtlx_provenance(node: mx.Node) -> Provenance | None:
    """The provenance recorded on a MaterialX node, or None."""
    if not node.hasAttribute(MtlxNames.SOURCE_ASSET):
        return None

    def floats(name: str, n: int = 2) -> tuple:
        text = node.getAttribute(name)
        return tuple(float(v) for v in text.split(",")) if text else (0.0,) * n

    return Provenance(
        source_asset=node.getAttribute(MtlxNames.SOURCE_ASSET),
        crop_size=tuple(int(v) for v in floats(MtlxNames.CROP_SIZE)),
        uv_scale=floats(MtlxNames.UV_SCALE),
        q_passed=(node.getAttribute(MtlxNames.Q_PASSED) == "true") if node.hasAttribute(MtlxNames.Q_PASSED) else None,
        q_tau=floats(MtlxNames.Q_TAU, 1)[0],
        q_band_min=floats(MtlxNames.Q_BAND_MIN),
        model_hash=node.getAttribute(MtlxNames.MODEL_HASH),
        tool_version=node.getAttribute(MtlxNames.TOOL_VERSION),
        passed=node.getAttribute(MtlxNames.PASSED) == "true",
        verdict=node.getAttribute(MtlxNames.VERDICT),
        straightened=floats(MtlxNames.STRAIGHTENED, 1)[0],
        levelled=floats(MtlxNames.LEVELLED, 1)[0],
        evened=floats(MtlxNames.EVENED, 1)[0],
        uv_turn=floats(MtlxNames.UV_TURN, 1)[0],
        rectified=floats(MtlxNames.RECTIFIED, 3),
    )


def _same_path(a: str | None, b: Path) -> bool:
    if not a:
        return False
    try:
        return os.path.samefile(a, b)
    except OSError:
        return Path(a).resolve() == b


class _MtlxAuthor(_PlaceUV):
    def __init__(self, doc: mx.Document, src: Path, out: Path, result: AuthoringResult):
        self.doc, self.src, self.out, self.result = doc, src, out, result
        self.read_from = src  # the document ``doc`` was read from: its recorded source assets are relative to it
        self.changed = False
        self._uv_nodes: dict[tuple, str] = {}
        self._uv_updates: dict[str, tuple] = {}  # a place2d a run before inserted -> (total scale, turn): once a run
        self._done: dict[str, tuple] = {}
        self._tiling_set: dict[str, tuple] = {}  # a tiledimage's uvtiling / uvoffset input -> (its value, the new)

    def _plan(self, line: str) -> None:
        self.result.plan.append(f"{line} in {asset_ref(self.out.name)}")
        self.changed = True

    def _record(self, elem: mx.Element, values: list[tuple[str, str | None]]) -> None:
        """Set the provenance attributes ``values`` on ``elem`` (None: not recorded, an older run's value goes), with
        one plan line for them all: a dry run's values are not yet those of the run."""
        changed = False
        for name, value in values:
            if value is None:
                if elem.hasAttribute(name):
                    elem.removeAttribute(name)
                    changed = True
            elif elem.getAttribute(name) != value:
                elem.setAttribute(name, value)
                changed = True
        if changed:
            self._plan(f"record the tile's provenance (seamless_* attributes) on {prim_ref(elem.getNamePath())}")

    def set_source_hash(self, source_hash: str) -> None:
        """Record on the new document what it was made from (:data:`MtlxNames.MADE_FROM`)."""
        if source_hash and self.doc.getAttribute(MtlxNames.MADE_FROM) != source_hash:
            self.doc.setAttribute(MtlxNames.MADE_FROM, source_hash)  # not a change of its own: no plan line

    def rebase_files(self) -> None:
        """Keep this document's relative file paths valid from a new folder."""
        if any(e.getSourceUri() for e in self.doc.getChildren()):
            self.result.findings.append(Finding(
                Severity.WARNING, Codes.MTLX_INCLUDES_MOVED, asset_ref(self.out),
                "the new document is in another folder; its XIncludes keep their relative hrefs"))
        for child in self.doc.getChildren():
            if not child.getSourceUri():  # an included document's elements are not written: left as they are
                self._rebase(child, self.src.parent)

    def _rebase(self, elem: mx.Element, base: Path) -> None:
        """The relative file paths in ``elem``, read from the folder ``base``, made relative to the new document."""
        for inner in elem.traverseTree():
            if isinstance(inner, mx.Input) and inner.getType() == MtlxNames.FILENAME and inner.getValueString():
                value = inner.getResolvedValueString()
                if value and not os.path.isabs(value):
                    self._set_file(inner, relative_asset_path(base / value, self.out.parent))

    def _adopt(self, node: mx.Node) -> None:
        """Bring the document an ``xi:include`` reads, when it holds ``node``, into this one, so that the edits are
        written (MaterialX writes an included element back as the include, without them): every element it holds
        (an element of the same name, written beside the include, would lose to the included one when read), its
        file paths made relative to the new document."""
        top = node
        while top.getParent() != self.doc:
            top = top.getParent()
        uri = top.getSourceUri()
        if not uri:
            return
        included = Path(uri) if os.path.isabs(uri) else Path(self.doc.getSourceUri() or self.src).parent / uri
        for child in self.doc.getChildren():
            if child.getSourceUri() == uri:
                child.setSourceUri("")
                self._rebase(child, included.parent)
        self._plan(f"write the elements of the included {asset_ref(uri)} into the document")
        self.result.findings.append(Finding(
            Severity.WARNING, Codes.MTLX_INCLUDE_INLINED, prim_ref(top.getNamePath()),
            f"comes from {asset_ref(uri)}, which the document includes: that document's elements are written into "
            f"{asset_ref(self.out.name)} in place of the include, with the edits, and the included file is left as "
            "it is"))

    def _set_file(self, inp: mx.Input, rel: str) -> None:
        rel = rel[2:] if rel.startswith("./") else rel
        # the input's own fileprefix "./" overrides any inherited one: the value is doc-relative
        if inp.getActiveFilePrefix() and (not inp.hasFilePrefix() or inp.getFilePrefix() != "./"):
            inp.setFilePrefix("./")
            self.changed = True
        if inp.getValueString() != rel:
            inp.setValueString(rel)
            self._plan(f"set {prim_ref(inp.getNamePath())} = {asset_ref(rel)}")

    def _authored(self, node: mx.Node, name: str, type_name: str) -> mx.Input:
        """The input holding ``name``'s value: the interface input it reads, or the node's own."""
        inp = node.getInput(name)
        if inp is not None and inp.getInterfaceName():
            iface = inp.getInterfaceInput()
            if iface is not None:
                return iface
        return inp if inp is not None else UnauthoredInput(node, name, type_name)

    def _periodic(self, node: mx.Node, dry: bool = False) -> bool:
        """Address modes to periodic (``tiledimage`` always repeats); whether they already were. ``dry``: only
        say whether they are."""
        already = True
        if node.getCategory() == MtlxNames.TILED_IMAGE:
            return already
        for name in (MtlxNames.U_ADDRESS, MtlxNames.V_ADDRESS):
            inp = self._authored(node, name, MtlxNames.STRING)
            if inp.getValueString() != MtlxNames.PERIODIC:
                already = False
                if not dry:
                    inp, cut = own_input(node, name, inp)  # an interface input a decal reads too stays as it is
                    if cut:
                        self._plan(cut)
                    inp.setValueString(MtlxNames.PERIODIC)
                    self._plan(f"set {prim_ref(inp.getNamePath())} = {MtlxNames.PERIODIC}")
        return already

    def edit_map(self, map_result, uv_scale, provenance: Provenance, wrap_only: bool = False,
                 turn: UVTurn | None = None, scale_known: bool = True) -> None:
        """Edit one map's node; ``wrap_only`` (an already-tileable source): address modes only; ``turn``: a
        straightened tile turned back in the UVs; ``scale_known`` False: a dry run's guessed UV scale, planned as
        a factor of the tile's."""
        tex_map = map_result.map
        node_path = tex_map.node.strip("<>")
        node = self.doc.getDescendant(node_path)
        if node is None or not isinstance(node, mx.Node):
            self.result.findings.append(Finding(Severity.ERROR, Codes.MISSING_PRIM,
                                                prim_ref(node_path), "MaterialX node not found"))
            self.result.not_written.append((node_key(tex_map), "MaterialX node not found in the document"))
            return
        if wrap_only:
            if not self._periodic(node, dry=True):
                self._adopt(node)
                self._periodic(node)
            return
        self._adopt(node)
        out_file = Path(map_result.output_path).resolve()
        if not out_file.is_file() and not self.result.dry_run:  # a dry run plans unwritten tiles
            self.result.findings.append(Finding(
                Severity.ERROR, Codes.MISSING_OUTPUT, asset_ref(out_file),
                f"tileable file for {prim_ref(node_path)} not found; nothing written for it"))
            self.result.not_written.append((node_key(tex_map), f"tileable file {asset_ref(out_file)} not found"))
            return
        scale = (float(uv_scale[0]), float(uv_scale[1]))
        if node_path in self._done:
            if self._done[node_path][:2] != (out_file, scale):
                self.result.findings.append(Finding(
                    Severity.WARNING, Codes.SHARED_CONFLICT, prim_ref(node_path),
                    f"node shared by {self._done[node_path][2]} and {tex_map.material} with "
                    f"different results; kept {self._done[node_path][2]}'s"))
                self.result.not_written_for.append((tex_map.material, node_key(tex_map),
                                                    shared_with(self._done[node_path][2])))
            return
        self._done[node_path] = (out_file, scale, tex_map.material)
        before = len(self.result.plan)
        recorded = read_mtlx_provenance(node)
        recorded_source = None if recorded is None else self.read_from.parent / recorded.source_asset
        from_source = recorded is None or _same_path(str(recorded_source), Path(tex_map.resolved))
        # file
        at = tex_map.file_at
        owner = self.doc.getDescendant(at.prim.strip("<>")) if at.prim else None
        file_input = owner if isinstance(owner, mx.Input) else (
            owner.getInput(at.attribute) if owner is not None and hasattr(owner, "getInput") else None)
        if file_input is None:
            file_input = self._authored(node, MtlxNames.FILE, MtlxNames.FILENAME)
        file_input, cut = own_file_input(node, file_input)
        if cut:
            self._plan(cut)
        current = file_input.getResolvedValueString()
        if current and set_by_hand(str(self.out.parent / current), tex_map.resolved):
            self.result.not_written.append((node_key(tex_map), SET_BY_HAND.format(
                where=f" in {asset_ref(self.out)}", asset=asset_ref(file_input.getValueString()), kind="document")))
            return
        self._set_file(file_input, relative_asset_path(out_file, self.out.parent))
        category = node.getCategory()
        self._periodic(node)
        # UV scale
        prior = recorded.uv_scale if recorded else None
        total = scale if from_source or prior is None else (prior[0] * scale[0], prior[1] * scale[1])
        degrees = 0.0
        if category == MtlxNames.TILED_IMAGE:
            undo = prior or (1.0, 1.0)
            for name in (MtlxNames.UV_TILING, MtlxNames.UV_OFFSET):
                inp = self._authored(node, name, MtlxNames.VECTOR2)
                if isinstance(inp, mx.Input) and (inp.getNodeName() or inp.getNodeGraphString()):  # fed by a node
                    self._scale_connected(inp, name, total)
                    continue
                where = inp.getNamePath()
                value = vector2(inp.getValueString()) if inp.getValueString() else (
                    (1.0, 1.0) if name == MtlxNames.UV_TILING else (0.0, 0.0))
                value = self._tiling_set.get(where, (value,))[0]  # an input nodes share is scaled once a run
                new = (value[0] / undo[0] * total[0], value[1] / undo[1] * total[1])
                if where in self._tiling_set:
                    if any(abs(new[i] - self._tiling_set[where][1][i]) > 1e-9 for i in range(2)):
                        self.result.findings.append(Finding(
                            Severity.WARNING, Codes.SHARED_CONFLICT, prim_ref(where),
                            f"{name} shared by texture nodes of different UV scales; kept the first one's"))
                    continue
                self._tiling_set[where] = (value, new)
                if any(abs(new[i] - value[i]) > 1e-9 for i in range(2)):
                    set_vector2(inp, new)
                    self._plan(f"set {prim_ref(inp.getNamePath())} = {fmt(new)}")
                elif self.result.dry_run and name == MtlxNames.UV_TILING and not scale_known:  # known once made
                    self._plan(f"set {prim_ref(inp.getNamePath())} = {fmt(value)} x the tile's UV scale")
        elif category.startswith(MtlxNames.GLTF_PREFIX) and not gltf_identity(node):
            self.result.findings.append(Finding(
                Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(node_path),
                "gltf image node with its own UV transform: file replaced, scale its UVs by hand"))
            total = (1.0, 1.0)
        else:
            total, degrees = self._place2d(node, scale, from_source, turn)
        if turn is not None and not degrees and from_source:
            self.result.findings.append(Finding(
                Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(node_path),
                f"{category} node: {TURN_NOT_AUTHORED}"))
        # provenance
        if recorded and not from_source:  # the tile was made from an earlier tile: keep the origin
            source = relative_asset_path(recorded_source, self.out.parent).removeprefix("./")
        elif tex_map.resolved:
            source = relative_asset_path(Path(tex_map.resolved), self.out.parent).removeprefix("./")
        else:
            source = provenance.source_asset
        p = provenance
        self._record(node, [
            (MtlxNames.SOURCE_ASSET, source),
            (MtlxNames.CROP_SIZE, fmt(p.crop_size)),
            (MtlxNames.UV_SCALE, fmt(total)),
            (MtlxNames.PASSED, "true" if p.passed else "false"),
            (MtlxNames.VERDICT, p.verdict),
            (MtlxNames.Q_PASSED, None if p.q_passed is None else "true" if p.q_passed else "false"),
            (MtlxNames.Q_TAU, None if p.q_passed is None else fmt([float(p.q_tau)])),
            (MtlxNames.Q_BAND_MIN, None if p.q_passed is None else fmt(p.q_band_min)),
            (MtlxNames.MODEL_HASH, p.model_hash or None),  # no network made it: not recorded
            (MtlxNames.TOOL_VERSION, p.tool_version),
            (MtlxNames.STRAIGHTENED, fmt([float(p.straightened)]) if p.straightened else None),
            (MtlxNames.LEVELLED, fmt([float(p.levelled)]) if p.levelled else None),
            (MtlxNames.EVENED, fmt([float(p.evened)]) if p.evened else None),
            (MtlxNames.UV_TURN, fmt([float(degrees)]) if degrees else None),
            (MtlxNames.RECTIFIED, fmt([float(v) for v in p.rectified]) if p.rectified[2] else None),
        ])
        if len(self.result.plan) > before and prim_ref(node_path) not in self.result.edited_prims:
            self.result.edited_prims.append(prim_ref(node_path))
