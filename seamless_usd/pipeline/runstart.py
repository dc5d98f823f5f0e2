"""Starting and finishing a run of ``process``: the options checked before any work, where the triage's figures
are kept, and the reports written at the end."""
from __future__ import annotations

import time
from pathlib import Path

from seamless_usd.errors import InputError, UsageError
from seamless_usd.fileio import folder_problem
from seamless_usd.pipeline.cache import StackCache
from seamless_usd.pipeline.executors import make_executor
from seamless_usd.pipeline.options import Options, ProgressEvent, check_device
from seamless_usd.pipeline.rows import Run, authoring_module
from seamless_usd.report.model import Report
from seamless_usd.version import __version__

__all__ = ["as_options", "finish_run", "new_run", "triage_of"]


def finish_run(run: Run, started: float) -> Report:
    from seamless_usd.report.html import write_html, write_json
    from seamless_usd.report.index import write_library_html

    report = run.report
    report.tool_version = __version__
    report.options = run.options.summary()
    report.timings["total"] = time.perf_counter() - started
    if run.options.report is not None:
        html_path, json_path = _report_paths(run.options.report)
        html_path.parent.mkdir(parents=True, exist_ok=True)
        if len(report.sources) > 1:
            told = run.options.progress
            write_library_html(report, html_path, progress=None if told is None else
                               lambda done, total: told(ProgressEvent("report", "", done, total)))
        else:
            write_html(report, html_path)
        write_json(report, json_path)
        report.options["report_html"] = str(html_path)
        report.options["report_json"] = str(json_path)
    return report


def _report_paths(asked: Path) -> tuple[Path, Path]:
    """The HTML report's path and the JSON report's beside it (:func:`.report.target.report_target`); a
    :class:`UsageError` when either would replace a file that is not one of this tool's reports."""
    from seamless_usd.report.target import report_target

    try:
        html_path = report_target(asked)
        return html_path, report_target(html_path, ".json")
    except InputError as exc:
        raise UsageError(f"--report: {exc}") from None


def as_options(options) -> Options:
    """``options``, or the defaults for None; anything else is a usage error."""
    if options is None:
        return Options()
    if not isinstance(options, Options):
        raise UsageError(f"options must be seamless_usd.Options; got {type(options).__name__}")
    return options


def new_run(options: Options) -> Run:
    authoring = authoring_module()
    try:  # a mode it does not know is refused before any work (it failed once every tile was written)
        options = options.with_(mode=authoring.WriteMode(options.mode or authoring.WriteMode.NEW_LAYER),
                                plan_mode=None if options.plan_mode is None else authoring.WriteMode(options.plan_mode))
    except ValueError:
        modes = ", ".join(repr(m.value) for m in authoring.WriteMode)
        raise UsageError(f"Options.mode / plan_mode must be a WriteMode ({modes}); got {options.mode!r} / "
                         f"{options.plan_mode!r}") from None
    from seamless_usd.synthesis import get_preset

    try:
        get_preset(options.preset)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    from seamless_usd.discover.tokens import MIN_CROP

    if options.max_size is not None and options.max_size < MIN_CROP:
        raise UsageError(
            f"--max-size {options.max_size} is below the {MIN_CROP} px minimum crop; use {MIN_CROP} or more"
        )
    if options.device is not None:
        check_device(options.device)
    if options.report is not None:
        _report_paths(options.report)  # refused before any work when it would replace a file of the user's
    cache_root = StackCache(options.cache_dir).root
    problem = folder_problem(cache_root)  # a file, or a folder that can neither be written nor holds results
    if problem and not (cache_root.is_dir() and any(cache_root.iterdir())):
        raise UsageError(f"--cache-dir: {problem}; name a folder this run can write (a read-only cache is used only "
                         "when it holds results already)")
    if options.output_dir is not None and options.mode is not authoring.WriteMode.DRY_RUN:
        problem = folder_problem(options.output_dir)
        if problem:
            raise UsageError(f"--output-dir: {problem}")
    return Run(options=options, executor=make_executor(options.scheduler, options.jobs))


def triage_of(options: Options) -> tuple[Path, bool]:
    """Where the triage's pixel figures are kept between runs (beside the trained stacks), and whether this run
    adds to them (a dry run writes nothing)."""
    return StackCache(options.cache_dir).root / "triage", options.mode is not authoring_module().WriteMode.DRY_RUN
