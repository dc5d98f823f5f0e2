"""Make the textures of a stage or MaterialX document tileable and write them back.

Trains a SeamlessGAN per texture stack, samples a tileable stack, writes the maps beside the
stage (tileable/) and, by default, a new layer <scene>.seamless.usda that sublayers the
original and holds the edits. A stack *passed* when its written tiles have no seam (at the wrap,
the centre lines or inside, in any map, judged against the source's own lines) and every fidelity
figure is inside the tolerance its source sets. Exit codes: 0 all stacks passed; 1 some stack failed
or did not pass (the rest were written); 2 usage error or unreadable input; 3 internal error (a log
file is named); 130 stopped by Ctrl-C or SIGTERM (the report says how far each stack got); 141 the
reader of its output went away.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, ProgressColumn, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text

from seamless_usd.api import Options, process_paths
from seamless_usd.authoring import WriteMode
from seamless_usd.errors import Interrupted
from seamless_usd.pipeline.options import MAX_SEED, REFINE_MODES, TILE_SIZES, ProgressEvent
from seamless_usd.report import Report, StackStatus

__all__ = ["add_arguments", "run"]


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("paths", nargs="+", metavar="PATH",
                   help="USD stages (.usd/.usda/.usdc/.usdz), .mtlx documents, folders (walked) or glob patterns")
    p.add_argument("--preset", default="default",
                   help="synthesis preset: default (CPU), long (4x the default's training, for structured stacks), "
                        "draft (minutes; often not faithful), paper (GPU), tiny (seconds: plumbing checks, "
                        "not for tiles to ship) (default: %(default)s)")
    p.add_argument("--materials", action="append", default=[], metavar="GLOB",
                   help="only materials whose path or name matches (repeatable)")
    p.add_argument("--dry-run", action="store_true",
                   help="show what would be done, write no tile, layer or document (the --report asked for is "
                        "written; with --in-place: the in-place edits are shown)")
    p.add_argument("--in-place", action="store_true", help="edit the source layers (keeps .bak copies)")
    p.add_argument("-o", "--output-layer", type=Path, help="override layer (or, for a .mtlx input, new MaterialX document) to write "
                   "(default <scene>.seamless.usda, <doc>.seamless.mtlx)")
    p.add_argument("--output-dir", type=Path, help="folder for tileable maps (default <stage dir>/tileable)")
    p.add_argument("--device", help="cpu, cuda, cuda:N (default: CUDA when present)")
    p.add_argument("--seed", type=_seed, default=0, help="random seed, 0 to 2**32 - 1 (default: %(default)s)")
    p.add_argument("--max-size", type=int, help="working-resolution cap in pixels (longest side); default native")
    p.add_argument("--iterations", type=_positive, help="override the preset's training iterations")
    p.add_argument("--seeds", type=_positive,
                   help="seeds trained, the tile whose fidelity figures are best kept (default: the preset's "
                        "that run side by side on a job's cores: one a job with --jobs 2 on two cores)")
    p.add_argument("--max-pixels", type=_positive, default=1 << 28,
                   help="refuse images whose header claims more pixels, before decoding (default: %(default)s)")
    p.add_argument("--cache-dir", type=Path, help="trained models and checkpoints (default: user cache dir)")
    p.add_argument("--jobs", "-j", type=int, help="stacks trained at once in local worker processes (default 1)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="run stacks on Dask: local:N (a local cluster of N workers) or tcp://host:8786 "
                        "(default: inprocess, or --jobs N local worker processes without Dask)")
    p.add_argument("--refine", choices=REFINE_MODES, default="on",
                   help="on: the SeamlessGAN tile refined to the source's resolution with real source texels, "
                        "or a tile cut from the source (whole periods of a texture that repeats, one window of "
                        "one that continues itself, else a quilt of large source blocks) when the verdict and "
                        "the figures prefer it; gan: the refined GAN tile only; off: the pure SeamlessGAN tile "
                        "(default: %(default)s)")
    p.add_argument("--tile-size", choices=TILE_SIZES, default="source",
                   help="source: the tile has the source's pixel size (same texture memory); "
                        "paper: the paper's 2c x 2c tile (default: %(default)s)")
    p.add_argument("--straighten", action="store_true",
                   help="a stack whose lines (planks, courses, tiles) run at an angle is turned until they run "
                        "along the axes, and that is tiled; the tile is written straight and the asset's UVs turn "
                        "it back (a UV transform before the UV scale), so the asset looks as before")
    p.add_argument("--write-straight", action="store_true",
                   help="straighten (implies --straighten) but author no UV turn: the pattern on the asset turns by "
                        "the angle the report and seamless:straightened record (normal maps' vectors turn with it)")
    p.add_argument("--force", action="store_true",
                   help="process every stack, also those classed uv-atlas, already-tileable or other")
    p.add_argument("--force-materials", action="append", default=[], metavar="GLOB",
                   help="process these materials whatever their tiling intent (repeatable)")
    p.add_argument("--report", type=Path, help="HTML report path (the JSON report is written beside it)")
    p.add_argument("--json", action="store_true", help="print the JSON report on stdout")


def _seed(text: str) -> int:
    """An argparse type: a seed torch and numpy both take (0 to 2**32 - 1)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"must be from 0 to {MAX_SEED}, got {value}")
    return value


def _positive(text: str) -> int:
    """An argparse type: an integer of at least 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def _options(args: argparse.Namespace, progress) -> Options:
    writing = WriteMode.IN_PLACE if args.in_place else WriteMode.NEW_LAYER
    return Options(
        preset=args.preset,
        materials=tuple(args.materials),
        mode=WriteMode.DRY_RUN if args.dry_run else writing,
        plan_mode=writing,
        output_layer=args.output_layer,
        output_dir=args.output_dir,
        device=args.device,
        seed=args.seed,
        report=args.report,
        cache_dir=args.cache_dir,
        max_size=args.max_size,
        max_pixels=args.max_pixels,
        iterations=args.iterations,
        seeds=args.seeds,
        jobs=args.jobs,
        scheduler=args.scheduler,
        refine=args.refine,
        tile_size=args.tile_size,
        straighten=args.straighten or args.write_straight,
        write_straight=args.write_straight,
        force=args.force,
        force_materials=tuple(args.force_materials),
        progress=progress,
    )


class _Count(ProgressColumn):
    """``done/total`` where a step has a total, nothing where it has none (a refinement: "0/None")."""

    def render(self, task) -> Text:
        return Text(f"{task.completed:.0f}/{task.total:.0f}" if task.total is not None else "")


class _ProgressView:
    """Rich progress bars: one for the stacks, one for each stack being made (two at once with ``--jobs 2``); where
    stderr is not a terminal (a farm's log, a file), a line as each stack starts and ends instead (a bar is drawn
    there only once, at the end)."""

    def __init__(self, console: Console):
        from seamless_usd.hooks.loglines import progress_logger

        self.progress = Progress(
            TextColumn("{task.description}"), BarColumn(), _Count(),
            TextColumn("{task.fields[rate]}"), TimeElapsedColumn(), TimeRemainingColumn(),
            console=console, transient=False, disable=not console.is_terminal,
        )
        self.lines = None if console.is_terminal else progress_logger(
            lambda line: console.print(escape(str(line)), highlight=False, soft_wrap=True))
        self.stacks = None
        self.pages = None  # the library report's pages, once they are written
        self.steps: dict[str, object] = {}  # stack id -> its bar

    def __enter__(self):
        self.progress.__enter__()
        return self

    def __exit__(self, *exc):
        return self.progress.__exit__(*exc)

    def __call__(self, event: ProgressEvent) -> None:
        if self.lines is not None:
            self.lines(event)
            return
        p = self.progress
        if event.kind == "report":  # the library report's pages, written after the stacks
            if self.pages is None:
                self.pages = p.add_task("report pages", total=event.total, rate="")
            p.update(self.pages, completed=event.index, total=event.total)
            return
        if self.stacks is None:
            self.stacks = p.add_task("stacks", total=event.total, rate="")
        step = self.steps.get(event.stack_id)
        if event.kind == "stack-start":
            if step is not None:
                p.remove_task(step)
            self.steps[event.stack_id] = p.add_task(f"  {event.stack_id[:40]}", total=None, rate="")
        elif event.kind == "train" and step is not None and event.detail is not None:
            d = event.detail
            p.update(step, total=d.total, completed=d.iteration, rate=f"{d.it_per_s:.1f} it/s")
        elif event.kind == "sample" and step is not None and event.detail is not None:
            d = event.detail
            p.update(step, total=d.planned, completed=d.index, rate=f"Q search, crop {_wh(d.candidate.crop_size)}")
        elif event.kind == "stage" and step is not None:
            p.update(step, total=None, rate=str(event.detail))
        elif event.kind == "refine" and step is not None and event.detail is not None:
            d = event.detail
            p.update(step, total=None, rate=f"refining at {d['tile'][1]}x{d['tile'][0]} ({d['seconds']:.1f}s)")
        elif event.kind == "stack-done":
            p.advance(self.stacks)
            if step is not None:  # the stack's own bar goes with it (a stack cut from its source has no steps)
                p.remove_task(self.steps.pop(event.stack_id))


def _wh(size) -> str:
    """An (h, w) size as people read sizes: width x height."""
    return f"{size[1]}x{size[0]}"


def _summary(report: Report, console: Console) -> None:
    if report.stacks:
        _stack_table(report, console)
    names = _file_names(report)
    for f in report.findings:
        text = f.message if f.where in f.message else f"{f.where}: {f.message}"
        # several inputs: a library's files share material paths (every </World/Looks/Wood>), so each line names its
        # file, unless it names it already
        of = names.get(f.source, "") if f.source else ""
        text += f" (in {of})" if of and f"@{f.source}@" not in text and f"@{of}@" not in text else ""
        console.print(f"[bold]{f.severity.value}[/]: {escape(text)}", highlight=False, soft_wrap=True)
    for layer in report.layers_written:  # paths and messages as they are: a "[v2]" in a folder name is no markup
        console.print(f"wrote {escape(str(layer))}", highlight=False, soft_wrap=True)
    if report.options.get("mode") == "dry-run":
        for line in report.plan:
            console.print(f"would {escape(line)}", highlight=False, soft_wrap=True)
    if report.stacks:  # last, where a long table or plan ends: what the run came to, in one line
        console.print(escape(_counts_line(report)), highlight=False, soft_wrap=True)


def _counts_line(report: Report) -> str:
    """``12 stacks: 7 passed, 3 not passed, 2 left alone`` (a dry run: how many are planned, and how many of those
    reuse another stack's tiles)."""
    counts = report.counts()
    planned = [s for s in report.stacks if s.status is StackStatus.PLANNED]
    reused = sum(1 for s in planned if s.duplicate_of)
    known_bad = sum(1 for s in planned if s.verdict.get("passed") is False)  # a dry run's exit 1: say why
    notes = [f"{reused} reusing another stack's tiles"] * bool(reused) + [
        f"{known_bad} known from the cache not to pass"] * bool(known_bad)
    parts = [f"{counts[status.value]} {status.value.replace('-', ' ')}"
             + (f" ({'; '.join(notes)})" if status is StackStatus.PLANNED and notes else "")
             for status in StackStatus if counts[status.value]]
    total = len(report.stacks)
    return f"{total} stack{'s' if total != 1 else ''}: {', '.join(parts)}"


def _file_names(report: Report) -> dict[str, str]:
    """Each input of a run of several, as the library report names it (its path under their shared folder); none
    for a run of one."""
    from seamless_usd.report.index import shown_names

    sources = [s for s in report.sources if s]
    return shown_names(sources) if len(sources) > 1 else {}


#: Below this many columns the table keeps the material, its status and why (a terminal of 80 columns cut the
#: reasons off the edge and split material paths mid-word).
WIDE_TABLE = 110


def _stack_table(report: Report, console: Console) -> None:
    wide = console.width >= WIDE_TABLE
    table = Table(title="seamless-usd process", show_lines=False)
    table.add_column("material", overflow="fold", min_width=16 if wide else 12, ratio=None if wide else 2)
    for col in ("status", "maps", "crop", "tile", "UV scale", "time") if wide else ("status",):
        table.add_column(col, no_wrap=True)
    table.add_column("why not passed", overflow="fold", min_width=20, ratio=None if wide else 3)
    names = _file_names(report)
    for s in report.stacks:
        style = {StackStatus.PASSED: "green", StackStatus.NOT_PASSED: "yellow", StackStatus.FAILED: "red"}.get(s.status, "")
        where = f" of {names[s.source]}" if s.source in names else ""  # several inputs
        cells = [
            str(len(s.maps)),
            _wh(s.crop_size) if s.crop_size and s.model_hash else "-",  # no GAN, no crop
            _wh(s.tile_size) if s.tile_size else "-",
            ", ".join(f"{v:.3g}" for v in s.uv_scale) if s.uv_scale else "-",
            "cached" if s.origin == "cache" else "-" if s.origin == "duplicate"  # a duplicate's work was its twin's
            else f"{sum(s.timings.values()):.0f}s" if s.timings else "-",
        ]
        table.add_row(
            escape(s.material + (f" in {s.variant}" if s.variant else "") + where),
            f"[{style}]{s.status.value}[/]" if style else s.status.value,
            *(cells if wide else []),
            escape(s.message) if s.status in (StackStatus.NOT_PASSED, StackStatus.FAILED)
            or (s.status is StackStatus.PLANNED and s.verdict.get("passed") is False) else "",  # known from the cache
        )
    console.print(table)


def run(args: argparse.Namespace) -> int:
    console = Console(stderr=True)
    if not console.is_terminal:
        console = Console(stderr=True, width=120)  # logs and CI: wide enough that prim paths stay whole
    try:
        with _ProgressView(console) as view:
            report = process_paths([Path(p) for p in args.paths], _options(args, view))
    except Interrupted as stop:  # what was done is said (and printed as JSON) before the run ends as interrupted
        _said(stop.report, console, args.json)
        raise
    _said(report, console, args.json)
    return report.exit_code


def _said(report, console: Console, as_json: bool) -> None:
    """The summary table, the report's path, and with ``--json`` the report on stdout."""
    _summary(report, console)
    if report.options.get("report_html"):
        console.print(f"report: {escape(str(report.options['report_html']))}", highlight=False, soft_wrap=True)
    if as_json:
        json.dump(report.to_dict(), sys.stdout, indent=2)
        sys.stdout.write("\n")
