"""The discovery entry points: scan stages, in-memory stages and MaterialX documents."""
from __future__ import annotations

import contextlib
import re
from dataclasses import replace
from collections.abc import Sequence
from pathlib import Path

from pxr import Sdf, Tf, Usd

from seamless_usd.discover import mtlx, usd, uvgeom
from seamless_usd.discover.bound import Geometry as _Geometry
from seamless_usd.discover.images import IMAGE_SUFFIXES
from seamless_usd.discover.intent import THRESHOLDS, classify_stacks
from seamless_usd.discover.triagememo import TriageMemo
from seamless_usd.discover.maps import HeaderCache, TextureUse, build_maps
from seamless_usd.discover.stacks import build_stacks
from seamless_usd.discover.tokens import MTLX_SUFFIX, Codes
from seamless_usd.textures import ExploredSelection, ScanResult, TextureStack, VariantExploration, describe_selection
from seamless_usd.discover.variants import VariantSpace
from seamless_usd.errors import InputError, Interrupted
from seamless_usd.findings import Finding, Severity, asset_ref, not_found_words, prim_ref

__all__ = ["scan_paths", "scan_stage", "scan_mtlx", "open_stage"]


def not_a_scene(path: Path) -> InputError:
    """The error for a file given as a stage or document that is neither (a picture: ``check`` judges it)."""
    picture = path.suffix.lower() in IMAGE_SUFFIXES
    return InputError(f"{asset_ref(path)} is {'a picture' if picture else 'neither a USD stage nor a MaterialX document'}"
                      ": scan and process read USD stages (.usd, .usda, .usdc, .usdz) and MaterialX documents (.mtlx)"
                      + ("; judge a picture on its own with `seamless-usd check`" if picture else ""))


def open_stage(path: str | Path) -> Usd.Stage:
    """Open a USD stage with all payloads loaded; InputError naming the file when it cannot be."""
    path = Path(path)
    if path.is_dir():
        raise InputError(f"{asset_ref(path)} is a folder, not a USD stage")
    if not path.is_file():
        raise InputError(f"{asset_ref(path)}: no such file")
    if not Sdf.FileFormat.FindByExtension(path.suffix.lstrip(".").lower() or "-"):
        raise not_a_scene(path)
    try:
        with quiet_mtlx():
            stage = Usd.Stage.Open(str(path.resolve()), Usd.Stage.LoadAll)
    except Tf.ErrorException as exc:
        raise InputError(f"{asset_ref(path)}: cannot open the USD stage: {_tf_message(str(exc))}") from None
    if stage is None:
        raise InputError(f"{asset_ref(path)}: cannot open the USD stage")
    dirty = [layer for layer in stage.GetUsedLayers() if layer.dirty and not layer.anonymous]
    if dirty:  # held open and edited in this process (a stage process_stage authored into, not saved)
        raise InputError(f"{asset_ref(dirty[0].realPath or dirty[0].identifier)} has unsaved changes in this process, "
                         f"so it is not the file on disk: save or reload it first")
    return stage


@contextlib.contextmanager
def quiet_mtlx():
    """usd-core cannot compose .mtlx references; discovery reads them itself, so USD's warnings
    about them (at each composition) are noise. So are the composition errors it prints as it composes (a sublayer
    or reference that cannot be opened): the scan reports each as a ``composition-error`` finding, under every
    variant selection explored. Every other diagnostic is passed on."""
    with Tf.DiagnosticTrap() as trap:
        yield
        trap.EraseMatching(lambda d: MTLX_SUFFIX in str(d.commentary).lower()
                           or str(d.sourceFunction).endswith("UsdStage::_ReportErrors"))


def _tf_message(text: str) -> str:
    """The useful part of a Tf error (``3:40: Expected ) at ...``), on one line: the quoted message whole (a
    parse error quotes the text it stopped at, newlines included), USD's internal namespace left out.

    >>> _tf_message("Error in 'f' at line 1 in file x.cpp : '/a/b.usda:4:1: parse error matching "
    ...             "pxrInternal_v0_26_11__pxrReserved__::Sdf_TextFileFormatParser::ListValueClose at '}\\n''")
    "line 4:1: parse error matching Sdf_TextFileFormatParser::ListValueClose at '}'"
    """
    text = text.strip() or "unreadable"
    blocks = [b for b in re.split(r"(?=\bError in ')", text) if b.strip()]  # the first error says why
    text = blocks[0] if blocks else text
    quoted = re.search(r" : '(.*)'", text, re.DOTALL)
    message = quoted.group(1) if quoted else next(ln.strip() for ln in text.splitlines() if ln.strip())
    message = re.sub(r"pxrInternal_v[0-9_]+?__pxrReserved__::", "", " ".join(message.split()))
    message = re.sub(r"at '(.*?)\s*'$", r"at '\1'", message)
    return re.sub(r"^\S+?\.usd[acz]?:(?=\d)", "line ", message)


_MTLX_ROOT = Sdf.Path("/MaterialX")  # where usdMtlx puts a document's prims
_MTLX_MATERIALS = _MTLX_ROOT.AppendChild("Materials")


def _mtlx_target(target: str) -> tuple[str, bool]:
    """(one material's name or "", materials directly under the referencing prim) for a
    reference's target path inside a ``.mtlx`` document, as usdMtlx lays documents out."""
    path = Sdf.Path(target) if target else _MTLX_ROOT
    if path == _MTLX_ROOT:
        return "", False
    if path == _MTLX_MATERIALS:
        return "", True
    return path.name, False


class _Scan:
    """Accumulates one scan over any number of stages and documents."""

    def __init__(self, triage_dir: Path | None = None, keep_triage: bool = True) -> None:
        self.triage = TriageMemo(triage_dir, repr(THRESHOLDS), keep_triage)  # pixel figures of the triage, by content
        self.result = ScanResult()
        self.uses: list[TextureUse] = []
        self.cache = HeaderCache()
        self.geometry = _Geometry()  # the bound geometry of each material, per variant selection
        self._use_keys: dict[tuple, TextureUse] = {}

    def add_stage(self, stage: Usd.Stage, source: str) -> None:
        """Walk ``stage`` under every selection of its variant space (see ``variants.py``)."""
        self.result.sources.append(source)
        space = VariantSpace(stage)
        explored: list[ExploredSelection] = []
        seen_refs: dict = {}  # a .mtlx reference is read once: its materials and uses
        seen_errors: set = set()
        with quiet_mtlx():  # recomposing under each selection
            self._explore(space, source, explored, seen_refs, seen_errors)
        for prim, name, variants, instance, count in space.in_instances():
            more = f" (and in {count - 1} more instance{'s' if count > 2 else ''} of it)" if count > 1 else ""
            self.result.findings.append(Finding(
                Severity.WARNING, Codes.VARIANT_IN_INSTANCE, prim_ref(prim),
                f"variant set '{name}' ({', '.join(variants)}) inside the instance {prim_ref(instance)}{more}: only "
                "its selected variant is scanned, as an instance's prims take no selection of their own; to reach "
                "the materials of its other variants, scan the asset's own file, or make the instance not "
                "instanceable"))
        if space.combinations > 1 or space.mode != "all":
            self.result.variants.append(VariantExploration(source, space.mode, space.combinations, space.limit,
                                                           tuple(explored)))

    def _explore(self, space: VariantSpace, source: str, explored: list, seen_refs: dict, seen_errors: set) -> None:
        for selection in space.selections():
            composed = space.current
            found: list[str] = []
            materials, uses, refs, errors = usd.walk_stage(composed)
            found.extend(materials)
            for err in errors:
                if (err.where, err.message) not in seen_errors:
                    seen_errors.add((err.where, err.message))
                    self.result.findings.append(err)
            self._composition_errors(composed, source, selection, seen_errors)
            for ref in refs:
                key = (ref.prim, ref.document, ref.target)
                if key not in seen_refs:
                    seen_refs[key] = self._add_reference(ref)
                found.extend(seen_refs[key][0])
                uses = uses + seen_refs[key][1]
            index = self.geometry.add(space, selection, uvgeom.material_bindings(composed))
            for use in uses:
                self._add_use(use, selection, index)
            for material in found:
                if material not in self.result.materials:
                    self.result.materials.append(material)
            explored.append(ExploredSelection(selection, tuple(dict.fromkeys(found))))

    def _add_use(self, use: TextureUse, selection: tuple, index: int) -> None:
        """A use seen first under ``selection`` keeps it; seen again, only its selections grow."""
        key = use.key()
        first = self._use_keys.get(key)
        if first is None:
            use.selection = selection
            self._use_keys[key] = use
            self.uses.append(use)
            first = use
        else:  # authored inside a variant only where it is so under every selection
            first.file_in_variant = first.file_in_variant and use.file_in_variant
        self.geometry.seen(first, index)

    def _composition_errors(self, stage: Usd.Stage, source: str, selection: tuple, seen: set) -> None:
        """The stage's composition errors under ``selection`` as findings, each once (``seen``)."""
        for err in stage.GetCompositionErrors():
            text = str(err.ToString()) if hasattr(err, "ToString") else str(err)
            if MTLX_SUFFIX in text.lower():
                continue  # .mtlx references are read below
            line = text.splitlines()[0]
            if ("composition", line) in seen:
                continue
            seen.add(("composition", line))
            where = f" (in {describe_selection(selection)})" if selection else ""
            # the prim whose arc failed names the finding where USD says it (a reference or payload to a missing file)
            site = re.search(r"introduced by @[^@]*@<([^>]+)>", line)
            fix = (": what it would bring is not scanned; restore the file or fix the arc's asset path"
                   if "Could not open asset" in line else "")
            self.result.findings.append(Finding(Severity.WARNING, Codes.COMPOSITION_ERROR,
                                                prim_ref(str(Sdf.Path(site.group(1)).StripAllVariantSelections()))
                                                if site else asset_ref(source),
                                                line.rstrip(".") + where + fix))

    def _add_reference(self, ref) -> tuple[list[str], list[TextureUse]]:
        """Materials and uses of a ``.mtlx`` document referenced from a prim."""
        if not ref.document:
            self.result.findings.append(
                Finding(Severity.SKIPPED, Codes.MISSING_FILE, f"{prim_ref(ref.prim)} {asset_ref(ref.asset)}",
                        "referenced MaterialX document not found")
            )
            return [], []
        try:
            doc = mtlx.read_document(ref.document)
        except InputError as exc:
            self.result.findings.append(
                Finding(Severity.SKIPPED, Codes.MTLX_UNREADABLE, f"{prim_ref(ref.prim)} {asset_ref(ref.asset)}",
                        str(exc))
            )
            return [], []
        only, flat = _mtlx_target(ref.target)
        materials, uses, errors = mtlx.walk_document(doc, ref.document, under=ref.prim, only=only, flat=flat)
        if ref.document not in self.result.sources:
            self.result.sources.append(ref.document)
        self.result.findings.extend(errors)
        return materials, uses

    def add_document(self, path: str | Path) -> None:
        doc = mtlx.read_document(path)
        source = str(Path(path).resolve())
        self.result.sources.append(source)
        materials, uses, errors = mtlx.walk_document(doc, source)
        self.result.materials.extend(materials)
        self.uses.extend(uses)
        self.result.findings.extend(errors)

    def finish(self) -> ScanResult:
        maps, findings = build_maps(self.uses, self.cache)
        self.result.findings.extend(findings)
        stacks = build_stacks(self.geometry.complete(maps))
        if self.result.sources:  # the stage or document scanned (a document it references is listed after it)
            stacks = [replace(s, source=self.result.sources[0]) for s in stacks]
        with quiet_mtlx():  # composing each selection again
            self.geometry.measure(stacks)
        self.result.stacks = classify_stacks(stacks, self.geometry, explored=self.geometry.explored_for,
                                             memo=self.triage)
        self.result.findings.extend(_undecodable(self.result.stacks, self.triage))
        return self.result


def _undecodable(stacks: list[TextureStack], triage: TriageMemo) -> list[Finding]:
    """A skipped ``unreadable-file`` finding for each file the triage found whose header reads but whose pixels do
    not decode (truncated, corrupt), as for one whose header does not read: its material's stack cannot be made."""
    out = []
    for stack in stacks:
        judged = triage.seen("verdict", stack.maps) or {}
        broken = [m for m in stack.maps if m.asset == judged.get("unreadable")]
        if broken:
            m = broken[0]
            out.append(Finding(Severity.SKIPPED, Codes.UNREADABLE_FILE, f"{prim_ref(m.node)} {asset_ref(m.asset)}",
                               f"cannot decode the image: {judged['error']} (material {stack.material})",
                               material=stack.material))
    return out


def scan_stage(stage: Usd.Stage, triage_dir: Path | None = None, keep_triage: bool = True) -> ScanResult:
    """Scan an open stage (possibly in memory, as a DCC export hook has it). ``triage_dir``: where the
    triage's pixel figures are kept between runs (see ``triagememo.py``); None keeps them for this scan only;
    ``keep_triage`` False reads the figures kept there and adds none (a dry run).

    >>> from pxr import Usd
    >>> scan_stage(Usd.Stage.CreateInMemory()).stacks
    []
    """
    scan = _Scan(triage_dir, keep_triage)
    layer = stage.GetRootLayer()
    scan.add_stage(stage, layer.realPath or layer.identifier)
    unloaded = sorted(set(stage.FindLoadable()) - set(stage.GetLoadSet()))
    if unloaded:  # an export hook's stage opened with LoadNone: what is inside those payloads is not composed
        more = f" and {len(unloaded) - 1} more" if len(unloaded) > 1 else ""
        scan.result.findings.append(Finding(
            Severity.WARNING, Codes.UNLOADED_PAYLOAD, prim_ref(unloaded[0]),
            f"payload not loaded{more}: the materials inside are not scanned or processed (load them first: "
            "stage.Load(), or open the stage with Usd.Stage.LoadAll)"))
    return scan.finish()


def scan_mtlx(path: str | Path, triage_dir: Path | None = None, keep_triage: bool = True) -> ScanResult:
    """Scan one MaterialX document (``triage_dir``, ``keep_triage``: as for :func:`scan_stage`)."""
    scan = _Scan(triage_dir, keep_triage)
    scan.add_document(path)
    return scan.finish()


def scan_paths(paths: Sequence[str | Path], unreadable: list | None = None) -> ScanResult:
    """Scan USD stages and ``.mtlx`` documents by path, into one result.

    Raises InputError (naming the file) for a stage or document that cannot be opened; with ``unreadable`` (a
    list), that file is appended to it instead, with an error finding, and the other inputs are scanned. Stopped by
    Ctrl-C (or SIGTERM, which the command line raises as one), it raises :class:`.errors.Interrupted` carrying what
    was scanned by then (``interrupted`` set).
    """
    merged = ScanResult()
    try:
        _scan_into(merged, paths, unreadable)
    except KeyboardInterrupt:
        merged.interrupted = True
        raise Interrupted(merged) from None
    return merged


def _scan_into(merged: ScanResult, paths: Sequence[str | Path], unreadable: list | None) -> None:
    """:func:`scan_paths`' work, into ``merged`` one input at a time (so an interrupted scan keeps what it found)."""
    first_by_content: dict[str, str] = {}
    for path in paths:  # each on its own: materials of two stages that share a prim path are two materials
        scan = _Scan()
        try:
            if Path(path).is_dir() or not Path(path).exists():  # a folder or a pattern that gave nothing
                raise InputError(f"{asset_ref(path)}: {not_found_words(path)}")
            if str(path).lower().endswith(MTLX_SUFFIX):
                scan.add_document(path)
            else:
                stage = open_stage(path)
                scan.add_stage(stage, str(Path(path).resolve()))
        except InputError as exc:
            if unreadable is None:
                raise
            unreadable.append(str(path))
            where = asset_ref(path)
            merged.findings.append(Finding(Severity.ERROR, "unreadable-input", where,
                                           str(exc).removeprefix(f"{where}: ")))
            continue
        found = scan.finish()
        for stack in found.stacks:
            earlier = first_by_content.setdefault(stack.content_key, stack.id)
            duplicate = stack.duplicate_of or (earlier if earlier != stack.id else None)
            merged.stacks.append(replace(stack, duplicate_of=duplicate))
        merged.sources += [s for s in found.sources if s not in merged.sources]
        merged.materials += found.materials
        merged.findings += found.findings
        merged.variants += found.variants
