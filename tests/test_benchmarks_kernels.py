"""The convolution benchmark finds the step's layers and counts their work right."""
from __future__ import annotations

import json
import time

from benchscripts import load_benchmark


def test_every_convolution_of_a_step_is_timed_with_its_work(tmp_path):
    k = load_benchmark("kernels")
    began = time.perf_counter()
    assert k.main(["--preset", "tiny", "--seconds", "0.01", "--out", str(tmp_path)]) == 0
    wall_ms = (time.perf_counter() - began) * 1e3
    data = json.loads((tmp_path / "kernels.json").read_text())
    rows = data["rows"]
    nets = {r["layer"].split(".")[0] for r in rows}
    assert nets == {"G", "D", "style"}
    peak = data["matmul_peak_gflops"]
    for r in rows:  # a time per call that fits in the run, for work no faster than a few times the matmul peak
        assert r["calls"] >= 1 and r["calls"] * r["ms"] <= wall_ms, r
        assert r["flops"] / (r["ms"] * 1e6) <= 4 * peak, (r, peak)
    assert any(r["kind"] == "convT" for r in rows)  # the decoders' transposed convolutions
    for r in rows:
        m, kk, n = r["gemm_shape"]
        gemm = 2 * m * kk * n  # the forward's multiply-adds
        grads = 2 if r["weight_grad"] else 1  # the input gradient, and the weight gradient of trained layers
        assert abs(r["flops"] - (1 + grads) * gemm) <= 0.02 * (1 + grads) * gemm, r
    assert not any(r["weight_grad"] for r in rows if r["layer"].startswith("style."))  # frozen random features
    assert data["conv_ms_per_step"] > 0 and 0 < data["conv_gflops"] < 10 * data["matmul_peak_gflops"]
