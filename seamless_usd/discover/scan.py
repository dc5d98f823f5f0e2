"""The discovery entry points: scan stages, in-memory stages and MaterialX documents."""
from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path

from pxr import Sdf, Tf, Usd

from seamless_usd.discover import mtlx, usd
from seamless_usd.discover.maps import HeaderCache, TextureUse, build_maps
from seamless_usd.discover.stacks import build_stacks
from seamless_usd.discover.tokens import MTLX_SUFFIX, Codes
from seamless_usd.discover.types import ScanResult
from seamless_usd.errors import InputError
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["scan_paths", "scan_stage", "scan_mtlx", "open_stage"]


def open_stage(path: str | Path) -> Usd.Stage:
    """Open a USD stage with all payloads loaded; InputError naming the file when it cannot be."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{asset_ref(path)}: no such file")
    try:
        with Tf.DiagnosticTrap() as trap:
            stage = Usd.Stage.Open(str(path.resolve()), Usd.Stage.LoadAll)
            # usd-core cannot compose .mtlx references; discovery reads them itself, so USD's
            # warning about them is noise. Every other diagnostic is passed on when the trap closes.
            trap.EraseMatching(lambda d: MTLX_SUFFIX in str(d.commentary).lower())
    except Tf.ErrorException as exc:
        raise InputError(f"{asset_ref(path)}: cannot open the USD stage: {_tf_message(str(exc))}") from None
    if stage is None:
        raise InputError(f"{asset_ref(path)}: cannot open the USD stage")
    return stage


def _tf_message(text: str) -> str:
    """The useful part of a Tf error (``3:40: Expected ) at ...``), on one line."""
    first = next((ln.strip() for ln in text.splitlines() if ln.strip()), "unreadable")
    quoted = re.search(r" : '(.*)'", first)
    message = quoted.group(1) if quoted else first
    return re.sub(r"^\S+?\.usd[acz]?:(?=\d)", "line ", message)


class _Scan:
    """Accumulates one scan over any number of stages and documents."""

    def __init__(self) -> None:
        self.result = ScanResult()
        self.uses: list[TextureUse] = []
        self.cache = HeaderCache()

    def add_stage(self, stage: Usd.Stage, source: str) -> None:
        self.result.sources.append(source)
        materials, uses, refs, errors = usd.walk_stage(stage)
        self.result.materials.extend(materials)
        self.uses.extend(uses)
        self.result.findings.extend(errors)
        for err in stage.GetCompositionErrors():
            text = str(err.ToString()) if hasattr(err, "ToString") else str(err)
            if MTLX_SUFFIX in text.lower():
                continue  # .mtlx references are read below
            self.result.findings.append(
                Finding(Severity.WARNING, Codes.COMPOSITION_ERROR, asset_ref(source), text.splitlines()[0])
            )
        for ref in refs:
            if not ref.document:
                self.result.findings.append(
                    Finding(Severity.SKIPPED, Codes.MISSING_FILE, f"{prim_ref(ref.prim)} {asset_ref(ref.asset)}",
                            "referenced MaterialX document not found")
                )
                continue
            try:
                doc = mtlx.read_document(ref.document)
            except InputError as exc:
                self.result.findings.append(
                    Finding(Severity.SKIPPED, Codes.MTLX_UNREADABLE, f"{prim_ref(ref.prim)} {asset_ref(ref.asset)}", str(exc))
                )
                continue
            only = Sdf.Path(ref.target).name if ref.target else ""
            materials, uses, errors = mtlx.walk_document(doc, ref.document, under=ref.prim, only=only)
            if ref.document not in self.result.sources:
                self.result.sources.append(ref.document)
            self.result.materials.extend(materials)
            self.uses.extend(uses)
            self.result.findings.extend(errors)

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
        self.result.stacks = build_stacks(maps)
        return self.result


def scan_stage(stage: Usd.Stage) -> ScanResult:
    """Scan an open stage (possibly in memory, as a DCC export hook has it).

    >>> from pxr import Usd
    >>> scan_stage(Usd.Stage.CreateInMemory()).stacks
    []
    """
    scan = _Scan()
    layer = stage.GetRootLayer()
    scan.add_stage(stage, layer.realPath or layer.identifier)
    return scan.finish()


def scan_mtlx(path: str | Path) -> ScanResult:
    """Scan one MaterialX document."""
    scan = _Scan()
    scan.add_document(path)
    return scan.finish()


def scan_paths(paths: Sequence[str | Path]) -> ScanResult:
    """Scan USD stages and ``.mtlx`` documents by path, into one result.

    Raises InputError (naming the file) for a stage or document that cannot be opened.
    """
    scan = _Scan()
    for path in paths:
        if str(path).lower().endswith(MTLX_SUFFIX):
            scan.add_document(path)
        else:
            stage = open_stage(path)
            scan.add_stage(stage, str(Path(path).resolve()))
    return scan.finish()
