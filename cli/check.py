"""Judge whether textures tile: the verdict of `process` as a command, with no training.

Lists each texture stack meant to tile in USD stages, MaterialX documents and folders, and each
picture named, with its verdict: passed (no seam at the wrap, the centre lines or inside, and, for a
tile this tool wrote, faithful to its recorded source) or not, and where each seam is. A texture
with no separate source is judged against itself: its own lines are the reference, and a seam is a
line unlike them. ``--json`` prints the result following ``schemas/check.schema.json``. Exit codes:
0 everything tiles; 1 something does not (or a texture could not be read); 2 unreadable input.
"""
from __future__ import annotations

import argparse
import json
import sys

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from seamless_usd.pipeline.check import CheckReport, check_paths
from seamless_usd.verdict import Verdict

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", nargs="+", metavar="PATH",
                        help="USD stage, .mtlx document, folder, or picture (.png, .jpg, .exr, .tif, ...)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON (schemas/check.schema.json)")


def _where(item) -> str:
    if item.error:
        return item.error
    v = Verdict.from_dict(item.verdict)
    return "; ".join(v.reasons()) or ("seamless and faithful" if v.reference == "source" else
                                      "seamless (judged against itself)")


def render(report: CheckReport, console: Console) -> None:
    table = Table(title="seamless-usd check", show_lines=False)
    table.add_column("texture or stack", overflow="fold", min_width=20)
    table.add_column("verdict", no_wrap=True)
    table.add_column("against", no_wrap=True)
    table.add_column("where", overflow="fold")
    for item in report.items:
        state = "[green]passed[/]" if item.passed else "[red]error[/]" if item.error else "[yellow]not passed[/]"
        table.add_row(escape(item.name), state, item.verdict.get("reference", "-"), escape(_where(item)))
    console.print(table)
    for why in report.unreadable:
        console.print(f"[red]unreadable[/] {escape(why)}", soft_wrap=True)
    console.print(f"{sum(i.passed for i in report.items)} of {len(report.items)} passed")


def run(args: argparse.Namespace) -> int:
    err = Console(stderr=True)
    report = check_paths(args.paths, progress=lambda name: err.print(f"checking {escape(name)}", highlight=False)
                         if err.is_terminal else None)
    if args.json:
        json.dump(report.to_dict(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        width = None if sys.stdout.isatty() else 160
        render(report, Console(file=sys.stdout, width=width, soft_wrap=False))
    return report.exit_code
