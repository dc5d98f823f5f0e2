"""Training-step figures for ``speed.py``: it/s and crops/s per variant, FLOP/s against the matmul peak,
OpenMP wait policies, torch.compile cold and warm, and a per-op profile. Every figure carries the
1-minute load average read just before it was measured.

Run through ``speed.py``; the ``--_child`` entry points here run in subprocesses (so that the OpenMP
settings and the compile cache can differ between runs).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import seamless_usd.synthesis  # noqa: F401  (first: sets the OpenMP wait policy before torch loads)
import torch  # noqa: E402

from seamless_usd.synthesis import get_preset  # noqa: E402
from seamless_usd.synthesis.config import SynthesisConfig  # noqa: E402
from seamless_usd.synthesis.gan.adam import Adam  # noqa: E402
from seamless_usd.synthesis.gan.engine import CropWorkers, maybe_compile, plan_engine  # noqa: E402
from seamless_usd.synthesis.gan.features import build_feature_extractor  # noqa: E402
from seamless_usd.synthesis.precision import cpu_supports_bf16  # noqa: E402
from seamless_usd.synthesis.gan.step import Batch, StepFunctions, d_loss, g_loss, generate, step_parts, training_step  # noqa: E402
from seamless_usd.synthesis.gan.train import build_networks  # noqa: E402

CHANNELS = [3, 3, 1]  # albedo, normal, roughness
HERE = Path(__file__).resolve().parent


def load_average() -> float:
    return round(os.getloadavg()[0], 2)


def matmul_gflops(dtype: torch.dtype, n: int = 2048, seconds: float = 1.5) -> float:
    a, b = torch.randn(n, n).to(dtype), torch.randn(n, n).to(dtype)
    a @ b
    reps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        a @ b
        reps += 1
    return 2 * n**3 * reps / (time.perf_counter() - t0) / 1e9


class StepRunner:
    """Training steps of one configuration on fixed random crops, run the way ``train`` runs them."""

    def __init__(self, cfg: SynthesisConfig, threads: int):
        self.cfg, self.dev = cfg, torch.device("cpu")
        self.plan = plan_engine(cfg, "cpu", threads=threads)
        self.G, self.D = build_networks(cfg, CHANNELS, seed=0)
        self.ext = build_feature_extractor(cfg)
        self.opt_g = Adam(self.G.parameters(), lr=cfg.lr, betas=cfg.betas)
        self.opt_d = Adam(self.D.parameters(), lr=cfg.lr, betas=cfg.betas)
        self.fns = StepFunctions(*(maybe_compile(f, self.plan) for f in (generate, d_loss, g_loss)))
        k = cfg.k
        g = torch.Generator().manual_seed(0)
        target = torch.rand(cfg.batch, sum(CHANNELS), 2 * k, 2 * k, generator=g) * 2 - 1  # (N, C, 2k, 2k)
        self.batch = Batch(target[:, :, k // 2: k // 2 + k, k // 2: k // 2 + k], target)
        self.steps = 0  # steps run, for the D and style periods (cfg.d_every, cfg.style_every)

    def step(self, workers: CropWorkers | None) -> None:
        update_d, use_style = step_parts(self.cfg, self.steps)
        self.steps += 1
        training_step(self.G, self.D, self.opt_g, self.opt_d, self.ext, self.batch, CHANNELS, self.cfg, self.dev,
                      self.plan.precision, None, workers, self.plan.stacked, self.fns, update_d, use_style)

    def flops(self) -> int:
        """FLOPs of one step (the mean over the D and style periods), counted on this thread (not on workers)."""
        from torch.utils.flop_counter import FlopCounterMode
        self.steps = 0
        period = self.cfg.d_every * self.cfg.style_every
        with FlopCounterMode(display=False) as fc:
            for _ in range(period):
                self.step(None)
        return fc.get_total_flops() // period

    def rate(self, steps: int) -> float:
        with CropWorkers(self.plan) as workers:
            self.step(workers)  # warm-up (oneDNN primitive creation)
            t0 = time.perf_counter()
            for _ in range(steps):
                self.step(workers)
            return steps / (time.perf_counter() - t0)


def step_variants() -> dict[str, tuple[SynthesisConfig, int]]:
    """name -> (config, CPU threads). ``batch 1, 2 intra-op threads`` is how ``default`` trained before the engine."""
    default, draft = get_preset("default"), get_preset("draft")
    return {
        "default (batch 1, auto: 1 thread)": (default, 2),
        "default, batch 1, 2 intra-op threads": (default.replace(workers=1), 2),
        "default net, batch 2, 2 crop workers": (default.replace(batch=2), 2),
        "default net, batch 2, 1 thread": (default.replace(batch=2), 1),
        "default, no style loss (auto)": (default.replace(lambda_style=0.0), 2),
        "default, D every 2nd step (auto)": (default.replace(d_every=2), 2),
        "default, D every 3rd step (auto)": (default.replace(d_every=3), 2),
        "default, resize-conv upsampling (auto)": (default.replace(upsample="resize"), 2),
        "default, style loss every 2nd step (auto)": (default.replace(style_every=2), 2),
        "default, D and style every 2nd step (auto)": (default.replace(d_every=2, style_every=2), 2),
        "draft (auto: 1 thread)": (draft, 2),
        "draft, 2 intra-op threads": (draft.replace(workers=1), 2),
        "paper (2 intra-op threads)": (get_preset("paper"), 2),
    }


def bench_steps(rounds: int, seconds_per_variant: float) -> dict:
    """Variants interleaved in rounds (the machine's speed drifts); medians, FLOP/s and the load at each figure."""
    variants = step_variants()
    runners = {name: StepRunner(cfg, threads) for name, (cfg, threads) in variants.items()}
    flops = {name: r.flops() for name, r in runners.items()}
    rates: dict[str, list[float]] = {name: [] for name in variants}
    loads: dict[str, list[float]] = {name: [] for name in variants}
    peaks: dict[str, list[float]] = {"fp32": [], "bf16": []}
    peak_loads: list[float] = []
    for rnd in range(rounds):
        torch.set_num_threads(2)
        peak_loads.append(load_average())
        peaks["fp32"].append(matmul_gflops(torch.float32))
        peaks["bf16"].append(matmul_gflops(torch.bfloat16, n=512 if not cpu_supports_bf16() else 2048, seconds=0.5))
        for name in variants:
            probe = runners[name].rate(1)
            loads[name].append(load_average())
            rates[name].append(runners[name].rate(max(1, int(seconds_per_variant * probe))))
            print(f"  round {rnd + 1}/{rounds} {name:36s} {rates[name][-1]:7.2f} it/s (load {loads[name][-1]:.2f})",
                  flush=True)
    torch.set_num_threads(2)
    peak32, peak16 = float(np.median(peaks["fp32"])), float(np.median(peaks["bf16"]))
    out = {"precision": runners[next(iter(runners))].plan.precision,
           "matmul_gflops": {"fp32": peaks["fp32"], "bf16": peaks["bf16"]}, "matmul_load": peak_loads, "variants": {}}
    for name, (cfg, threads) in variants.items():
        r = float(np.median(rates[name]))
        gflops = flops[name] * r / 1e9
        out["variants"][name] = {
            "k": cfg.k, "ngf": cfg.ngf, "ndf": cfg.ndf, "res_blocks": cfg.n_res_blocks, "threads": threads,
            "batch": cfg.batch, "engine": runners[name].plan.reason, "lambda_style": cfg.lambda_style,
            "it_per_s": rates[name], "it_per_s_median": r, "crops_per_s_median": r * cfg.batch, "load": loads[name],
            "gflop_per_step": flops[name] / 1e9, "achieved_gflops": gflops,
            "fraction_of_fp32_peak": gflops / peak32, "fraction_of_bf16_peak": gflops / peak16,
            "iterations": cfg.iterations, "train_minutes_at_median": cfg.iterations / r / 60}
    return out


def bench_seeds(rounds: int, steps: int = 40, preset: str = "default") -> dict:
    """Two seeds trained side by side (``config.seeds = 2``): two one-thread runs at once, against one alone.

    it/s per run; the pair's sum is the iterations the two cores deliver for a stack.
    """
    from concurrent.futures import ThreadPoolExecutor

    cfg = get_preset(preset)
    alone, pair, loads = [], [], []
    for _ in range(rounds):
        torch.set_num_threads(1)
        loads.append(load_average())
        alone.append(StepRunner(cfg, 1).rate(steps))
        runners = [StepRunner(cfg, 1), StepRunner(cfg, 1)]
        with ThreadPoolExecutor(2, initializer=torch.set_num_threads, initargs=(1,)) as pool:
            pair.append(list(pool.map(lambda r: r.rate(steps), runners)))
        print(f"  seeds: one run {alone[-1]:.2f} it/s; two side by side {pair[-1][0]:.2f} + {pair[-1][1]:.2f} it/s "
              f"(load {loads[-1]:.2f})", flush=True)
    torch.set_num_threads(2)
    per_run = [float(np.median([p[i] for p in pair])) for i in range(2)]
    return {"preset": preset, "steps": steps, "load": loads, "one_run_it_per_s": alone,
            "one_run_median": float(np.median(alone)), "pair_it_per_s": pair, "pair_median_per_run": per_run,
            "pair_median_sum": sum(per_run)}


def profile_step(name: str = "default (batch 1, auto: 1 thread)", steps: int = 20, top: int = 10) -> dict:
    """Top ops by self CPU time over ``steps`` steps of one variant (one thread: the profiler sees every op)."""
    from torch.profiler import ProfilerActivity, profile
    cfg, threads = step_variants()[name]
    runner = StepRunner(cfg, threads)
    runner.rate(2)
    load = load_average()
    torch.set_num_threads(threads)
    with profile(activities=[ProfilerActivity.CPU]) as prof:
        for _ in range(steps):
            runner.step(None)
    torch.set_num_threads(2)
    events = sorted(prof.key_averages(), key=lambda e: e.self_cpu_time_total, reverse=True)
    total = sum(e.self_cpu_time_total for e in events)
    rows = [{"op": e.key, "self_ms_per_step": e.self_cpu_time_total / 1e3 / steps, "share": e.self_cpu_time_total / total,
             "calls_per_step": e.count / steps} for e in events[:top]]
    return {"variant": name, "steps": steps, "load": load, "step_ms": total / 1e3 / steps, "top": rows}


# --- subprocess entry points ------------------------------------------------------------------------------

def _child(kind: str, preset: str, batch: int, workers: int, threads: int, steps: int) -> None:
    """Print one JSON line: the step rate of ``preset`` (``kind`` "rate"), or compile and steady times ("compile")."""
    cfg = get_preset(preset).replace(batch=batch, workers=workers)
    if kind == "compile":
        cfg = cfg.replace(compile="on")
    torch.set_num_threads(threads)
    runner = StepRunner(cfg, threads)
    t0 = time.perf_counter()
    with CropWorkers(runner.plan) as workers_:
        runner.step(workers_)
    first = time.perf_counter() - t0
    print(json.dumps({"first_step_s": first, "it_per_s": runner.rate(steps), "engine": runner.plan.reason}))


def _run_child(kind: str, preset: str, batch: int, workers: int, threads: int, steps: int,
               env: dict | None = None) -> dict:
    cmd = [sys.executable, str(HERE / "steps.py"), "--_child", kind, preset, str(batch), str(workers), str(threads),
           str(steps)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def bench_wait_policy(rounds: int, preset: str = "default", steps: int = 16) -> dict:
    """Batch 1 on 2 threads under three OpenMP wait settings, 1 thread, and the crop workers; interleaved subprocesses.

    The package sets ``OMP_WAIT_POLICY=PASSIVE`` (sleep at barriers) unless the environment says otherwise;
    libgomp's own default spins for a while first, and ``GOMP_SPINCOUNT`` overrides both.
    """
    variants = {  # name -> (environment, batch, workers, threads)
        "batch 1, 2 threads, PASSIVE (package setting)": ({"OMP_WAIT_POLICY": "PASSIVE"}, 1, 1, 2),
        "batch 1, 2 threads, libgomp default spin": ({"OMP_WAIT_POLICY": "PASSIVE", "GOMP_SPINCOUNT": "300000"}, 1, 1, 2),
        "batch 1, 2 threads, ACTIVE": ({"OMP_WAIT_POLICY": "ACTIVE"}, 1, 1, 2),
        "batch 1, 1 thread": ({"OMP_WAIT_POLICY": "PASSIVE"}, 1, 1, 1),
        "batch 2, 2 crop workers, PASSIVE": ({"OMP_WAIT_POLICY": "PASSIVE"}, 2, 2, 2),
    }
    rates: dict[str, list[float]] = {name: [] for name in variants}
    loads: dict[str, list[float]] = {name: [] for name in variants}
    for _ in range(rounds):
        for name, (extra, batch, workers, threads) in variants.items():
            env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
            loads[name].append(load_average())
            rates[name].append(_run_child("rate", preset, batch, workers, threads, steps, {**env, **extra})["it_per_s"]
                               * batch)
            print(f"  {name}: {rates[name][-1]:.2f} crops/s (load {loads[name][-1]:.2f})", flush=True)
    return {"preset": preset, "crops_per_s": rates, "load": loads,
            "median": {k: float(np.median(v)) for k, v in rates.items()}}


def bench_compile(preset: str = "default", threads: int = 1, steps: int = 30) -> dict:
    """torch.compile with an empty graph cache (cold), then again with the cache the first run filled (warm)."""
    out = {"preset": preset, "threads": threads}
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, TORCHINDUCTOR_CACHE_DIR=cache)
        for run in ("cold", "warm"):
            load = load_average()
            rec = _run_child("compile", preset, get_preset(preset).batch, 0, threads, steps, env)
            out[run] = {**rec, "load": load}
            print(f"  compile {run}: first step {rec['first_step_s']:.1f} s, then {rec['it_per_s']:.2f} it/s "
                  f"(load {load:.2f})", flush=True)
    eager = _run_child("rate", preset, get_preset(preset).batch, 0, threads, steps)
    out["eager"] = {**eager, "load": load_average()}
    print(f"  eager: first step {eager['first_step_s']:.1f} s, then {eager['it_per_s']:.2f} it/s", flush=True)
    return out


if __name__ == "__main__":
    assert sys.argv[1] == "--_child", "run benchmarks/speed.py; this module only holds its step measurements"
    kind, preset = sys.argv[2], sys.argv[3]
    batch, workers, threads, steps = map(int, sys.argv[4:8])
    _child(kind, preset, batch, workers, threads, steps)
