#!/usr/bin/env python3
"""What caps the training step: the speed of each convolution of the ``default`` network, on one thread.

Every convolution a ``default`` training step runs (generator, discriminator and the style loss's
random-feature extractor) is found by running one real step with hooks, then timed alone, forward
and backward (the input gradient, and the weight gradient of trained layers), on one CPU thread. Beside each, the same work as one
matrix product (the im2col GEMM: ``H_out W_out`` x ``C_in k k`` by ``C_in k k`` x ``C_out``; for a
transposed convolution ``H_in W_in`` x ``C_in`` by ``C_in`` x ``C_out k k``) shows
how fast these shapes can run at best, and the 2048² fp32 matmul gives the core's peak.

Writes ``<out>/kernels.json`` and ``<out>/kernels.md``. Run from anywhere::

    .venv/bin/python benchmarks/kernels.py             # about two minutes
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Sequence

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

from steps import StepRunner, load_average, matmul_gflops  # noqa: E402  (sets the OpenMP policy first)
from results_io import write_results  # noqa: E402

import torch  # noqa: E402
from torch import nn  # noqa: E402
from torch.utils.flop_counter import FlopCounterMode  # noqa: E402

from seamless_usd.synthesis import get_preset  # noqa: E402


def step_convolutions(runner: StepRunner) -> list[dict]:
    """Each distinct (layer, input shape) the step's convolutions see, with its calls per step."""
    seen: dict[tuple, dict] = {}
    handles = []
    for net_name, net in (("G", runner.G), ("D", runner.D), ("style", runner.ext)):
        for name, mod in net.named_modules():
            if isinstance(mod, (nn.Conv2d, nn.ConvTranspose2d)):
                def hook(m, inputs, output, label=f"{net_name}.{name}"):
                    key = (label, tuple(inputs[0].shape))
                    entry = seen.setdefault(key, {"layer": label, "module": m, "input": tuple(inputs[0].shape),
                                                  "calls": 0})
                    entry["calls"] += 1
                handles.append(mod.register_forward_hook(hook))
    try:
        runner.step(None)
    finally:
        for h in handles:
            h.remove()
    return list(seen.values())


def _timed(fn, seconds: float) -> float:
    """Seconds per call of ``fn``, after one warm-up call."""
    fn()
    reps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds or reps < 3:
        fn()
        reps += 1
    return (time.perf_counter() - t0) / reps


def time_convolution(entry: dict, seconds: float) -> dict:
    """Forward + backward (weight and input gradients) of one layer on its input shape."""
    mod = entry["module"]
    x = torch.randn(entry["input"], requires_grad=True)
    with torch.no_grad():
        out = mod(x)
    grad = torch.randn_like(out)
    params = [p for p in mod.parameters() if p.requires_grad]  # the style features are frozen

    def fwd_bwd():
        for t in (x, *params):
            t.grad = None
        mod(x).backward(grad)

    with FlopCounterMode(display=False) as fc:
        fwd_bwd()
    flops = fc.get_total_flops()
    t = _timed(fwd_bwd, seconds)
    kind = "convT" if isinstance(mod, nn.ConvTranspose2d) else "conv"
    k, s = mod.kernel_size[0], mod.stride[0]
    out_hw = tuple(out.shape[2:])
    # the forward's work as one GEMM (each gradient is a GEMM of the same size)
    if kind == "conv":  # im2col: (H_out W_out) x (C_in k k) by (C_in k k) x C_out
        gemm_m, gemm_k, gemm_n = out_hw[0] * out_hw[1], mod.in_channels * k * k, mod.out_channels
    else:  # then col2im: (H_in W_in) x C_in by C_in x (C_out k k)
        gemm_m, gemm_k, gemm_n = entry["input"][2] * entry["input"][3], mod.in_channels, mod.out_channels * k * k
    a, b = torch.randn(gemm_m, gemm_k), torch.randn(gemm_k, gemm_n)
    t_gemm = _timed(lambda: a @ b, seconds / 3)
    return {"layer": entry["layer"], "kind": kind, "in": mod.in_channels, "out": mod.out_channels, "kernel": k,
            "stride": s, "input_hw": list(entry["input"][2:]), "calls": entry["calls"],
            "weight_grad": bool(params), "ms": round(t * 1e3, 3), "flops": int(flops), "gflop": round(flops / 1e9, 4),
            "gflops": round(flops / t / 1e9, 1),
            "gemm_shape": [gemm_m, gemm_k, gemm_n], "gemm_gflops": round(2 * gemm_m * gemm_k * gemm_n / t_gemm / 1e9, 1)}


def run(preset: str, seconds: float) -> dict:
    torch.set_num_threads(1)
    load = load_average()
    peak = matmul_gflops(torch.float32)
    runner = StepRunner(get_preset(preset), threads=1)
    for net in (runner.G, runner.D):  # the D step takes D's weight gradients, the G step G's
        net.requires_grad_(True)
    rows = [time_convolution(e, seconds) for e in step_convolutions(runner)]
    step_rate = runner.rate(20)
    conv_ms = sum(r["ms"] * r["calls"] for r in rows)
    conv_gflop = sum(r["gflop"] * r["calls"] for r in rows)
    return {"preset": preset, "threads": 1, "load_start": load, "load_end": load_average(),
            "matmul_peak_gflops": round(peak, 1), "step_it_per_s": round(step_rate, 2),
            "step_ms": round(1e3 / step_rate, 1), "conv_ms_per_step": round(conv_ms, 1),
            "conv_gflop_per_step": round(conv_gflop, 3), "conv_gflops": round(conv_gflop / conv_ms * 1e3, 1),
            "rows": rows}


def to_markdown(r: dict) -> str:
    lines = ["# Convolution speed of one training step", "",
             f"Written by `benchmarks/kernels.py`: preset `{r['preset']}`, one thread, load {r['load_start']:.2f} at "
             f"the start and {r['load_end']:.2f} at the end. fp32 matmul peak on this thread (2048²): "
             f"**{r['matmul_peak_gflops']} GFLOP/s**.", "",
             f"- One training step: {r['step_it_per_s']} it/s, {r['step_ms']} ms.",
             f"- Its convolutions alone, timed layer by layer: {r['conv_ms_per_step']} ms for "
             f"{r['conv_gflop_per_step']} GFLOP, **{r['conv_gflops']} GFLOP/s** "
             f"({r['conv_gflops'] / r['matmul_peak_gflops']:.0%} of the thread's peak). Every call is timed with "
             "the forward, the input gradient and (for trained layers) the weight gradient, so this is an upper "
             "bound: some calls of the step need less (D's weights are frozen in the G step, the targets' style "
             "features need no gradient).",
             f"- So everything else in the step (normalisation, activations, losses, copies, Adam) takes at least "
             f"{r['step_ms'] - r['conv_ms_per_step']:.1f} ms.",
             "- GEMM: the layer's work as one matrix product of the im2col shape (M x K by K x N): the speed "
             "these shapes reach at best.", "",
             "| layer | kind | in -> out | k / stride | input | calls | ms (fwd+bwd) | GFLOP | GFLOP/s | GEMM M x K x N | GEMM GFLOP/s |",
             "|---|---|---|---|---|---:|---:|---:|---:|---|---:|"]
    for x in sorted(r["rows"], key=lambda x: -x["ms"] * x["calls"]):
        lines.append(f"| `{x['layer']}` | {x['kind']} | {x['in']} -> {x['out']} | {x['kernel']} / {x['stride']} | "
                     f"{x['input_hw'][0]}x{x['input_hw'][1]} | {x['calls']} | {x['ms']:.2f} | {x['gflop']:.3f} | "
                     f"{x['gflops']:.1f} | {' x '.join(map(str, x['gemm_shape']))} | {x['gemm_gflops']:.1f} |")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--preset", default="default")
    p.add_argument("--seconds", type=float, default=0.5, help="timing per layer (default: %(default)s s)")
    p.add_argument("--out", type=Path, default=HERE / "results")
    args = p.parse_args(argv)
    result = run(args.preset, args.seconds)
    page = to_markdown(result)
    write_results(args.out, "kernels", page, result)
    print(page)
    return 0


if __name__ == "__main__":
    sys.exit(main())
