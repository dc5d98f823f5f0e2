"""Checkpoints as safetensors: weights, optimiser state, step, config and versions; never pickles."""
from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import torch
from safetensors import SafetensorError
from safetensors.torch import load_file, save_file

__all__ = ["CHECKPOINT_NAME", "save_checkpoint", "load_checkpoint", "optimizer_tensors", "load_optimizer_tensors",
           "versions"]

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


def optimizer_tensors(prefix: str, opt: torch.optim.Optimizer) -> dict[str, torch.Tensor]:
    """Adam state flattened to named tensors: ``{prefix}.{param index}.{exp_avg|exp_avg_sq|step}``."""
    out = {}
    for idx, st in opt.state_dict()["state"].items():
        for name, t in st.items():
            out[f"{prefix}.{idx}.{name}"] = torch.as_tensor(t).detach().cpu().contiguous()
    return out


def load_optimizer_tensors(prefix: str, opt: torch.optim.Optimizer, tensors: dict[str, torch.Tensor]) -> None:
    sd = opt.state_dict()
    state: dict[int, dict[str, torch.Tensor]] = {}
    for key, t in tensors.items():
        if key.startswith(prefix + "."):
            _, idx, name = key.split(".", 2)
            state.setdefault(int(idx), {})[name] = t
    sd["state"] = state
    opt.load_state_dict(sd)


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
