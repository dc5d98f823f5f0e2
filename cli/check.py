"""Judge whether textures tile: the verdict of `process` as a command, with no training.

Lists each texture stack meant to tile in USD stages, MaterialX documents and folders, and each
picture named, with its verdict: passed (no seam at the wrap, the centre lines or inside, and, for a
tile this tool wrote, faithful to its recorded source) or not, and where each seam is. A texture
with no separate source is judged against itself: its own lines are the reference, and a seam is a
line unlike them. ``--json`` prints the result following ``schemas/check.schema.json``; ``--report``
writes a contact sheet (each picture repeated 2 x 2 with its seams drawn in red). A progress bar runs on a
terminal. Exit codes: 0 everything tiles; 1 something does not (a picture or texture that cannot be read
included); 2 a path that does not exist, a folder with nothing to judge, or a stage or document that cannot be
opened.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table

from seamless_usd.errors import InputError, UsageError
from seamless_usd.pipeline.check import CheckReport, check_paths

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("paths", nargs="+", metavar="PATH",
                        help="USD stage, .mtlx document, folder, or picture (.png, .jpg, .exr, .tif, ...)")
    parser.add_argument("--json", action="store_true", help="print the result as JSON (schemas/check.schema.json)")
    parser.add_argument("--report", type=Path, metavar="HTML",
                        help="write a contact sheet: each picture repeated 2 x 2 with its seams drawn in red")
    parser.add_argument("--jobs", type=int, default=0, metavar="N",
                        help="worker processes judging pictures (default 0: one per core, at most 8; 1: in this "
                             "process)")


def render(report: CheckReport, console: Console) -> None:
    table = Table(title="seamless-usd check", show_lines=False)
    table.add_column("texture or stack", overflow="fold", min_width=20)
    table.add_column("verdict", no_wrap=True)
    table.add_column("against", no_wrap=True)
    table.add_column("where", overflow="fold")
    scenes = {i.source for i in report.items if i.source != i.name}
    for item in report.items:
        state = "[green]passed[/]" if item.passed else "[red]error[/]" if item.error else "[yellow]not passed[/]"
        name = f"{item.name} in {item.source}" if len(scenes) > 1 and item.source != item.name else item.name
        table.add_row(escape(name), state, item.verdict.get("reference", "-"), escape(item.words()))
    if report.items:  # nothing judged (a path that is not there): the lines below say why, without an empty table
        console.print(table)
    for why in report.unreadable:
        console.print(f"[red]unreadable[/] {escape(why)}", soft_wrap=True)
    if report.not_judged:
        shown = ", ".join(f"@{p}@" for p in report.not_judged[:3]) + (", ..." if len(report.not_judged) > 3 else "")
        n = len(report.not_judged)
        console.print(f"not judged: {n} picture{'s' if n != 1 else ''} in folders of stages or documents that none of "
                      f"them uses ({escape(shown)}); name them, or a folder of pictures, to judge them", soft_wrap=True)
    if report.items or not report.unreadable:
        unread, counts = len(report.unreadable), report.counts()
        console.print(f"{counts['passed']} of {len(report.items)} passed"
                      + (f", {counts['errors']} could not be judged" if counts["errors"] else "")
                      + (f"; {unread} input{'s' if unread != 1 else ''} could not be read" if unread else ""))


def _checked(args: argparse.Namespace, err: Console) -> CheckReport:
    """check_paths, with a progress bar over the inputs on a terminal."""
    jobs = args.jobs if args.jobs > 0 else min(8, os.cpu_count() or 1)
    if not err.is_terminal:
        return check_paths(args.paths, jobs=jobs)
    with Progress(TextColumn("checking"), BarColumn(), TextColumn("{task.fields[count]}"),
                  TimeElapsedColumn(), TimeRemainingColumn(), TextColumn("{task.description}"),
                  console=err, transient=True) as bar:
        task = bar.add_task("", total=None, count="")  # the count shows once the inputs are known

        def step(name: str, done: int, total: int) -> None:
            bar.update(task, completed=done, total=total, count=f"{done}/{total}",
                       description=escape(Path(name).name) if name else "")

        return check_paths(args.paths, progress=step, jobs=jobs)


def run(args: argparse.Namespace) -> int:
    err = Console(stderr=True)
    if args.jobs < 0:
        raise UsageError(f"--jobs {args.jobs}: give a number of worker processes, or 0 for one per core")
    sheet = None
    if args.report is not None:
        from seamless_usd.report.target import report_target

        try:  # refused before any work when it would replace a file of the user's (a picture, a stage)
            sheet = report_target(args.report)
        except InputError as exc:
            raise UsageError(f"--report: {exc}") from None
    report = _checked(args, err)
    if report.interrupted:  # Ctrl-C or SIGTERM: what was judged by then is reported, exit 130
        err.print(f"seamless-usd: interrupted; {len(report.items)} judged by then", highlight=False)
    if sheet is not None:
        from seamless_usd.report.contact import write_contact_sheet

        written = write_contact_sheet([item.card() for item in report.items], sheet, unreadable=report.unreadable,
                                      not_judged=report.not_judged, exit_code=report.exit_code)
        err.print(f"contact sheet: {escape(str(written))}", highlight=False)
    if args.json:
        json.dump(report.to_dict(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        width = None if sys.stdout.isatty() else 160
        render(report, Console(file=sys.stdout, width=width, soft_wrap=False))
    return report.exit_code
