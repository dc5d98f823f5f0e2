"""Test helper: a script of ``benchmarks/`` (or of ``benchmarks/experiments/``) loaded as a module (the scripts
are not a package)."""
from __future__ import annotations

import functools
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


@functools.cache
def load_benchmark(name: str) -> ModuleType:
    """``benchmarks/{name}.py`` (``name`` may name a subfolder: ``experiments/levers``), executed once per
    test session; registered in ``sys.modules`` under ``benchmark_{name}`` with ``/`` as ``_`` (dataclasses
    look their module up there)."""
    spec = importlib.util.spec_from_file_location(f"benchmark_{name.replace('/', '_')}", BENCHMARKS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module
