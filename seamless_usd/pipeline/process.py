"""The main job: scan, train and sample each unique stack, write tiles, author the edits, report.

``process_paths`` and ``process_stage`` share one core: every input is scanned first; a
:class:`Run` then hands each unique stack (identical stacks are processed once and reused) to an
executor (in this process, worker processes or Dask), and the stage/document edits happen in this
process afterwards, one source at a time. One failing stack or source is reported and the rest go on.
"""
from __future__ import annotations

import itertools
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

from seamless_usd.discover import open_stage, scan_mtlx, scan_stage
from seamless_usd.discover.scan import not_a_scene
from seamless_usd.discover.select import (BLOCKING_SKIPS, blocked_stacks, from_recorded_sources, hand_set_stacks,
                                          instanced_stacks, matches_any, select_stacks, set_aside_stacks,
                                          unmatched_patterns)
from seamless_usd.discover.select import left_alone_stacks as _left_alone, shared_node_stacks
from seamless_usd.textures import ScanResult, TextureStack
from seamless_usd.errors import InputError, Interrupted, SeamlessUsdError, UsageError
from seamless_usd.fileio import folder_problem, marked_writable
from seamless_usd.findings import Finding, Severity, asset_ref, not_found_words
from seamless_usd.pipeline.cache import JobIndex, job_fingerprint
from seamless_usd.pipeline.executors import InProcessExecutor
from seamless_usd.pipeline.options import Options
from seamless_usd.pipeline.outputlayer import MTLX_SUFFIXES, check_output_layer, default_layer_problem
from seamless_usd.pipeline.inputs import expand_inputs
from seamless_usd.pipeline.outcome import StackOutcome
from seamless_usd.pipeline.rows import (Run, authoring_module, check_written, error_message, record_authoring,
                                        set_aside_rows, stack_rows, unread_rows)
from seamless_usd.pipeline.runstart import as_options, finish_run, new_run, triage_of
from seamless_usd.pipeline.stackjob import StackJob
from seamless_usd.report.model import Report

__all__ = ["process_paths", "process_stage", "select_stacks", "blocked_stacks", "BLOCKING_SKIPS"]

USD_SUFFIXES = {".usd", ".usda", ".usdc", ".usdz"}


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
            key = (label, stack.id)
            if (key in run.blocked or key in run.set_aside or key in run.left_alone
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
    if cold and hasattr(run.executor, "reach"):  # a remote scheduler that cannot be reached: before any tile is written
        run.executor.reach()
    runs = [InProcessExecutor().run(warm, progress)]
    if cold:
        runs.append(run.executor.run(cold, progress))
    try:
        for job, result in itertools.chain(*runs):
            run.outcomes[job.stack.content_key] = result
            if isinstance(result, StackOutcome) and fingerprints[id(job)]:
                index.record(fingerprints[id(job)], result.model_hash, result.cache_key)
            run.emit("stack-done", job.stack.id, result)
            run.index += 1
    finally:  # stopped (Ctrl-C) or done: an executor's workers end with it, not when it is collected
        for each in runs:
            each.close()


@dataclass
class _Source:
    path: Path
    kind: str  # "usd" or "mtlx"
    scan: ScanResult
    stacks: list[TextureStack]
    instanced: dict[tuple[str, str], str] = field(default_factory=dict)  # stacks inside instances, with why
    sites: dict[str, set] = field(default_factory=dict)  # USD: stack id -> where in-place edits of its nodes land


def _scan_source(path: Path, patterns: Sequence[str], triage_dir: Path | None = None, keep_triage: bool = True,
                 in_place: bool = False) -> _Source:
    """Open and scan one input; InputError when it cannot be read. ``triage_dir`` keeps the triage's pixel
    figures between runs (``keep_triage`` False: only reads them); ``in_place``: where each stack's edits would land
    is noted (``_Source.sites``), while the stage is open."""
    if path.is_dir() or not path.exists():  # a folder or a pattern that gave nothing, a path that is not there
        raise InputError(f"{asset_ref(path)}: {not_found_words(path)}")
    suffix = path.suffix.lower()
    if suffix in MTLX_SUFFIXES:
        scan, kind = scan_mtlx(path, triage_dir, keep_triage), "mtlx"
    elif suffix in USD_SUFFIXES:
        authoring_module()  # registers the schema plugin before the stage is opened
        stage = open_stage(path)
        scan, kind = scan_stage(stage, triage_dir, keep_triage), "usd"
    else:
        raise not_a_scene(path)
    stacks = select_stacks(scan, patterns)
    if kind != "usd":
        return _Source(path, kind, scan, stacks)
    from seamless_usd.authoring.usdshared import node_sites

    sites = {s.id: node_sites(stage, s.maps) for s in scan.stacks if not s.selection} if in_place else {}
    return _Source(path, kind, scan, stacks, instanced_stacks(stage, stacks, str(path)), sites)


def _author_source(run: Run, src: _Source) -> None:
    authoring = authoring_module()
    run.report.findings += _selected_findings(run, src.scan)
    run.report.variants += [v.to_dict() for v in src.scan.variants]
    results, handed = stack_rows(run, src.stacks, str(src.path), _output_dir(run.options, src.path))
    if not results and run.options.mode != authoring.WriteMode.DRY_RUN:
        return
    plan = run.options.plan_mode or authoring.WriteMode.NEW_LAYER
    try:
        if src.kind == "mtlx":
            edit = authoring.author_mtlx(src.path, results, mode=run.options.mode, plan_mode=plan,
                                         output_path=run.options.output_layer)
        else:
            edit = authoring.author_usd(src.path, results, mode=run.options.mode,
                                        output_layer=run.options.output_layer, plan_mode=plan, shared=run.shared)
    except Exception as exc:  # noqa: BLE001 - one source's edits failing must not stop the others
        # The tiles are written; the edits of this source are not. Say so; the other sources go on.
        if not isinstance(exc, (SeamlessUsdError, OSError)):
            exc = error_message(exc)
        run.report.findings.append(
            Finding(Severity.ERROR, "authoring-failed", asset_ref(src.path), f"the edits were not written: {exc}")
        )
        if run.options.mode != authoring.WriteMode.DRY_RUN:
            check_written(run, handed, None, failure=str(exc))
        return
    record_authoring(run, edit)
    if run.options.mode != authoring.WriteMode.DRY_RUN:
        check_written(run, handed, edit)


def _check_patterns(run: Run, sources: Sequence[_Source]) -> None:
    """--materials that match no material of any input: a usage error (nothing would be done, and a typo must not
    read as success); some of them, or --force-materials, matching none: a warning."""
    seen = [m for src in sources for m in src.scan.materials]
    named = f"the {len(set(seen))} material(s) found: {', '.join(sorted(set(seen))[:8])}" + (
        ", ..." if len(set(seen)) > 8 else "")
    for option, patterns in (("--materials", run.options.materials), ("--force-materials", run.options.force_materials)):
        unmatched = unmatched_patterns(seen, patterns)
        if not unmatched:
            continue
        said = (f"{option} {' '.join(unmatched)} matches no material of the inputs ({named}); a pattern matches a "
                "material's prim path or name, upper and lower case apart")
        if option == "--materials" and len(unmatched) == len(patterns) and sources:
            raise UsageError(said)
        run.report.findings.append(Finding(Severity.WARNING, "pattern-unmatched", option, said))
    if run.options.materials:  # a material forced but not selected is not processed at all: said, not ignored
        chosen = [m for m in seen if matches_any(m, run.options.materials)]
        left = [p for p in run.options.force_materials
                if not unmatched_patterns(seen, [p]) and not any(matches_any(m, [p]) for m in chosen)]
        if left:
            run.report.findings.append(Finding(
                Severity.WARNING, "pattern-unmatched", "--force-materials",
                f"--force-materials {' '.join(left)} names only materials --materials leaves out, so they are not "
                "processed at all; add them to --materials"))


def _selected_findings(run: Run, scan: ScanResult) -> list[Finding]:
    """The scan's findings, less those about a material that ``--materials`` leaves out (a missing texture of a
    material not asked for is not this run's to report)."""
    if not run.options.materials:
        return list(scan.findings)
    return [f for f in scan.findings if not f.material or matches_any(f.material, run.options.materials)]


def _block_shared_nodes(run: Run, scan: ScanResult, stacks: list[TextureStack], label: str) -> None:
    """Stacks whose texture nodes another use reads that is not made tileable fail (:func:`shared_node_stacks`)."""
    by_id = {s.id: s for s in scan.stacks}
    kept = {key: by_id[key[1]].intent for key in run.left_alone if key[0] == label and key[1] in by_id}
    kept.update({k: v for k, v in {**run.set_aside, **run.blocked}.items() if k[0] == label})
    run.blocked.update(shared_node_stacks(scan, stacks, label, kept))


def _scan_sources(run: Run, inputs: list[Path], sources: list[_Source]) -> None:
    """Scan every input into ``sources``; an unreadable input is reported and the others go on."""
    for path in inputs:
        run.report.sources.append(str(path))
        before = len(run.report.findings)
        try:
            in_place = authoring_module().WriteMode.IN_PLACE in (run.options.mode, run.options.plan_mode)
            src = _scan_source(path, run.options.materials, *triage_of(run.options), in_place=in_place)
            run.blocked.update(blocked_stacks(src.scan, src.stacks, str(src.path)))
            run.blocked.update(hand_set_stacks(src.stacks, str(src.path)))
            if not in_place:  # in place, a stack inside an instance is edited in its prototype's own layer
                run.blocked.update(src.instanced)
            run.set_aside.update(set_aside_stacks(src.scan, src.stacks, str(src.path)))
            unread_rows(run, src.scan, str(src.path))
            set_aside_rows(run, src.scan, str(src.path))
            run.left_alone.update(_left_alone(src.stacks, str(src.path), run.options.force, run.options.force_materials))
            src.stacks, found = from_recorded_sources(src.stacks, str(src.path), run.left_alone)
            run.report.findings += found
            sources.append(src)
        except InputError as exc:
            run.report.unreadable.append(str(path))
            where = asset_ref(path)
            # the finding names the file once, as its place (the error names it as given, or resolved)
            said = str(exc).removeprefix(f"{where}: ").removeprefix(f"{asset_ref(path.resolve())}: ")
            run.report.findings.append(Finding(Severity.ERROR, "unreadable-input", where, said))
        finally:  # each finding names its file: a library's files share material paths
            run.report.findings[before:] = [f if f.source else replace(f, source=str(path))
                                            for f in run.report.findings[before:]]


def process_paths(paths: Sequence[str | Path] | str | Path, options: Options | None = None) -> Report:
    """Process stages and MaterialX documents (files, folders, glob patterns); the report owns the exit code.

    Every input is scanned first (so progress knows the total), then stacks are processed one
    after another. An unreadable input is reported (exit code 2) and the other inputs go on.
    """
    started = time.perf_counter()
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]  # one path given as itself
    if not isinstance(paths, (list, tuple)) or not all(isinstance(p, (str, os.PathLike)) for p in paths):
        raise UsageError(f"process_paths() takes a path or a list of paths, not {type(paths).__name__} "
                         "(an open stage: process_stage())")
    if not paths:  # the command takes at least one path: nothing processed is not a pass
        raise UsageError("process_paths() was given no path: give a stage, document, folder or pattern")
    run = new_run(as_options(options))
    sources = []
    inputs = expand_inputs(paths, require_scenes=True)
    modes = authoring_module().WriteMode
    packages = [p for p in inputs if p.suffix.lower() == ".usdz"]
    if packages and modes.IN_PLACE in (run.options.mode, run.options.plan_mode):
        raise UsageError(f"--in-place: {asset_ref(packages[0])} is a .usdz package, which is not edited in place; "
                         "leave --in-place out (a new layer beside it sublayers the package) or unpack it")
    if run.options.output_layer is not None:
        if modes.IN_PLACE in (run.options.mode, run.options.plan_mode):
            raise UsageError("-o/--output-layer names a new layer, but --in-place edits the source layers: use one "
                             "or the other")
        check_output_layer(Path(run.options.output_layer), inputs)
    try:
        _scan_sources(run, inputs, sources)
    except KeyboardInterrupt:  # nothing is made yet: the stacks found so far, not made
        raise Interrupted(_interrupted(run, sources, started)) from None
    for src in sources:
        _block_shared_nodes(run, src.scan, src.stacks, str(src.path))
    if modes.IN_PLACE in (run.options.mode, run.options.plan_mode if run.options.mode is modes.DRY_RUN else None):
        for src in sources:  # edits in place into a layer marked read-only cannot be made: no tiles for them either
            run.blocked.update(_locked_in_place(run, src))
    _check_patterns(run, sources)
    if modes.IN_PLACE in (run.options.mode, run.options.plan_mode):
        run.shared = _shared_edits(run, sources)
    mode = run.options.plan_mode if run.options.mode is modes.DRY_RUN else run.options.mode
    if mode is modes.NEW_LAYER and run.options.output_layer is None:
        for src in sources:  # a file of the default new layer's name that is not this tool's: never replaced
            problem = default_layer_problem(src.path)
            if problem:
                run.blocked.update({(str(src.path), s.id): problem
                                    for s in src.stacks if (str(src.path), s.id) not in run.left_alone})
    if run.options.mode != modes.DRY_RUN:
        for src in sources:  # a source whose tiles' folder cannot be made: its stacks fail with why, before any work
            problem = folder_problem(_output_dir(run.options, src.path))
            if problem:
                hint = "; give --output-dir to write the tiles elsewhere"
                if mode is modes.NEW_LAYER and run.options.output_layer is None:
                    hint += " (and -o for the new layer, which is written beside the stage)"
                run.blocked.update({(str(src.path), s.id): f"its tiles cannot be written: {problem}{hint}"
                                    for s in src.stacks if (str(src.path), s.id) not in run.left_alone})
        try:
            _run_jobs(run, [(str(src.path), src.stacks, _output_dir(run.options, src.path)) for src in sources])
        except KeyboardInterrupt:
            raise Interrupted(_interrupted(run, sources, started)) from None
    for done, src in enumerate(sources):
        rows, findings = len(run.report.stacks), len(run.report.findings)
        try:
            _author_source(run, src)
        except KeyboardInterrupt:  # the sources before are edited; this one's rows (if any) and the rest say stopped
            del run.report.stacks[rows:], run.report.findings[findings:]
            raise Interrupted(_interrupted(run, sources[done:], started)) from None
        # each finding names its file: a library's files share material paths (every </World/Looks/Brick>)
        run.report.findings[findings:] = [f if f.source else replace(f, source=str(src.path))
                                          for f in run.report.findings[findings:]]
    return finish_run(run, started)


def _shared_edits(run: Run, sources: list[_Source]):
    """In place, where the stacks that are not made read their files (an asset two materials of a stage reference,
    a library layer two stages share): those must not change under them (:mod:`.authoring.usdshared`), so the stacks
    that would change one fail."""
    from seamless_usd.authoring.usdshared import SharedEdits

    shared = SharedEdits()
    for src in sources:
        label, selected = str(src.path), {s.id for s in src.stacks}
        for stack in src.scan.stacks:
            key = (label, stack.id)
            why = (stack.intent if key in run.left_alone else run.set_aside.get(key) or run.blocked.get(key)
                   or (None if stack.id in selected else "not selected (--materials)"))
            if why is not None and stack.id in src.sites:
                shared.keep(src.sites[stack.id], label, stack.material, why.split(";")[0])
    for src in sources:  # a stack that would change such a use fails before its tiles are made
        label = str(src.path)
        for stack in src.stacks:
            key = (label, stack.id)
            if key not in run.left_alone and key not in run.set_aside and key not in run.blocked:
                why = shared.refusal(src.sites.get(stack.id, ()), label)
                if why is not None:
                    run.blocked[key] = why
    return shared


def _interrupted(run: Run, sources: list[_Source], started: float) -> Report:
    """The report of a run stopped by Ctrl-C: every stack of ``sources`` (those whose stages were not edited yet) with
    its row as far as it got (tiles written and cached, or not made); written where ``--report`` asks, as a finished
    run's is."""
    run.report.interrupted = True
    for src in sources:
        run.report.findings += _selected_findings(run, src.scan)
        stack_rows(run, src.stacks, str(src.path), _output_dir(run.options, src.path))
    return finish_run(run, started)


def _locked_in_place(run: Run, src: _Source) -> dict[tuple[str, str], str]:
    """The stacks of ``src`` whose file values are authored in a layer or document marked read-only, with why:
    edited in place they cannot be written, so their tiles are not made either."""
    out = {}
    for stack in src.stacks:
        key = (str(src.path), stack.id)
        locked = sorted({m.file_at.layer for m in stack.maps if m.file_at and m.file_at.layer
                         and Path(m.file_at.layer).is_file() and not marked_writable(m.file_at.layer)})
        if locked and key not in run.left_alone:
            out[key] = (f"{asset_ref(locked[0])} is marked read-only, so its edits cannot be made in place and no tile "
                        "is written; make it writable, or leave out --in-place for a new layer")
    return out


def process_stage(stage, options: Options | None = None) -> Report:
    """Process an open stage in memory, as DCC export hooks receive it.

    Tiles are written to ``options.output_dir`` (default ``<root layer dir>/tileable``; a relative one is taken
    from the root layer's folder, not the working folder) and the edits are authored into the stage's current edit
    target; the stage is not saved.
    """
    started = time.perf_counter()
    from pxr import Usd

    if not isinstance(stage, Usd.Stage):
        raise UsageError(f"process_stage() takes an open Usd.Stage, not {type(stage).__name__} "
                         "(a file on disk: process_paths())")
    options = as_options(options)
    root = stage.GetRootLayer()
    source = None if root.anonymous else Path(root.realPath)
    if options.output_dir is not None and not Path(options.output_dir).is_absolute() and source is not None:
        # a DCC's working folder is anywhere: a relative folder is the stage's, as the hooks take it
        options = options.with_(output_dir=source.parent / options.output_dir)
    run = new_run(options)
    authoring = authoring_module()
    label = root.identifier
    run.report.sources.append(label)
    scan = scan_stage(stage, *triage_of(run.options))
    run.report.findings += _selected_findings(run, scan)
    run.report.variants += [v.to_dict() for v in scan.variants]
    stacks = select_stacks(scan, run.options.materials)
    # The open stage is authored as it is composed: stacks of other variant selections are named, not processed
    from seamless_usd.authoring.usdedits import variant_not_composed

    run.report.findings += [variant_not_composed(s) for s in stacks if s.selection]
    stacks = [s for s in stacks if not s.selection]
    _check_patterns(run, [_Source(Path(label), "usd", scan, stacks)])
    run.blocked.update(blocked_stacks(scan, stacks, label))
    run.blocked.update(hand_set_stacks(stacks, label))
    run.blocked.update(instanced_stacks(stage, stacks, label, open_stage=True))
    run.set_aside.update(set_aside_stacks(scan, stacks, label))
    unread_rows(run, scan, label)
    set_aside_rows(run, scan, label)
    run.left_alone.update(_left_alone(stacks, label, run.options.force, run.options.force_materials))
    stacks, found = from_recorded_sources(stacks, label, run.left_alone)
    run.report.findings += found
    _block_shared_nodes(run, scan, stacks, label)
    out_dir = _output_dir(run.options, source)
    if run.options.mode != authoring.WriteMode.DRY_RUN:
        _run_jobs(run, [(label, stacks, out_dir)])
    results, handed = stack_rows(run, stacks, label, out_dir)
    if results and run.options.mode != authoring.WriteMode.DRY_RUN:
        edit = authoring.author_usd_stage(stage, results)
        record_authoring(run, edit)
        check_written(run, handed, edit)
    return finish_run(run, started)
