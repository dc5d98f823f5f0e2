"""One run of ``process``: its state across sources (:class:`Run`), and the report's rows made from each stack's
outcome (:func:`stack_rows`): passed, not passed, failed, reused, left alone, blocked, planned, and the materials
none of whose textures can be read. The report and the disk agree: a stack whose edits were not written is failed
(:func:`check_written`)."""
from __future__ import annotations

import time
import traceback
from dataclasses import dataclass, field
from pathlib import Path

from seamless_usd.discover.select import set_aside_materials, unread_files, unread_materials
from seamless_usd.errors import SeamlessUsdError
from seamless_usd.authoring.types import node_key
from seamless_usd.findings import Finding, Severity, prim_ref
from seamless_usd.pipeline.executors import Executor
from seamless_usd.pipeline.options import Options, ProgressEvent
from seamless_usd.pipeline.outcome import StackOutcome, reused_message
from seamless_usd.pipeline.planned import cached_plan, elsewhere_words, plan_line, planned_result, wrap_only_result
from seamless_usd.pipeline.rerun import changed_words
from seamless_usd.pipeline.stackjob import JobSettings, StackJob, run_stack
from seamless_usd.report.model import MapReport, Report, StackReport, StackStatus
from seamless_usd.textures import ScanResult, TextureStack, describe_selection

__all__ = ["Run", "authoring_module", "stack_rows", "unread_rows", "set_aside_rows", "check_written", "record_authoring",
           "error_message"]

TILING, ALREADY_TILEABLE = "tiling", "already-tileable"  # discover.intent.Intent values


def authoring_module():
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
    blocked: dict[tuple[str, str], str] = field(default_factory=dict)  # (source, stack id) -> why it fails
    set_aside: dict[tuple[str, str], str] = field(default_factory=dict)  # (source, stack id) -> why it is left alone
    left_alone: set[tuple[str, str]] = field(default_factory=set)  # (source, stack id) not meant to tile, not forced
    placed: dict[tuple[str, Path], StackOutcome | Exception] = field(default_factory=dict)  # (key, dir) -> tiles there
    claimed: dict[str, tuple[str, str]] = field(default_factory=dict)  # content key -> first (source, stack id)
    planned_first: dict[tuple[str, Path], str] = field(default_factory=dict)  # dry run: (key, dir) -> first stack id
    shared: object | None = None  # in place: the layers the stages share (authoring.usdshared.SharedEdits)
    began: float = field(default_factory=time.time)  # when the run began (seconds since the epoch)
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


def stack_rows(run: Run, stacks: list[TextureStack], source_label: str, out_dir: Path):
    """Turn the outcomes of ``stacks`` into stack reports; return authoring inputs for the done
    ones, and ``(report, stack)`` for each stack whose result is handed to authoring."""
    authoring = authoring_module()
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
        elif (source_label, stack.id) in run.set_aside:
            report.status = StackStatus.LEFT_ALONE
            report.maps = [MapReport.for_map(m) for m in stack.maps]
            report.message = run.set_aside[(source_label, stack.id)]
            run.report.findings.append(Finding(Severity.SKIPPED, "stack-set-aside", where, report.message,
                                               stack.material))
        elif (source_label, stack.id) in run.blocked:
            report.message = run.blocked[(source_label, stack.id)]
            run.report.findings.append(Finding(Severity.ERROR, "stack-blocked", where, report.message, stack.material))
        elif dry and (cached := cached_plan(stack, out_dir, run.settings, run.options.cache_dir)) is not None \
                and cached.changed:  # tiles a TD changed since: the run leaves them and fails the stack
            report.maps = [MapReport.for_map(m) for m in stack.maps]
            report.message = changed_words(list(cached.changed))
            run.report.findings.append(Finding(Severity.ERROR, "stack-blocked", where, report.message, stack.material))
        elif dry:
            tiles_of = run.planned_first.setdefault((stack.content_key, out_dir), stack.id)
            duplicate_of = first_of.get(stack.content_key) or stack.duplicate_of
            if cached is not None and cached.outcome is not None:  # what the run will say, from its last result
                cached.outcome.fill_report(report, stack, reused=duplicate_of is not None)
                planned = cached.outcome.stack_result(stack)
            else:
                planned = planned_result(stack, out_dir, run.options, run.settings.tile_key(), tiles_of=tiles_of,
                                         cached=cached)
            report.status, report.duplicate_of = StackStatus.PLANNED, duplicate_of
            report.maps = report.maps or [MapReport.for_map(mr.map, mr.output_path) for mr in planned.maps]
            report.uv_scale = planned.uv_scale
            if cached is not None and cached.outcome is None:
                report.origin, report.message = "cache", "from the cache; judged again once written"
                if cached.verdict_elsewhere is not None:  # the verdict the run will give, known from another folder
                    report.verdict = cached.verdict_elsewhere
                    report.message += elsewhere_words(cached.verdict_elsewhere)
            elif cached is not None:
                outcome = cached.outcome
                said = (report.message if duplicate_of is not None else "passed" if outcome.passed
                        else f"not passed: {'; '.join(outcome.reasons())}")
                report.origin, report.message = "cache", f"from the cache: {said}"
            if duplicate_of is None:
                run.report.plan.append(plan_line(where, stack, out_dir, planned.uv_scale, cached))
            results.append(planned)
        elif run.report.interrupted:  # stopped by Ctrl-C while tiles were made: how far each stack got
            _interrupted_row(run, report, stack, source_label, out_dir)
        else:
            outcome = run.outcomes.get(stack.content_key)
            try:
                if isinstance(outcome, StackOutcome) and outcome.output_dir != out_dir:
                    outcome = _place(run, stack, out_dir)
                if isinstance(outcome, StackOutcome):
                    _outcome_row(run, report, stack, outcome, source_label, results)
            except Exception as exc:  # noqa: BLE001 - this stack fails, named; the batch goes on
                outcome, report.status = exc, StackStatus.FAILED
            if not isinstance(outcome, StackOutcome):
                message = error_message(outcome)
                report.message = message
                run.report.findings.append(Finding(Severity.ERROR, "stack-failed", where, message, stack.material))
        if len(results) > before:
            handed.append((report, stack))
        if stack.intent and stack.intent != TILING and report.status is not StackStatus.LEFT_ALONE:
            report.message = (report.message + "; " if report.message else "") + f"processed although {stack.intent} (forced)"
        first_of.setdefault(stack.content_key, stack.id)
        run.report.stacks.append(report)
    return results, handed


def _outcome_row(run: Run, report: StackReport, stack: TextureStack, outcome: StackOutcome, source_label: str,
                 results: list) -> None:
    """``report`` filled from ``outcome`` (this stack's, or an identical one's it reuses), and its authoring input
    added to ``results``."""
    first = run.claimed.setdefault(stack.content_key, (source_label, stack.id))
    reused = first != (source_label, stack.id)
    outcome.fill_report(report, stack, reused=reused)
    if not reused:
        run.report.findings += list(outcome.findings)
    if reused:
        report.duplicate_of = first[1] if first[0] == source_label else f"{first[1]} in {first[0]}"
        report.message = reused_message(report.duplicate_of, outcome)
    results.append(outcome.stack_result(stack))


#: What a stack's row says when the run was stopped before its stage edits.
INTERRUPTED_MADE = ("interrupted before the stage was edited: its tiles are written and cached; run again to edit "
                    "the stage (nothing is made again)")
INTERRUPTED_NOT_MADE = "interrupted before its tiles were made; run again (what was finished comes from the cache)"
INTERRUPTED_UNJUDGED = ("interrupted after {files} {was} written, before {judged} judged{rest}; run again to judge "
                        "its tiles and edit the stage (they come from the cache)")


def _interrupted_row(run: Run, report: StackReport, stack: TextureStack, source_label: str, out_dir: Path) -> None:
    """``report`` of a stack in a run stopped by Ctrl-C: failed, as its stage was not edited, with its tiles' figures
    where they were made into ``out_dir`` (another folder's copy is not placed: nothing more is done)."""
    outcome = run.outcomes.get(stack.content_key)
    if isinstance(outcome, StackOutcome) and outcome.output_dir == out_dir:
        _outcome_row(run, report, stack, outcome, source_label, [])
        report.message = f"{INTERRUPTED_MADE}; its tiles {'passed' if outcome.passed else 'did not pass'}"
    elif isinstance(outcome, Exception):  # it failed before the run was stopped, as it would have anyway
        report.message = error_message(outcome)
        run.report.findings.append(Finding(Severity.ERROR, "stack-failed", prim_ref(stack.material.strip("<>")),
                                           report.message, stack.material))
    else:
        # the files the job writes, by name: those this run wrote
        planned = planned_result(stack, out_dir, run.options, run.settings.tile_key())
        written = [mr.output_path for mr in planned.maps if _written_since(mr.output_path, run.began)]
        report.maps = [MapReport.for_map(mr.map, mr.output_path) for mr in planned.maps if mr.output_path in written]
        left = len(planned.maps) - len(written)
        report.message = INTERRUPTED_UNJUDGED.format(
            files=", ".join(Path(p).name for p in written), was="was" if len(written) == 1 else "were",
            judged="it was" if len(written) == 1 else "they were",
            rest=f" ({left} of its {len(planned.maps)} maps not written)" if left else "") if written \
            else INTERRUPTED_NOT_MADE
    report.status = StackStatus.FAILED


def _written_since(path, began: float) -> bool:
    """Whether the file at ``path`` was written at or after ``began`` (seconds since the epoch): a tile an earlier
    run left there has the same name."""
    try:
        return Path(path).stat().st_mtime >= began - 1.0
    except OSError:
        return False


def unread_rows(run: Run, scan: ScanResult, source_label: str) -> None:
    """A failed row for each selected material none of whose textures could be read: it has no stack, and is
    not left out of the table, the counts or the exit code."""
    for material, skipped in unread_materials(scan, run.options.materials).items():
        slug = material.strip("<>").strip("/").replace("/", "_") or "material"
        files = unread_files(skipped)
        message = f"nothing processed: no texture of it can be read: {files}; fix or restore them and run again"
        run.report.stacks.append(StackReport(id=f"{slug}-unread", material=material, source=source_label,
                                             status=StackStatus.FAILED, message=message))
        run.report.findings.append(Finding(Severity.ERROR, "stack-unread", prim_ref(material.strip("<>")), message,
                                           material))


def set_aside_rows(run: Run, scan: ScanResult, source_label: str) -> None:
    """A left-alone row for each selected material every texture of which this tool does not make tileable (a UDIM
    set, a picture too small): it has no stack, and is not left out of the table or the counts."""
    for material, skipped in set_aside_materials(scan, run.options.materials).items():
        slug = material.strip("<>").strip("/").replace("/", "_") or "material"
        run.report.stacks.append(StackReport(
            id=f"{slug}-set-aside", material=material, source=source_label, status=StackStatus.LEFT_ALONE,
            message="left alone: " + "; ".join(f"{f.where.split(' ')[-1]}: {f.message.split(' (material ')[0]}"
                                               for f in skipped)))


def check_written(run: Run, handed, edit, failure: str | None = None) -> None:
    """The report agrees with the disk: a stack whose edits were not written is failed."""
    for report, stack in handed:
        unwritten = edit.unwritten_nodes(stack.material) if edit is not None else {}
        if failure is not None:
            why = failure
        else:
            missing = [(node_key(m), unwritten[node_key(m)]) for m in stack.maps if node_key(m) in unwritten]
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


def error_message(exc: Exception | None) -> str:
    if exc is None:
        return "not processed"
    if isinstance(exc, SeamlessUsdError):
        return str(exc)
    last = traceback.format_exception_only(type(exc), exc)[-1].strip()
    return f"internal error: {last} (please report it)"


def record_authoring(run: Run, result) -> None:
    run.report.layers_written += [str(p) for p in result.layers_written]
    run.report.backups += [str(p) for p in result.backups]
    run.report.findings += list(result.findings)
    run.report.plan += list(getattr(result, "plan", []) or [])
