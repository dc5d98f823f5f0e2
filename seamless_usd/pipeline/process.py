"""The main job: scan, train and sample each unique stack, write tiles, author the edits, report.

``process_paths`` and ``process_stage`` share one core: every input is scanned first; a
:class:`Run` then hands each unique stack (identical stacks are processed once and reused) to an
executor (in this process, worker processes or Dask), and the stage/document edits happen in this
process afterwards, one source at a time. One failing stack or source is reported and the rest go on.
"""
from __future__ import annotations

import itertools
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from seamless_usd.version import __version__
from seamless_usd.discover import open_stage, scan_mtlx, scan_stage
from seamless_usd.discover.select import BLOCKING_SKIPS, blocked_stacks, select_stacks, unread_materials
from seamless_usd.discover.select import left_alone_stacks as _left_alone
from seamless_usd.textures import ScanResult, TextureStack, describe_selection
from seamless_usd.errors import InputError, SeamlessUsdError, UsageError
from seamless_usd.fileio import folder_problem
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref
from seamless_usd.pipeline.cache import JobIndex, StackCache, job_fingerprint
from seamless_usd.pipeline.executors import Executor, InProcessExecutor, make_executor
from seamless_usd.pipeline.options import Options, ProgressEvent, check_device
from seamless_usd.pipeline.inputs import expand_inputs
from seamless_usd.pipeline.planned import planned_result, wrap_only_result
from seamless_usd.pipeline.outcome import StackOutcome
from seamless_usd.pipeline.stackjob import JobSettings, StackJob, run_stack
from seamless_usd.report.model import MapReport, Report, StackReport, StackStatus

__all__ = ["process_paths", "process_stage", "select_stacks", "blocked_stacks", "BLOCKING_SKIPS"]

USD_SUFFIXES = {".usd", ".usda", ".usdc", ".usdz"}
TILING, ALREADY_TILEABLE = "tiling", "already-tileable"  # discover.intent.Intent values
MTLX_SUFFIXES = {".mtlx"}


def _authoring():
    # Imported here so that the schema plugin is registered before any stage is opened.
    from seamless_usd import authoring

    return authoring


@dataclass
class Run:
    """State of one process run across sources."""

    options: Options
    executor: Executor
    report: Report = field(default_factory=Report)
    outcomes: dict[str, StackOutcome | Exception] = field(default_factory=dict)  # content key -> result
    blocked: dict[tuple[str, str], str] = field(default_factory=dict)  # (source, stack id) -> why it is left alone
    left_alone: set[tuple[str, str]] = field(default_factory=set)  # (source, stack id) not meant to tile, not forced
    placed: dict[tuple[str, Path], StackOutcome | Exception] = field(default_factory=dict)  # (key, dir) -> tiles there
    claimed: dict[str, tuple[str, str]] = field(default_factory=dict)  # content key -> first (source, stack id)
    total: int = 0
    index: int = 0
    _settings: JobSettings | None = field(default=None, init=False, repr=False)

    @property
    def settings(self) -> JobSettings:
        """The jobs' settings, fixed once for the run (the seeds a job trains follow its executor's threads, and a
        stack placed later for another output folder must find the same cache entry)."""
        if self._settings is None:
            self._settings = JobSettings.from_options(self.options, self.executor.threads_per_job)
        return self._settings

    def emit(self, kind: str, stack_id: str, detail=None) -> None:
        if self.options.progress is not None:
            self.options.progress(ProgressEvent(kind, stack_id, self.index, self.total, detail))


def _output_dir(options: Options, source: Path | None) -> Path:
    if options.output_dir is not None:
        return Path(options.output_dir).resolve()
    if source is None:
        raise UsageError("the stage has no file on disk (anonymous root layer): give an output directory")
    return source.resolve().parent / "tileable"


def _run_jobs(run: Run, sources: Sequence[tuple[str, list[TextureStack], Path]]) -> None:
    """Train and sample every unique stack once (identical stacks share the result)."""
    jobs: list[StackJob] = []
    seen: set[str] = set()
    settings = run.settings
    for label, stacks, out_dir in sources:
        for stack in stacks:
            if ((label, stack.id) in run.blocked or (label, stack.id) in run.left_alone
                    or stack.content_key in seen or stack.content_key in run.outcomes):
                continue
            seen.add(stack.content_key)
            jobs.append(StackJob(stack=stack, settings=settings, output_dir=out_dir))
    run.total = len(jobs)

    def progress(job: StackJob, kind: str, detail) -> None:
        run.emit(kind, job.stack.id, detail)

    # Warm jobs first, in this process, from the cache: an executor (a Dask cluster, worker
    # processes) is started only for the jobs that need work.
    index = JobIndex(run.options.cache_dir)
    fingerprints: dict[int, str | None] = {}
    warm, cold = [], []
    for job in jobs:
        try:
            fingerprints[id(job)] = job_fingerprint(job.stack, job.settings)
        except OSError:  # unreadable file: the job reports it
            fingerprints[id(job)] = None
        (warm if fingerprints[id(job)] and index.finished(fingerprints[id(job)]) else cold).append(job)
    runs = [InProcessExecutor().run(warm, progress)]
    if cold:
        runs.append(run.executor.run(cold, progress))
    for job, result in itertools.chain(*runs):
        run.outcomes[job.stack.content_key] = result
        if isinstance(result, StackOutcome) and fingerprints[id(job)]:
            index.record(fingerprints[id(job)], result.model_hash)
        run.emit("stack-done", job.stack.id, result)
        run.index += 1


def _reports_for(run: Run, stacks: list[TextureStack], source_label: str, out_dir: Path):
    """Turn the outcomes of ``stacks`` into stack reports; return authoring inputs for the done
    ones, and ``(report, stack)`` for each stack whose result is handed to authoring."""
    authoring = _authoring()
    results = []
    handed: list[tuple[StackReport, TextureStack]] = []
    dry = run.options.mode == authoring.WriteMode.DRY_RUN
    first_of: dict[str, str] = {}
    for stack in stacks:
        report = StackReport(id=stack.id, material=stack.material, source=source_label, status=StackStatus.FAILED,
                             intent=stack.intent, intent_reason=stack.intent_reason,
                             variant=describe_selection(stack.selection))
        where = prim_ref(stack.material.strip("<>"))
        before = len(results)
        if (source_label, stack.id) in run.left_alone:
            report.status = StackStatus.LEFT_ALONE
            report.maps = [MapReport.for_map(m) for m in stack.maps]
            report.message = (f"left alone ({stack.intent}): {stack.intent_reason}; "
                              "--force or --force-materials to process it anyway")
            if stack.intent == ALREADY_TILEABLE:
                report.message = f"already tileable, kept as is (wrap set to repeat): {stack.intent_reason}"
                results.append(wrap_only_result(stack))
            run.report.findings.append(Finding(Severity.SKIPPED, stack.intent, where, report.message, stack.material))
        elif (source_label, stack.id) in run.blocked:
            report.message = run.blocked[(source_label, stack.id)]
            run.report.findings.append(Finding(Severity.ERROR, "stack-blocked", where, report.message, stack.material))
        elif dry:
            report.status = StackStatus.PLANNED
            planned = planned_result(stack, out_dir, run.options)
            report.maps = [MapReport.for_map(mr.map, mr.output_path) for mr in planned.maps]
            report.uv_scale = planned.uv_scale
            report.duplicate_of = first_of.get(stack.content_key) or stack.duplicate_of
            if report.duplicate_of is None:
                run.report.plan.append(
                    f"train and sample {where} ({len(stack.maps)} maps: "
                    f"{', '.join(Path(m.asset).name for m in stack.maps)}) and write tiles to {out_dir} "
                    f"(UV scale {planned.uv_scale[0]:g} x {planned.uv_scale[1]:g} if the whole texture passes Q; "
                    "a smaller crop, or a cut of whole lattice periods on a repeating texture, gives a larger scale)"
                )
            results.append(planned)
        else:
            outcome = run.outcomes.get(stack.content_key)
            if isinstance(outcome, StackOutcome) and outcome.output_dir != out_dir:
                outcome = _place(run, stack, out_dir)
            if isinstance(outcome, StackOutcome):
                first = run.claimed.setdefault(stack.content_key, (source_label, stack.id))
                reused = first != (source_label, stack.id)
                outcome.fill_report(report, stack, reused=reused)
                if not reused:
                    run.report.findings += list(outcome.findings)
                if reused:
                    report.duplicate_of = first[1] if first[0] == source_label else f"{first[1]} in {first[0]}"
                    report.message = f"identical to stack {report.duplicate_of}: its result is reused"
                results.append(outcome.stack_result(stack))
            else:
                message = _error_message(outcome)
                report.message = message
                run.report.findings.append(Finding(Severity.ERROR, "stack-failed", where, message, stack.material))
        if len(results) > before:
            handed.append((report, stack))
        if stack.intent and stack.intent != TILING and report.status is not StackStatus.LEFT_ALONE:
            report.message = (report.message + "; " if report.message else "") + f"processed although {stack.intent} (forced)"
        first_of.setdefault(stack.content_key, stack.id)
        run.report.stacks.append(report)
    return results, handed


def _unread(run: Run, scan: ScanResult, source_label: str) -> None:
    """A failed row for each selected material none of whose textures could be read: it has no stack, and is
    not left out of the table, the counts or the exit code."""
    for material, skipped in unread_materials(scan, run.options.materials).items():
        slug = material.strip("<>").strip("/").replace("/", "_") or "material"
        files = ", ".join(f"{f.where.split(' ')[-1]} ({f.code})" for f in skipped)
        message = f"nothing processed: no texture of it can be read: {files}; fix or restore them and run again"
        run.report.stacks.append(StackReport(id=f"{slug}-unread", material=material, source=source_label,
                                             status=StackStatus.FAILED, message=message))
        run.report.findings.append(Finding(Severity.ERROR, "stack-unread", prim_ref(material.strip("<>")), message,
                                           material))


def _check_written(run: Run, handed, edit, failure: str | None = None) -> None:
    """The report agrees with the disk: a stack whose edits were not written is failed."""
    unwritten = edit.unwritten_nodes() if edit is not None else {}
    for report, stack in handed:
        if failure is not None:
            why = failure
        else:
            missing = [(prim_ref(m.node.strip("<>")), unwritten[prim_ref(m.node.strip("<>"))])
                       for m in stack.maps if prim_ref(m.node.strip("<>")) in unwritten]
            if not missing:
                continue
            why = "; ".join(f"{node}: {reason}" for node, reason in missing)
        report.status = StackStatus.FAILED
        report.message = f"tiles written but the stage edits were not: {why}"


def _place(run: Run, stack: TextureStack, out_dir: Path) -> StackOutcome | Exception:
    """Tiles of an identical stack written for another output folder: write them here too.

    The model and tiles come from the cache (no training), so each source's layer refers to
    tiles in its own output folder and stays self-contained.
    """
    key = (stack.content_key, out_dir)
    if key not in run.placed:
        job = StackJob(stack=stack, settings=run.settings, output_dir=out_dir)
        try:
            run.placed[key] = run_stack(job, None)
        except Exception as exc:  # noqa: BLE001 - reported per stack
            run.placed[key] = exc
    return run.placed[key]


def _error_message(exc: Exception | None) -> str:
    if exc is None:
        return "not processed"
    if isinstance(exc, SeamlessUsdError):
        return str(exc)
    last = traceback.format_exception_only(type(exc), exc)[-1].strip()
    return f"internal error: {last} (please report it)"


def _record_authoring(run: Run, result) -> None:
    run.report.layers_written += [str(p) for p in result.layers_written]
    run.report.backups += [str(p) for p in result.backups]
    run.report.findings += list(result.findings)
    run.report.plan += list(getattr(result, "plan", []) or [])


@dataclass
class _Source:
    path: Path
    kind: str  # "usd" or "mtlx"
    scan: ScanResult
    stacks: list[TextureStack]


def _scan_source(path: Path, patterns: Sequence[str], triage_dir: Path | None = None) -> _Source:
    """Open and scan one input; InputError when it cannot be read. ``triage_dir`` keeps the triage's pixel
    figures between runs."""
    if not path.exists():
        raise InputError(f"{asset_ref(path)} does not exist")
    suffix = path.suffix.lower()
    if suffix in MTLX_SUFFIXES:
        scan, kind = scan_mtlx(path, triage_dir), "mtlx"
    elif suffix in USD_SUFFIXES:
        _authoring()  # registers the schema plugin before the stage is opened
        stage = open_stage(path)
        scan, kind = scan_stage(stage, triage_dir), "usd"
    else:
        raise InputError(f"{asset_ref(path)} is neither a USD stage (.usd/.usda/.usdc/.usdz) nor a .mtlx document")
    return _Source(path, kind, scan, select_stacks(scan, patterns))


def _author_source(run: Run, src: _Source) -> None:
    authoring = _authoring()
    run.report.findings += src.scan.findings
    run.report.variants += [v.to_dict() for v in src.scan.variants]
    results, handed = _reports_for(run, src.stacks, str(src.path), _output_dir(run.options, src.path))
    if not results and run.options.mode != authoring.WriteMode.DRY_RUN:
        return
    plan = run.options.plan_mode or authoring.WriteMode.NEW_LAYER
    try:
        if src.kind == "mtlx":
            edit = authoring.author_mtlx(src.path, results, mode=run.options.mode, plan_mode=plan)
        else:
            edit = authoring.author_usd(
                src.path, results, mode=run.options.mode, output_layer=run.options.output_layer, plan_mode=plan
            )
    except Exception as exc:  # noqa: BLE001 - one source's edits failing must not stop the others
        # The tiles are written; the edits of this source are not. Say so; the other sources go on.
        if not isinstance(exc, (SeamlessUsdError, OSError)):
            exc = _error_message(exc)
        run.report.findings.append(
            Finding(Severity.ERROR, "authoring-failed", asset_ref(src.path), f"the edits were not written: {exc}")
        )
        if run.options.mode != authoring.WriteMode.DRY_RUN:
            _check_written(run, handed, None, failure=str(exc))
        return
    _record_authoring(run, edit)
    if run.options.mode != authoring.WriteMode.DRY_RUN:
        _check_written(run, handed, edit)


def _finish(run: Run, started: float) -> Report:
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
            write_library_html(report, html_path)
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


def _new_run(options: Options) -> Run:
    authoring = _authoring()
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
    if options.output_dir is not None and options.mode is not authoring.WriteMode.DRY_RUN:
        problem = folder_problem(options.output_dir)
        if problem:
            raise UsageError(f"--output-dir: {problem}")
    if options.mode is None:
        options = options.with_(mode=authoring.WriteMode.NEW_LAYER)
    return Run(options=options, executor=make_executor(options.scheduler, options.jobs))


def _triage_dir(options: Options) -> Path:
    """Where the triage's pixel figures are kept between runs: beside the trained stacks."""
    return StackCache(options.cache_dir).root / "triage"


def process_paths(paths: Sequence[str | Path], options: Options | None = None) -> Report:
    """Process stages and MaterialX documents (files, folders, glob patterns); the report owns the exit code.

    Every input is scanned first (so progress knows the total), then stacks are processed one
    after another. An unreadable input is reported (exit code 2) and the other inputs go on.
    """
    started = time.perf_counter()
    run = _new_run(options or Options())
    sources = []
    inputs = expand_inputs(paths)
    if run.options.output_layer is not None and sum(p.suffix.lower() in USD_SUFFIXES for p in inputs) > 1:
        raise UsageError("-o/--output-layer names one layer, but several USD inputs were given; leave it out "
                         "(each stage then gets its own <name>.seamless.usda)")
    for path in inputs:
        run.report.sources.append(str(path))
        try:
            src = _scan_source(path, run.options.materials, _triage_dir(run.options))
            run.blocked.update(blocked_stacks(src.scan, src.stacks, str(src.path)))
            _unread(run, src.scan, str(src.path))
            run.left_alone.update(_left_alone(src.stacks, str(src.path), run.options.force, run.options.force_materials))
            sources.append(src)
        except InputError as exc:
            run.report.unreadable.append(str(path))
            run.report.findings.append(Finding(Severity.ERROR, "unreadable-input", asset_ref(path), str(exc)))
    if run.options.mode != _authoring().WriteMode.DRY_RUN:
        _run_jobs(run, [(str(src.path), src.stacks, _output_dir(run.options, src.path)) for src in sources])
    for src in sources:
        _author_source(run, src)
    return _finish(run, started)


def process_stage(stage, options: Options | None = None) -> Report:
    """Process an open stage in memory, as DCC export hooks receive it.

    Tiles are written to ``options.output_dir`` (default ``<root layer dir>/tileable``) and the
    edits are authored into the stage's current edit target; the stage is not saved.
    """
    started = time.perf_counter()
    run = _new_run(options or Options())
    authoring = _authoring()
    root = stage.GetRootLayer()
    source = None if root.anonymous else Path(root.realPath)
    label = root.identifier
    run.report.sources.append(label)
    scan = scan_stage(stage, _triage_dir(run.options))
    run.report.findings += scan.findings
    run.report.variants += [v.to_dict() for v in scan.variants]
    stacks = select_stacks(scan, run.options.materials)
    # The open stage is authored as it is composed: stacks of other variant selections are named, not processed
    from seamless_usd.authoring.usdedits import variant_not_composed

    run.report.findings += [variant_not_composed(s) for s in stacks if s.selection]
    stacks = [s for s in stacks if not s.selection]
    run.blocked.update(blocked_stacks(scan, stacks, label))
    _unread(run, scan, label)
    run.left_alone.update(_left_alone(stacks, label, run.options.force, run.options.force_materials))
    out_dir = _output_dir(run.options, source)
    if run.options.mode != authoring.WriteMode.DRY_RUN:
        _run_jobs(run, [(label, stacks, out_dir)])
    results, handed = _reports_for(run, stacks, label, out_dir)
    if results and run.options.mode != authoring.WriteMode.DRY_RUN:
        edit = authoring.author_usd_stage(stage, results)
        _record_authoring(run, edit)
        _check_written(run, handed, edit)
    return _finish(run, started)
