"""What every DCC export hook shares, with no DCC imported: settings (``settings.py``), output
folder, log lines (``loglines.py``) and the one entry point hooks call.

A hook adapter (Blender add-on, Maya export chaser, Houdini output processor) does three things:
read its DCC's settings into a :class:`HookSettings`, hand the open stage to :func:`run_hook`, and
print the :class:`LogLine` s it gets back in the DCC's own way. Everything here is plain Python, so
it is tested without any DCC; ``pxr`` and ``torch`` are imported only when a hook actually runs.

Example
-------
>>> settings = settings_from_mapping({"preset": "draft", "materials": "/root/_materials/Brick*"})
>>> settings.preset, settings.materials
('draft', ('/root/_materials/Brick*',))
"""
from __future__ import annotations

import fnmatch
import logging
import os
import re
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from seamless_usd.errors import SeamlessUsdError, UsageError
from seamless_usd.findings import asset_ref
from seamless_usd.hooks.loglines import PREFIX, Level, LogLine, _failed, _log_emit, progress_logger, report_lines
from seamless_usd.hooks.settings import (
    SETTING_NAMES,
    HookError,
    HookSettings,
    parse_bool,
    parse_patterns,
    settings_from_attributes,
    settings_from_mapping,
    settings_to_chaser_args,
)

__all__ = [
    "HookSettings",
    "Level",
    "LogLine",
    "HookError",
    "run_guarded",
    "SETTING_NAMES",
    "parse_bool",
    "parse_patterns",
    "settings_from_mapping",
    "settings_from_attributes",
    "settings_to_chaser_args",
    "resolve_output_dir",
    "options_for_stage",
    "report_lines",
    "export_ok",
    "progress_logger",
    "HookRun",
    "run_hook",
    "process_layer",
]

log = logging.getLogger("seamless_usd.hooks")

# Shader ids of the texture nodes discovery reads (UsdPreviewSurface and MaterialX in USD).
_TEXTURE_SHADER_IDS = ("UsdUVTexture", "ND_image_*", "ND_tiledimage_*", "ND_gltf_*image*")



def _expand(text: str) -> Path:
    return Path(os.path.expandvars(os.path.expanduser(text)))


def _layer_dir(stage: object) -> Path | None:
    """Folder of the stage's root layer on disk, or None for an anonymous (in-memory) layer."""
    root = stage.GetRootLayer()  # type: ignore[attr-defined]
    if root.anonymous or not root.realPath:
        return None
    return Path(root.realPath).resolve().parent


def resolve_output_dir(setting: str, *, layer_dir: Path | None, export_path: Path | None = None) -> Path | None:
    """Where the tileable maps go.

    - blank: ``None`` (the library's default, ``<layer dir>/tileable``) when the exported layer is
      on disk; ``<export dir>/tileable`` for an in-memory layer with a known export path;
    - absolute (after ``~`` and ``$VAR`` expansion): as given;
    - relative: from the exported layer's folder (for a ``.usdz`` export that is the DCC's staging
      folder, so the maps are packaged), else from the export path's folder.

    An in-memory layer with neither an export path nor an absolute folder is a :class:`UsageError`.

    >>> resolve_output_dir("", layer_dir=Path("/shots/a")) is None
    True
    >>> resolve_output_dir("maps", layer_dir=Path("/shots/a")).as_posix()
    '/shots/a/maps'
    """
    base = layer_dir if layer_dir is not None else (export_path.parent if export_path else None)
    text = setting.strip()
    if not text:
        if layer_dir is not None:
            return None
        if base is not None:
            return base / "tileable"
        raise UsageError("the exported stage is in memory only: set an absolute output folder for tileable maps")
    path = _expand(text)
    if path.is_absolute():
        return path
    if base is None:
        raise UsageError(
            f"output folder {text!r} is relative but the exported stage is in memory only: give an absolute folder"
        )
    return base / path


def options_for_stage(
    settings: HookSettings,
    stage: object,
    *,
    export_path: Path | None = None,
    progress: Callable[[Any], None] | None = None,
):
    """The :class:`seamless_usd.Options` a hook passes to ``process_stage`` for this stage."""
    import seamless_usd

    layer_dir = _layer_dir(stage)
    changes: dict[str, Any] = {
        "preset": settings.preset or "default",
        "materials": tuple(settings.materials),
        "seed": settings.seed,
        "output_dir": resolve_output_dir(settings.output_dir, layer_dir=layer_dir, export_path=export_path),
        "progress": progress,
    }
    if settings.device:
        changes["device"] = settings.device
    if settings.report:
        report = _expand(settings.report)
        base = layer_dir or (export_path.parent if export_path else None)
        changes["report"] = report if report.is_absolute() or base is None else base / report
    if settings.cache_dir:
        changes["cache_dir"] = _expand(settings.cache_dir)
    if settings.max_size > 0:
        changes["max_size"] = settings.max_size
    if settings.iterations > 0:
        changes["iterations"] = settings.iterations
    if settings.seeds > 0:
        changes["seeds"] = settings.seeds
    if settings.straighten:  # the asset keeps its look: the turn goes back in the UVs (never --write-straight)
        changes["straighten"] = True
    if settings.dry_run:
        changes["mode"] = seamless_usd.WriteMode.DRY_RUN
    return seamless_usd.Options(**changes)



def _default_process(stage: object, options: object) -> object:
    import seamless_usd

    return seamless_usd.process_stage(stage, options)


@dataclass
class HookRun:
    """What :func:`run_hook` did: the report (None when nothing ran) and the lines it logged."""

    report: object | None = None
    lines: list[LogLine] = field(default_factory=list)
    ok: bool = True


def export_ok(run: HookRun, settings: HookSettings) -> bool:
    """What a hook tells its DCC (False: the export failed): a stack that failed or did not pass fails the export only
    with ``strict``; otherwise it is logged and the export goes on (Blender's ``on_export``, Maya's chaser)."""
    return run.ok or not settings.strict


def setting_words(message: str) -> str:
    """``message`` with the command line's option names (``--max-size``) given as the hook's setting names (``the
    max_size setting``), which are what a DCC user sees."""
    def named(match: re.Match) -> str:
        name = match.group(1).replace("-", "_")
        return f"the {name} setting" if name in SETTING_NAMES else match.group(0)

    return re.sub(r"(?<![\w-])--([a-z][a-z-]*)", named, message)


def run_guarded(action: Callable[[], object], settings: HookSettings, what: str, *,
                emit: Callable[[LogLine], None] | None = None) -> bool:
    """Run a hook's step that is not a run of the tool (writing the textures an export left unwritten) under
    :func:`run_hook`'s rule, so that it never takes the DCC's export down by default: an expected error is one
    line, an unexpected one its traceback; with ``settings.strict`` a :class:`HookError` follows. Returns whether
    the step succeeded."""
    emit = emit or _log_emit
    try:
        action()
        return True
    except SeamlessUsdError as exc:
        emit(LogLine(Level.ERROR, f"{PREFIX}: {what}: {exc}"))
        if settings.strict:
            raise HookError(f"{what}: {exc}") from exc
    except Exception as exc:  # noqa: BLE001 - a hook must not take the DCC's export down by default
        emit(LogLine(Level.ERROR, f"{PREFIX}: {what}: unexpected error:\n{traceback.format_exc()}"))
        if settings.strict:
            raise HookError(f"{what}: unexpected error: {exc!r}") from exc
    return False


def run_hook(
    stage: object,
    settings: HookSettings,
    *,
    export_path: Path | None = None,
    emit: Callable[[LogLine], None] | None = None,
    process: Callable[[object, object], object] | None = None,
    on_progress: Callable[[Any], None] | None = None,
) -> HookRun:
    """Run ``process_stage`` on a stage a DCC is exporting; never leave the DCC with a half error.

    ``on_progress`` gets every :class:`seamless_usd.ProgressEvent` (for a DCC progress bar).
    Edits go into the stage's current edit target and the stage is not saved (the DCC saves it).
    Expected errors (:class:`seamless_usd.errors.SeamlessUsdError`) are logged as one line;
    unexpected ones with their traceback. With ``settings.strict`` a failure raises
    :class:`HookError` after logging, so that the DCC reports the export as failed; otherwise the
    export goes on with the textures as they were.
    """
    emit = emit or _log_emit
    run = HookRun()

    def say(line: LogLine) -> None:
        run.lines.append(line)
        emit(line)

    if not settings.enabled:
        say(LogLine(Level.INFO, f"{PREFIX}: disabled, textures left as exported"))
        return run
    try:
        options = options_for_stage(settings, stage, export_path=export_path, progress=progress_logger(say, on_progress))
        run.report = (process or _default_process)(stage, options)
    except SeamlessUsdError as exc:
        run.ok = False
        say(LogLine(Level.ERROR, f"{PREFIX}: {setting_words(str(exc))}"))
        if settings.strict:
            raise HookError(str(exc)) from exc
        return run
    except Exception as exc:  # noqa: BLE001 - a hook must not take the DCC's export down by default
        run.ok = False
        say(LogLine(Level.ERROR, f"{PREFIX}: unexpected error, textures left as exported:\n{traceback.format_exc()}"))
        if settings.strict:
            raise HookError(f"unexpected error: {exc!r}") from exc
        return run
    for line in report_lines(run.report):
        say(line)
    if _failed(run.report):
        run.ok = False
        if settings.strict:
            raise HookError("some texture stacks failed (see the log above)")
    return run


def process_layer(
    layer: object,
    save_path: str | Path | None,
    settings: HookSettings,
    *,
    emit: Callable[[LogLine], None] | None = None,
    process: Callable[[object, object], object] | None = None,
) -> HookRun:
    """Run the hook on one ``Sdf.Layer`` that is about to be saved to ``save_path`` (Houdini).

    Output processors get each layer before it is written, often as an anonymous layer whose
    relative asset paths are meant from ``save_path``. The content is moved into a scratch layer
    whose identifier is ``save_path`` (so relative paths resolve and maps go next to it), the
    stage on it is processed, and the result is moved back into ``layer``. A layer that already
    has an identifier on disk is processed as it is. Returns the run; ``run.report`` is None when
    the layer holds no texture shader (nothing to do, nothing touched).
    """
    from pxr import Sdf, Usd

    run = HookRun()
    if not settings.enabled or not _has_texture_shader(layer):
        return run
    if not layer.anonymous:  # type: ignore[attr-defined]
        moved = _saved_elsewhere(layer, save_path)
        if moved:  # said first, so that the DCC's log shows it before the run's lines
            (emit or _log_emit)(moved)
        run = run_hook(Usd.Stage.Open(layer), settings, emit=emit, process=process)
        if moved:
            run.lines.insert(0, moved)
        return run
    if save_path is None:
        return run_hook(Usd.Stage.Open(layer), settings, emit=emit, process=process)
    save_path = Path(save_path).resolve()
    fmt = Sdf.FileFormat.FindByExtension(save_path.suffix.lstrip(".") or "usda") or Sdf.FileFormat.FindById("usda")
    name = save_path
    if Sdf.Layer.Find(str(save_path)):
        # A layer with that identifier is open already (a node that loads the last save): a scratch layer of
        # another name in the same folder, so relative paths still resolve from there (never saved)
        import uuid

        name = save_path.with_name(f".{save_path.stem}.{uuid.uuid4().hex}{save_path.suffix}")
    scratch = Sdf.Layer.New(fmt, str(name))
    scratch.TransferContent(layer)
    run = run_hook(Usd.Stage.Open(scratch), settings, export_path=save_path, emit=emit, process=process)
    if run.report is not None:
        layer.TransferContent(scratch)  # type: ignore[attr-defined]
    return run


def _saved_elsewhere(layer: object, save_path: str | Path | None) -> LogLine | None:
    """A warning when a layer already on disk is about to be saved somewhere else: it is processed where it is (its
    relative asset paths, the tiles' among them, are meant from its own folder), so they do not resolve from the
    save path unless the DCC rewrites them."""
    real = getattr(layer, "realPath", "") or ""
    if save_path is None or not real or Path(save_path).resolve() == Path(real).resolve():
        return None
    return LogLine(Level.WARNING, f"{PREFIX}: {asset_ref(real)} is a layer on disk saved to {asset_ref(save_path)}: "
                   f"it was processed where it is, so its tiles are beside it and its relative asset paths, the tiles' "
                   f"among them, resolve from {asset_ref(Path(real).parent)}, not from the save path's folder; save "
                   f"the layer where it is, or export it as a new layer")


def _has_texture_shader(layer: object) -> bool:
    """Whether the layer authors a texture node that discovery looks at (cheap pre-check)."""
    ids: list[str] = []

    def collect(path: object) -> None:
        if path.IsPropertyPath() and path.name == "info:id":  # type: ignore[attr-defined]
            spec = layer.GetAttributeAtPath(path)  # type: ignore[attr-defined]
            if spec is not None and spec.default:
                ids.append(str(spec.default))

    layer.Traverse(layer.pseudoRoot.path, collect)  # type: ignore[attr-defined]
    return any(fnmatch.fnmatch(i, p) for i in ids for p in _TEXTURE_SHADER_IDS)
