"""seamless-usd: make USD / MaterialX material textures seamlessly tileable with SeamlessGAN.

The public API (see :mod:`seamless_usd.api`): :func:`scan`, :func:`process_stage`,
:func:`process_paths`, :class:`Options`, :class:`WriteMode`, :class:`Report`. Names are loaded on
first use so that ``import seamless_usd`` stays light (no torch, no pxr) for DCC start-up.
"""
from __future__ import annotations

from seamless_usd.version import __version__

_API = {"scan", "process_stage", "process_paths", "Options", "ProgressEvent", "Report", "StackReport", "StackStatus", "WriteMode"}

__all__ = ["__version__", *sorted(_API)]


def __getattr__(name: str):
    if name in _API:
        from seamless_usd import api

        return getattr(api, name)
    raise AttributeError(f"module 'seamless_usd' has no attribute {name!r}")
