"""The public Python API: what the CLI, export hooks and pipeline scripts call.

Example
-------
>>> import seamless_usd  # doctest: +SKIP
>>> report = seamless_usd.process_paths(["scene.usda"], seamless_usd.Options(preset="draft"))  # doctest: +SKIP
>>> report.exit_code  # doctest: +SKIP
0
"""
from __future__ import annotations

from pathlib import Path

from seamless_usd.textures import ScanResult
from seamless_usd.pipeline.options import Options, ProgressEvent
from seamless_usd.pipeline.process import process_paths, process_stage
from seamless_usd.report.model import Report, StackReport, StackStatus

__all__ = [
    "Options",
    "ProgressEvent",
    "Report",
    "StackReport",
    "StackStatus",
    "WriteMode",
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

    Scanning reads headers only; nothing is written.
    """
    from seamless_usd import discover

    if isinstance(stage_or_path, (str, Path)):
        return discover.scan_paths([stage_or_path])
    return discover.scan_stage(stage_or_path)
