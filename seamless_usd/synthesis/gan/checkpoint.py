"""Checkpoints as safetensors: weights, optimiser state, step, config and versions; never pickles."""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, save_file

__all__ = ["CHECKPOINT_NAME", "save_checkpoint", "load_checkpoint", "versions"]

CHECKPOINT_NAME = "checkpoint.safetensors"
FORMAT_VERSION = 1


def versions() -> dict[str, str]:
    from importlib.metadata import PackageNotFoundError, version
    try:
        ours = version("seamless-usd")
    except PackageNotFoundError:
        ours = "unknown"
    return {"seamless_usd": ours, "torch": torch.__version__, "numpy": np.__version__,
            "format": str(FORMAT_VERSION)}


def save_checkpoint(path: Path, tensors: dict[str, torch.Tensor], meta: dict) -> None:
    """Write atomically (temp file + rename) so a killed run never leaves a torn checkpoint."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    save_file({k: v.detach().cpu().contiguous() for k, v in tensors.items()}, str(tmp),
              metadata={"meta": json.dumps(meta, sort_keys=True)})
    os.replace(tmp, path)


def load_checkpoint(path: Path) -> tuple[dict[str, torch.Tensor], dict]:
    """(tensors, meta). Anything that is not a safetensors file written by ``save_checkpoint`` is refused."""
    path = Path(path)
    try:
        tensors = load_file(str(path))
        from safetensors import safe_open
        with safe_open(str(path), "pt") as f:
            meta_text = (f.metadata() or {}).get("meta")
    except (SafetensorError, OSError, ValueError) as e:
        raise ValueError(f"{path.name}: not a safetensors checkpoint; refusing to load it ({e})") from e
    if meta_text is None:
        raise ValueError(f"{path.name}: safetensors file without seamless-usd metadata")
    return tensors, json.loads(meta_text)
