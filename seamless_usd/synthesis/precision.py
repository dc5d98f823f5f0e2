"""Device and precision choice, and the one place where autocast is set up."""
from __future__ import annotations

import contextlib
import functools

import torch

__all__ = ["pick_device", "cpu_supports_bf16", "choose_precision", "bf16_support", "resolve_precision", "autocast"]


def pick_device(device: str | torch.device | None = None) -> torch.device:
    """The given device, else CUDA when present, else the CPU."""
    if device is not None:
        return torch.device(device)
    return torch.device("cuda" if torch.cuda.is_available() else "cpu")


@functools.cache
def cpu_supports_bf16() -> bool:
    """True when oneDNN has native bf16 kernels on this CPU (AVX-512 BF16 / AMX).

    Without them bf16 convolutions and matmuls are emulated and far slower than fp32.
    """
    try:
        return bool(torch.ops.mkldnn._is_mkldnn_bf16_supported())
    except (AttributeError, RuntimeError):
        return False


def choose_precision(requested: str, device_type: str, *, cuda_bf16: bool = False) -> str:
    """Map "auto" to "bf16", "fp16" or "fp32" from what the device can do (a pure function, testable anywhere).

    On the CPU "auto" is fp32 even where oneDNN has native bf16 kernels (AVX-512 BF16): there the
    ``default`` step ran no faster in bf16 (20.7 against 20.3 it/s, 2 cores, AVX-512 host), and bf16
    kernels sum in an order that depends on the thread layout, so seeds trained side by side would no
    longer train exactly as each seed alone. bf16 on the CPU is there when asked for.

    >>> choose_precision("auto", "cuda", cuda_bf16=False)
    'fp16'
    >>> choose_precision("auto", "cpu")
    'fp32'
    """
    if requested != "auto":
        return requested
    if device_type == "cuda":
        return "bf16" if cuda_bf16 else "fp16"
    return "fp32"


def bf16_support(device: torch.device) -> dict[str, bool]:
    """What ``device`` can do natively, as the ``cuda_bf16`` flag of ``choose_precision``."""
    return {"cuda_bf16": device.type == "cuda" and torch.cuda.is_bf16_supported()}


def resolve_precision(requested: str, device: torch.device) -> str:
    """Map "auto" to a concrete precision for ``device``: "bf16", "fp16" or "fp32"."""
    return choose_precision(requested, device.type, **bf16_support(device))


_DTYPES = {"bf16": torch.bfloat16, "fp16": torch.float16}


def autocast(device: torch.device, precision: str) -> contextlib.AbstractContextManager:
    """The mixed-precision context for network forward passes (losses are computed in fp32)."""
    if precision == "fp32":
        return contextlib.nullcontext()
    return torch.autocast(device_type=device.type, dtype=_DTYPES[precision])
