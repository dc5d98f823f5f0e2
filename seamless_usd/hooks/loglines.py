"""What a hook prints: the report as log lines with levels, and progress as lines, for any DCC."""
from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import Any

__all__ = ["Level", "LogLine", "PREFIX", "report_lines", "progress_logger"]

log = logging.getLogger("seamless_usd.hooks")


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


def _done(result: object) -> str:
    """A finished stack's result (the job's outcome, or the error it ended in) in a word or two."""
    if isinstance(result, Exception):
        return "failed"
    passed = getattr(result, "passed", None)
    return "done" if passed is None else "passed" if passed else "not passed"


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
    said: set[tuple[str, str]] = set()  # (material, message) of each stack line: a finding saying the same is not
    #                                     logged again
    for s in stacks:
        status = _value(s.status)
        material = str(s.material)
        said.add((material, str(getattr(s, "message", ""))))
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
        if (str(f.where), str(f.message)) in said:
            continue
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
    """An ``Options.progress`` callback that logs each stack's start, its long stages and its end (not every step),
    and hands every event to ``also`` (a DCC's progress bar) when given."""

    def progress(event: Any) -> None:
        if also is not None:
            also(event)
        kind = getattr(event, "kind", "")
        if kind == "stack-start":
            emit(LogLine(Level.INFO, f"{PREFIX}: stack {event.index + 1}/{event.total}: {event.stack_id}"))
        elif kind == "stage":  # a step that may take minutes on a large stack (cutting tiles, writing, judging)
            emit(LogLine(Level.INFO, f"{PREFIX}: stack {event.index + 1}/{event.total}: {event.detail}"))
        elif kind == "stack-done":
            emit(LogLine(Level.INFO, f"{PREFIX}: stack {event.index + 1}/{event.total} "
                                     f"{_done(getattr(event, 'detail', None))}"))

    return progress


def _log_emit(line: LogLine) -> None:
    {Level.INFO: log.info, Level.WARNING: log.warning, Level.ERROR: log.error}[line.level](line.text)


