"""seamless-usd: make USD / MaterialX material textures seamlessly tileable with SeamlessGAN.

The public API (see :mod:`seamless_usd.api`): :func:`scan`, :func:`check`, :func:`process_stage`,
:func:`process_paths`, :class:`Options`, :class:`WriteMode`, :class:`Report`, :class:`CheckReport`. Names are
loaded on first use so that ``import seamless_usd`` stays light (no torch, no pxr) for DCC start-up.
"""
from __future__ import annotations

import os

from seamless_usd.version import __version__

# Threads that sleep instead of spinning at OpenMP barriers: on a busy machine (other jobs on the same cores)
# spinning made 2-thread training 5-10x slower than 1 thread (benchmarks/speed.py). Set here, before any step
# first imports torch (the verdict imports it only when it resizes a map); an explicit setting always wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

_API = {"scan", "check", "process_stage", "process_paths", "Options", "ProgressEvent", "Report", "StackReport",
        "StackStatus", "CheckReport", "CheckItem", "WriteMode"}

__all__ = ["__version__", *sorted(_API)]


def __getattr__(name: str):
    if name in _API:
        from seamless_usd import api

        return getattr(api, name)
    raise AttributeError(f"module 'seamless_usd' has no attribute {name!r}")
