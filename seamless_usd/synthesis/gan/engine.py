"""How a training run uses the hardware: precision, crop workers, threads and graph compilation.

``plan_engine`` is a pure function of the config and of what the device can do, so the choice made
for a GPU can be checked on a machine without one. ``CropWorkers`` runs the crops of one step in
parallel on CPU threads.

Figures behind the choices (``benchmarks/results/speed.md``, 2-core AVX2 host, ``default`` network):
one crop per step runs at 8.2 it/s on one thread and at 5.0 it/s on two intra-op threads whose OpenMP
workers sleep at barriers (the package's setting, which a busy machine needs), so a single crop of a
small network gets one thread. With several crops per step each core takes whole crops: 13.5 crops/s
on two threads against 7.8 on one. ``torch.compile`` made the CPU step no faster (6.5 against 6.8
it/s) for 118 s of cold compilation (6 s warm), so the CPU path runs eagerly unless asked.
"""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, TypeVar

import torch

from ..config import SynthesisConfig
from ..precision import bf16_support, choose_precision

__all__ = ["EnginePlan", "plan_engine", "engine_for", "CropWorkers", "compile_cache_dir", "maybe_compile"]

SMALL_NGF = 32  # generators this narrow (<= 64-channel convolutions) run faster on one thread than on two
R = TypeVar("R")


@dataclass(frozen=True)
class EnginePlan:
    """What one training run does with the device; ``reason`` says why, for logs and the report."""

    device_type: str  # "cpu" or "cuda"
    precision: str  # "fp32", "bf16" or "fp16"
    workers: int  # CPU threads that each compute whole crops of a step (1: crops run one after another)
    intra_threads: int  # torch intra-op threads per worker while training
    stacked: bool  # the crops of a step go through the networks as one (N, C, H, W) batch (GPU)
    compile: bool  # forward passes through torch.compile (backward compiled by AOTAutograd)
    grad_scaler: bool  # fp16 needs loss scaling
    reason: str


def plan_engine(config: SynthesisConfig, device_type: str, *, threads: int, cuda_bf16: bool = False) -> EnginePlan:
    """The engine for ``config`` on a ``device_type`` device.

    ``threads`` is the CPU thread budget (``torch.get_num_threads()``: 1 inside a one-thread batch worker),
    ``cuda_bf16`` whether the GPU can do bf16 natively.

    >>> plan_engine(SynthesisConfig(batch=2), "cpu", threads=2).workers
    2
    >>> p = plan_engine(SynthesisConfig(batch=2), "cuda", threads=2, cuda_bf16=True)
    >>> (p.precision, p.stacked, p.compile)
    ('bf16', True, True)
    """
    assert device_type in ("cpu", "cuda"), f"unknown device type {device_type!r}"
    precision = choose_precision(config.precision, device_type, cuda_bf16=cuda_bf16)
    threads = max(1, int(threads))
    if device_type == "cuda":
        compile_ = config.compile != "off"
        return EnginePlan("cuda", precision, 1, threads, True, compile_, precision == "fp16",
                          f"GPU: {config.batch} crop(s) as one batch, {precision} autocast"
                          + (", compiled" if compile_ else ""))
    compile_ = config.compile == "on"
    if compile_:  # compiled graphs are not shared between Python threads: one worker, crops stacked
        return EnginePlan("cpu", precision, 1, threads, True, True, precision == "fp16",
                          f"CPU: {config.batch} crop(s) as one compiled batch on {threads} thread(s)")
    wanted = config.workers or config.batch
    workers = max(1, min(wanted, config.batch, threads))
    intra = max(1, threads // workers)
    if workers == 1 and config.workers == 0 and config.ngf <= SMALL_NGF:
        intra = 1  # one thread beats two on these small convolutions (default 8.2 vs 5.0 it/s, draft 15.7 vs 5.6)
    if workers == 1:
        reason = f"CPU: {config.batch} crop(s) one after another on {intra} thread(s)"
    else:
        reason = f"CPU: {config.batch} crops on {workers} worker threads, {intra} intra-op thread(s) each"
    return EnginePlan("cpu", precision, workers, intra, False, False, precision == "fp16", reason)


def engine_for(config: SynthesisConfig, device: torch.device) -> EnginePlan:
    """``plan_engine`` with what this machine's device really supports."""
    return plan_engine(config, device.type, threads=torch.get_num_threads(), **bf16_support(device))


class CropWorkers:
    """Runs one function over the crops of a step, on ``plan.workers`` threads; results in crop order.

    Each worker thread (and the calling thread, while the pool is open) uses ``plan.intra_threads``
    intra-op threads; the caller's setting comes back on ``close``.
    """

    def __init__(self, plan: EnginePlan):
        self.plan = plan
        self._before = torch.get_num_threads()
        self._pool: ThreadPoolExecutor | None = None
        if plan.device_type == "cpu":
            torch.set_num_threads(plan.intra_threads)
        if plan.workers > 1:
            intra = plan.intra_threads
            self._pool = ThreadPoolExecutor(plan.workers, thread_name_prefix="seamless-crop",
                                            initializer=torch.set_num_threads, initargs=(intra,))

    def map(self, fn: Callable[..., R], *items: Iterable) -> list[R]:
        if self._pool is None:
            return list(map(fn, *items))
        return list(self._pool.map(fn, *items))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None
        if self.plan.device_type == "cpu":
            torch.set_num_threads(self._before)

    def __enter__(self) -> "CropWorkers":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def compile_cache_dir() -> Path:
    """Where compiled graphs are kept between runs: ``$TORCHINDUCTOR_CACHE_DIR`` if set, else the user cache."""
    if os.environ.get("TORCHINDUCTOR_CACHE_DIR"):
        return Path(os.environ["TORCHINDUCTOR_CACHE_DIR"])
    base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "seamless-usd" / "torch-compile"


def maybe_compile(fn: Callable[..., R], plan: EnginePlan) -> Callable[..., R]:
    """``fn`` itself, or ``torch.compile(fn)`` with the on-disk graph cache, so a second run skips the compile."""
    if not plan.compile:
        return fn
    path = compile_cache_dir()
    path.mkdir(parents=True, exist_ok=True)
    os.environ.setdefault("TORCHINDUCTOR_CACHE_DIR", str(path))  # read by inductor when it first compiles
    import torch._dynamo.config as dynamo_config
    import torch._inductor.config as inductor_config
    inductor_config.fx_graph_cache = True
    dynamo_config.suppress_errors = True  # a graph the backend cannot compile (no compiler, no Triton) runs eagerly
    return torch.compile(fn, dynamic=False)
