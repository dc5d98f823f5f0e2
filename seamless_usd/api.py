"""The public Python API: what the CLI, export hooks and pipeline scripts call.

Example
-------
>>> import seamless_usd  # doctest: +SKIP
>>> report = seamless_usd.process_paths(["scene.usda"], seamless_usd.Options(preset="draft"))  # doctest: +SKIP
>>> report.exit_code  # doctest: +SKIP
0
"""
from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path

from seamless_usd.errors import UsageError
from seamless_usd.textures import ScanResult
from seamless_usd.pipeline.check import CheckItem, CheckReport, check_paths
from seamless_usd.pipeline.options import Options, ProgressEvent
from seamless_usd.pipeline.process import process_paths, process_stage
from seamless_usd.report.model import Report, StackReport, StackStatus

__all__ = [
    "CheckItem",
    "CheckReport",
    "Options",
    "ProgressEvent",
    "Report",
    "StackReport",
    "StackStatus",
    "WriteMode",
    "check",
    "scan",
    "process_stage",
    "process_paths",
]


def __getattr__(name: str):
    if name == "WriteMode":
        from seamless_usd.authoring import WriteMode

        return WriteMode
    raise AttributeError(name)


def scan(stage_or_path) -> ScanResult:
    """List the texture stacks of an open ``Usd.Stage``, or of a stage / ``.mtlx`` file path.

    Scanning reads headers only; nothing is written. Anything else is a :class:`~seamless_usd.errors.UsageError`
    naming what was given.
    """
    from seamless_usd import discover

    if isinstance(stage_or_path, (str, os.PathLike)):
        return discover.scan_paths([Path(stage_or_path)])
    from pxr import Usd

    if not isinstance(stage_or_path, Usd.Stage):
        raise UsageError(f"scan() takes an open Usd.Stage or the path of a stage or .mtlx document, "
                         f"not {type(stage_or_path).__name__}")
    return discover.scan_stage(stage_or_path)


def check(paths: Sequence[str | os.PathLike] | str | os.PathLike, *, jobs: int = 1,
          progress: Callable[[str, int, int], None] | None = None) -> CheckReport:
    """The verdict, as ``seamless-usd check`` gives it, on stages, ``.mtlx`` documents, pictures and folders:
    every stack meant to tile (a tile this tool wrote, against the source it records), every picture (a tile with
    its stack's other tiles, against their sources; any other texture on its own). Nothing is written.

    ``report.exit_code`` is the command's; ``report.items`` one :class:`CheckItem` per stack or picture
    (``passed``, ``verdict``, ``note``, ``error``); ``report.unreadable`` the inputs that could not be opened.
    ``jobs``: worker processes judging pictures; ``progress(name, done, total)`` is called as work is done.

    >>> import seamless_usd  # doctest: +SKIP
    >>> report = seamless_usd.check("tileable/")  # doctest: +SKIP
    >>> [item.name for item in report.items if not item.passed]  # doctest: +SKIP
    []
    """
    if isinstance(paths, (str, os.PathLike)):
        paths = [paths]  # one path given as itself, not as its letters
    elif not isinstance(paths, Sequence) or not all(isinstance(p, (str, os.PathLike)) for p in paths):
        raise UsageError(f"check() takes a path or a list of paths, not {type(paths).__name__}")
    if not paths:  # the command takes at least one path: nothing to judge is not a pass
        raise UsageError("check() was given no path: give a stage, document, picture or folder")
    if not isinstance(jobs, int) or isinstance(jobs, bool) or jobs < 1:
        raise UsageError(f"check(jobs={jobs!r}): a whole number of worker processes, at least 1")
    return check_paths([Path(p) for p in paths], progress=progress, jobs=jobs)
