"""List the texture stacks of USD stages and MaterialX documents, and what would be skipped.

For each material: its maps, their roles and channels, colour space, size and UV chain; then the
skipped items and warnings with their reasons. ``--json`` prints the scan as JSON following
``schemas/scan.schema.json``. Exit code 0 when the scan ran (even with skipped items), 2 for a
stage or document that cannot be read, 130 stopped by Ctrl-C or SIGTERM (what was scanned by then is
said, ``interrupted`` in the JSON), 141 the reader of its output went away.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path, PurePath

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from seamless_usd.discover import ScanResult, TextureMap, TextureStack, UVChain, scan_paths
from seamless_usd.errors import Interrupted
from seamless_usd.pipeline.inputs import expand_inputs
from seamless_usd.textures import describe_selection

__all__ = ["add_arguments", "run", "render"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", nargs="+", metavar="PATH",
                        help="USD stage (.usd/.usda/.usdc/.usdz), .mtlx document, folder (walked for them) or glob")
    parser.add_argument("--json", action="store_true", help="print the scan as JSON (schemas/scan.schema.json)")


def _inputs(paths: list[str]) -> list[Path]:
    """Stages and documents named, found in folders or matched by globs, as ``process`` takes them (a folder that
    holds none, or a pattern that matches none, is given back to be named as an input that cannot be read)."""
    return expand_inputs(paths, require_scenes=True)


def run(args: argparse.Namespace) -> int:
    unreadable: list[str] = []  # named as errors; the other inputs are scanned (exit code 2)
    try:
        result = scan_paths(_inputs(args.paths), unreadable=unreadable)
    except Interrupted as stop:  # what was scanned by then is said (with --json, printed) before the run ends so
        _said(stop.report, args.json)
        raise
    _said(result, args.json)
    return 2 if unreadable else 0


def not_made(result: ScanResult) -> dict[str, str]:
    """Stack id -> why ``process`` will leave that stack meant to tile alone or fail it (a map inside a package, a UDIM
    set, a texture that cannot be read), so the scan says what the run will; read where one stage or document was
    scanned (across several, material paths may be shared, and a finding's material names no file)."""
    from seamless_usd.discover.select import blocked_stacks, set_aside_stacks

    if len(result.sources) != 1:
        return {}
    kept = {**set_aside_stacks(result, result.stacks, ""), **blocked_stacks(result, result.stacks, "")}
    return {s.id: kept[("", s.id)] for s in result.stacks if s.intent == "tiling" and ("", s.id) in kept}


def _said(result: ScanResult, as_json: bool) -> None:
    """The inputs that could not be read on stderr; the scan as JSON or as tables on stdout."""
    for f in result.findings:
        if f.code == "unreadable-input":
            print(f"seamless-usd: error: {f.where}: {f.message}", file=sys.stderr)
    if as_json:
        payload, kept = result.to_dict(), not_made(result)
        for row in payload["stacks"]:
            if row["id"] in kept:
                row["not_made"] = kept[row["id"]]
        print(json.dumps(payload, indent=2))
    elif result.sources:  # when nothing could be read, the error lines above are the whole answer
        # A pipe or file gets a wide table rather than rich's 80-column fallback.
        width = None if sys.stdout.isatty() else 160
        render(result, Console(file=sys.stdout, width=width, soft_wrap=False))


def _uv_text(uv: UVChain) -> str:
    parts = [f"primvar {uv.primvar}" if uv.primvar else ("default UVs" if uv.reader is None else "reader")]
    for t in uv.transforms:
        parts.append(f"{t.kind} scale {t.scale[0]:g},{t.scale[1]:g}" + (" (interface)" if t.authored else ""))
    return " > ".join(parts)


def _roles_text(m: TextureMap) -> str:
    return ", ".join(f"{r.role} ({r.channels})" for r in m.roles)


def _size_text(m: TextureMap) -> str:
    if m.image is None:
        return "?"
    return f"{m.image.width}x{m.image.height} {m.image.channels}ch {m.image.dtype} {m.image.file_format}"


def _stack_table(stack: TextureStack, common: str | None = None, kept: str = "") -> Table:
    """One stack's table; ``kept``: why ``process`` leaves a stack meant to tile alone or fails it (a map inside a
    package, a UDIM set, a texture that cannot be read), so the scan says what the run will."""
    title = escape(f"{stack.material}  stack {stack.id}")
    if common is not None and stack.source:  # several stages scanned: which one it is in
        title += escape(f"  of {os.path.relpath(stack.source, common)}")
    if stack.selection:
        title += escape(f"  in {describe_selection(stack.selection)}")
    if stack.duplicate_of:
        title += f"  (same as {stack.duplicate_of})"
    if stack.intent:
        title += escape(f"  intent: {stack.intent}")
    caption = f"UV: {_uv_text(stack.uv)}" + (f"\nintent {stack.intent}: {stack.intent_reason}" if stack.intent else "")
    caption += f"\nprocess: {kept}" if kept else ""
    table = Table(title=title, title_justify="left", caption=escape(caption), caption_justify="left")
    table.add_column("map", no_wrap=True)
    table.add_column("roles (channels)")
    for col in ("colour space", "size", "wrap", "notes"):
        table.add_column(col, overflow="fold")
    for m in stack.maps:
        notes = []
        if m.scale != (1.0, 1.0, 1.0, 1.0) or m.bias != (0.0, 0.0, 0.0, 0.0):
            notes.append(f"scale {','.join(f'{v:g}' for v in m.scale)} bias {','.join(f'{v:g}' for v in m.bias)}")
        if m.normal_y_flip:
            notes.append("Y-flipped normal")
        if m.resolved and PurePath(m.asset).name != PurePath(m.resolved.rstrip("]")).name:
            notes.append(f"reads {PurePath(m.resolved.rstrip(']')).name}")  # fileprefix, package paths
        if m.in_package:
            notes.append("inside package")
        if m.file_at.prim != m.node:
            notes.append(f"file set on <{m.file_at.prim}>")
        cells = (
            f"@{m.asset}@",
            _roles_text(m),
            f"{m.color_space.value}: {m.color_space_reason}",
            _size_text(m),
            f"{m.wrap_s}/{m.wrap_t}",
            "; ".join(notes),
        )
        table.add_row(*(escape(c) for c in cells))
    return table


#: Up to this many stages and documents scanned are listed by name at the top; more (a library) by their folder.
_LISTED_SOURCES = 5


def _duplicate_line(stack: TextureStack, first: TextureStack, common: str | None) -> str:
    """A stack whose maps and reads are those of ``first``, listed above in full, with the same UV chain and intent:
    one line."""
    where = f"  of {os.path.relpath(stack.source, common)}" if common is not None and stack.source else ""
    chosen = f"  in {describe_selection(stack.selection)}" if stack.selection else ""
    return escape(f"{stack.material}  stack {stack.id}{where}{chosen}: the same maps as {first.material} (stack "
                  f"{first.id}, above), intent {stack.intent}; made once for both")


def render(result: ScanResult, console: Console) -> None:
    """Print a scan as tables: one per stack (a stack the same as one listed above, read through the same UV chain
    with the same intent, in one line), then materials without stacks, then findings."""
    with_stacks = {s.material for s in result.stacks}
    scanned = sorted({s.source for s in result.stacks if s.source})
    common = os.path.commonpath([os.path.dirname(s) for s in scanned]) if len(scanned) > 1 else None
    if len(result.sources) > _LISTED_SOURCES:  # a library: its folder, not every file before the first stack
        where = os.path.commonpath([os.path.dirname(os.path.abspath(s)) for s in result.sources])
        console.print(f"[bold]scanned[/bold] {len(result.sources)} files under {escape(where)}")
    else:
        console.print(f"[bold]scanned[/bold] {escape(', '.join(result.sources))}")
    kept = not_made(result)
    first_of: dict[str, TextureStack] = {}  # each id's first stack, which its copies name
    for stack in result.stacks:
        first_of.setdefault(stack.id, stack)
    for stack in result.stacks:
        why = kept.get(stack.id, "")
        first = first_of.get(stack.duplicate_of) if stack.duplicate_of else None
        if first is not None and first.intent == stack.intent and _uv_text(first.uv) == _uv_text(stack.uv) and not why:
            console.print(_duplicate_line(stack, first, common))
        else:
            console.print(_stack_table(stack, common, why))
    bare = [m for m in result.materials if m not in with_stacks]
    if bare:
        console.print(escape(f"materials without texture stacks: {', '.join(bare)}"))
    for explored in result.variants:
        console.print(escape(f"variant selections of {explored.source}: {explored.note}"), soft_wrap=True)
        table = Table()
        table.add_column("variant selection")
        table.add_column("materials found", overflow="fold")
        for sel in explored.selections:
            table.add_row(escape(describe_selection(sel.selection) or "as the stage selects"),
                          escape(", ".join(sel.materials) or "none"))
        console.print(table)
    if result.findings:
        table = Table(title="skipped and warnings", title_justify="left")
        for col in ("severity", "code", "where", "reason"):
            table.add_column(col, overflow="fold")
        for f in result.findings:
            table.add_row(*(escape(c) for c in (f.severity.value, f.code, f.where, f.message)))
        console.print(table)
    n_dup = sum(1 for s in result.stacks if s.duplicate_of)
    intents: dict[str, int] = {}
    for s in result.stacks:
        intents[s.intent or "unclassified"] = intents.get(s.intent or "unclassified", 0) + 1
    by_intent = ", ".join(f"{n} {name}" for name, n in intents.items())
    console.print(
        f"{len(result.materials)} material(s), {len(result.stacks)} stack(s) ({n_dup} duplicate"
        + (f"; {by_intent}" if by_intent else "") + (f"; {len(kept)} that process will not make" if kept else "")
        + "), "
        f"{sum(len(s.maps) for s in result.stacks)} map(s), {len(result.findings)} finding(s)"
    )
