"""What every DCC export hook shares, with no DCC imported: settings, output folder, log lines.

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
import traceback
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from enum import Enum
from pathlib import Path
from typing import Any

from seamless_usd.errors import SeamlessUsdError, UsageError

__all__ = [
    "HookSettings",
    "Level",
    "LogLine",
    "HookError",
    "SETTING_NAMES",
    "parse_bool",
    "parse_patterns",
    "settings_from_mapping",
    "settings_from_attributes",
    "settings_to_chaser_args",
    "resolve_output_dir",
    "options_for_stage",
    "report_lines",
    "progress_logger",
    "HookRun",
    "run_hook",
    "process_layer",
]

log = logging.getLogger("seamless_usd.hooks")

# Shader ids of the texture nodes discovery reads (UsdPreviewSurface and MaterialX in USD).
_TEXTURE_SHADER_IDS = ("UsdUVTexture", "ND_image_*", "ND_tiledimage_*", "ND_gltf_*image*")


class HookError(SeamlessUsdError):
    """Raised by :func:`run_hook` in strict mode, so that the DCC's export itself fails."""


@dataclass(frozen=True)
class HookSettings:
    """The settings every DCC exposes, in DCC-neutral form (strings are as the user typed them).

    Empty strings and zeros mean "the library's default", so that a DCC's blank text field or
    zeroed number field never overrides :class:`seamless_usd.Options`.
    """

    enabled: bool = True  # run at export time at all
    preset: str = "default"  # synthesis preset name; validated by the library
    materials: tuple[str, ...] = ()  # glob patterns on material prim paths; empty = every material
    output_dir: str = ""  # "" = <folder of the exported layer>/tileable; relative = from that folder
    device: str = ""  # "" = CUDA when present, else CPU
    seed: int = 0
    dry_run: bool = False  # plan only: nothing written, the stage left as it is
    report: str = ""  # HTML report path ("" = none); relative = from the exported layer's folder
    cache_dir: str = ""  # "" = the user's cache folder
    max_size: int = 0  # working-resolution cap in px (longest side); 0 = native size
    iterations: int = 0  # training iterations; 0 = the preset's
    strict: bool = False  # fail the DCC's export when a stack fails or the run raises

    def with_(self, **changes: Any) -> "HookSettings":
        return replace(self, **changes)


SETTING_NAMES: tuple[str, ...] = tuple(f.name for f in fields(HookSettings))

_TRUE = {"1", "true", "yes", "on", "y", "t"}
_FALSE = {"0", "false", "no", "off", "n", "f", ""}


def parse_bool(value: object) -> bool:
    """A DCC's boolean: a bool, an int toggle (Houdini) or a string (Maya chaser args).

    >>> parse_bool("On"), parse_bool(0), parse_bool("false")
    (True, False, False)
    """
    if isinstance(value, bool):
        return value
    if isinstance(value, (int, float)):
        return value != 0
    text = str(value).strip().lower()
    if text in _TRUE:
        return True
    if text in _FALSE:
        return False
    raise UsageError(f"not a yes/no value: {value!r} (use one of 1/0, true/false, yes/no, on/off)")


def parse_patterns(value: object) -> tuple[str, ...]:
    """Glob patterns from a text field: separated by commas, semicolons or whitespace.

    >>> parse_patterns("/root/_materials/Brick*, /World/Looks/*;  ")
    ('/root/_materials/Brick*', '/World/Looks/*')
    """
    if value is None:
        return ()
    if isinstance(value, (list, tuple)):
        items: Iterable[str] = (str(v) for v in value)
    else:
        items = str(value).replace(",", " ").replace(";", " ").split()
    return tuple(p.strip() for p in items if p.strip())


def _parse_int(value: object) -> int:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, (int, float)):
        return int(value)
    text = str(value).strip()
    if not text:
        return 0
    try:
        return int(text)
    except ValueError:
        raise UsageError(f"not a whole number: {value!r}") from None


def _parse_str(value: object) -> str:
    return "" if value is None else str(value).strip()


# One parser per setting (a registry rather than if/elif on names).
_PARSERS: dict[str, Callable[[object], Any]] = {
    "enabled": parse_bool,
    "preset": lambda v: _parse_str(v) or "default",
    "materials": parse_patterns,
    "output_dir": _parse_str,
    "device": _parse_str,
    "seed": _parse_int,
    "dry_run": parse_bool,
    "report": _parse_str,
    "cache_dir": _parse_str,
    "max_size": _parse_int,
    "iterations": _parse_int,
    "strict": parse_bool,
}
assert set(_PARSERS) == set(SETTING_NAMES), "every HookSettings field needs a parser"


def settings_from_mapping(
    values: Mapping[str, object], *, prefix: str = "", base: HookSettings | None = None, strict_keys: bool = True
) -> HookSettings:
    """Settings from name/value pairs: Maya chaser args (all strings) or Houdini parm values.

    ``prefix`` is stripped from names first (Houdini parm names are prefixed to stay unique on the
    ROP). Names that do not start with ``prefix`` are ignored; an unknown name after the prefix is
    an error listing the valid names (unless ``strict_keys`` is false).

    >>> settings_from_mapping({"seamlessusd_seed": "3", "lopoutput": "x.usd"}, prefix="seamlessusd_").seed
    3
    """
    changes: dict[str, Any] = {}
    for raw_name, value in values.items():
        if not raw_name.startswith(prefix):
            continue
        name = raw_name[len(prefix):]
        parser = _PARSERS.get(name)
        if parser is None:
            if strict_keys:
                raise UsageError(
                    f"unknown seamless-usd hook setting {raw_name!r}; valid: "
                    + ", ".join(prefix + n for n in SETTING_NAMES)
                )
            continue
        try:
            changes[name] = parser(value)
        except UsageError as exc:
            raise UsageError(f"hook setting {raw_name!r}: {exc}") from None
    return replace(base or HookSettings(), **changes)


def settings_from_attributes(obj: object, *, base: HookSettings | None = None) -> HookSettings:
    """Settings from an object with attributes of the same names (Blender add-on preferences).

    Attributes the object does not have keep their defaults.
    """
    values = {name: getattr(obj, name) for name in SETTING_NAMES if hasattr(obj, name)}
    return settings_from_mapping(values, base=base)


def settings_to_chaser_args(chaser: str, settings: HookSettings) -> list[list[str]]:
    """``[[chaser, name, value], ...]`` for Maya's ``chaserArgs`` (only non-default settings).

    >>> settings_to_chaser_args("seamless_usd", HookSettings(preset="draft", materials=("/a*", "/b")))
    [['seamless_usd', 'preset', 'draft'], ['seamless_usd', 'materials', '/a*,/b']]
    """
    default = HookSettings()
    out = []
    for name in SETTING_NAMES:
        value = getattr(settings, name)
        if value == getattr(default, name):
            continue
        if isinstance(value, tuple):
            text = ",".join(value)
        elif isinstance(value, bool):
            text = "1" if value else "0"
        else:
            text = str(value)
        out.append([chaser, name, text])
    return out


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
    if settings.dry_run:
        changes["mode"] = seamless_usd.WriteMode.DRY_RUN
    return seamless_usd.Options(**changes)


class Level(str, Enum):
    INFO = "info"
    WARNING = "warning"
    ERROR = "error"


@dataclass(frozen=True)
class LogLine:
    level: Level
    text: str

    def __str__(self) -> str:
        return self.text if self.level is Level.INFO else f"{self.level.value}: {self.text}"


_STATUS_LEVEL = {"failed": Level.ERROR, "not-passed": Level.WARNING}
_SEVERITY_LEVEL = {"error": Level.ERROR, "warning": Level.WARNING, "skipped": Level.INFO}
PREFIX = "seamless-usd"


def _value(x: object) -> str:
    return str(getattr(x, "value", x))


def report_lines(report: object) -> list[LogLine]:
    """A report as DCC log lines: one summary line, one per stack, one per finding.

    Stacks that failed and error findings are errors; stacks that did not pass the tileability
    check and warnings are warnings; the rest is information.
    """
    stacks = list(getattr(report, "stacks", []))
    counts: dict[str, int] = {}
    for s in stacks:
        counts[_value(s.status)] = counts.get(_value(s.status), 0) + 1
    exit_code = getattr(report, "exit_code", 0)
    parts = ", ".join(f"{n} {k}" for k, n in sorted(counts.items())) or "no texture stacks"
    lines = [
        LogLine(
            Level.INFO if exit_code == 0 else Level.WARNING,
            f"{PREFIX}: {len(stacks)} stack(s): {parts} (exit code {exit_code})",
        )
    ]
    for s in stacks:
        status = _value(s.status)
        material = str(s.material)
        text = f"{PREFIX}: {status}: {material if material.startswith('<') else f'<{material}>'}"
        if getattr(s, "uv_scale", None):
            text += " uv scale ({:.4g}, {:.4g})".format(*s.uv_scale)
        if getattr(s, "message", ""):
            text += f": {s.message}"
        lines.append(LogLine(_STATUS_LEVEL.get(status, Level.INFO), text))
        for m in getattr(s, "maps", []):
            if getattr(m, "output", None):
                lines.append(LogLine(Level.INFO, f"{PREFIX}:   @{m.asset}@ -> @{m.output}@"))
    for f in getattr(report, "findings", []):
        level = _SEVERITY_LEVEL.get(_value(f.severity), Level.WARNING)
        # Warnings and errors carry their level already (LogLine.__str__); skipped items say so.
        text = f"{PREFIX}: {f}" if level is Level.INFO else f"{PREFIX}: {f.where}: {f.message}"
        lines.append(LogLine(level, text))
    return lines


def _failed(report: object) -> bool:
    """Something broke (not merely "did not pass the tileability check")."""
    if getattr(report, "unreadable", None):
        return True
    if any(_value(s.status) == "failed" for s in getattr(report, "stacks", [])):
        return True
    return any(_value(f.severity) == "error" for f in getattr(report, "findings", []))


def progress_logger(
    emit: Callable[[LogLine], None], also: Callable[[Any], None] | None = None
) -> Callable[[Any], None]:
    """An ``Options.progress`` callback that logs each stack's start and end (not every step),
    and hands every event to ``also`` (a DCC's progress bar) when given."""

    def progress(event: Any) -> None:
        if also is not None:
            also(event)
        kind = getattr(event, "kind", "")
        if kind == "stack-start":
            emit(LogLine(Level.INFO, f"{PREFIX}: stack {event.index + 1}/{event.total}: {event.stack_id}"))
        elif kind == "stack-done":
            status = _value(getattr(getattr(event, "detail", None), "status", "done"))
            emit(LogLine(Level.INFO, f"{PREFIX}: stack {event.index + 1}/{event.total} {status}"))

    return progress


def _log_emit(line: LogLine) -> None:
    {Level.INFO: log.info, Level.WARNING: log.warning, Level.ERROR: log.error}[line.level](line.text)


def _default_process(stage: object, options: object) -> object:
    import seamless_usd

    return seamless_usd.process_stage(stage, options)


@dataclass
class HookRun:
    """What :func:`run_hook` did: the report (None when nothing ran) and the lines it logged."""

    report: object | None = None
    lines: list[LogLine] = field(default_factory=list)
    ok: bool = True


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
        say(LogLine(Level.ERROR, f"{PREFIX}: {exc}"))
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
        return run_hook(Usd.Stage.Open(layer), settings, emit=emit, process=process)
    if save_path is None:
        return run_hook(Usd.Stage.Open(layer), settings, emit=emit, process=process)
    save_path = Path(save_path).resolve()
    fmt = Sdf.FileFormat.FindByExtension(save_path.suffix.lstrip(".") or "usda") or Sdf.FileFormat.FindById("usda")
    if Sdf.Layer.Find(str(save_path)):
        # A layer with that identifier is open already: work on the anonymous layer, anchored
        # only through an explicit output folder from the save path.
        settings = settings.with_(
            output_dir=str(resolve_output_dir(settings.output_dir, layer_dir=None, export_path=save_path))
        )
        return run_hook(Usd.Stage.Open(layer), settings, export_path=save_path, emit=emit, process=process)
    scratch = Sdf.Layer.New(fmt, str(save_path))
    scratch.TransferContent(layer)
    run = run_hook(Usd.Stage.Open(scratch), settings, export_path=save_path, emit=emit, process=process)
    if run.report is not None:
        layer.TransferContent(scratch)  # type: ignore[attr-defined]
    return run


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
