"""The GPU benchmark, run on the CPU with the tiny preset: the GAN path end to end and its figures."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from benchscripts import load_benchmark

SHARED = Path(__file__).resolve().parents[2] / "shared" / "textures"


@pytest.mark.skipif(not (SHARED / "brick_base_gray.jpg").is_file(), reason="needs ../shared/textures")
def test_the_gpu_benchmark_trains_samples_and_refines_on_the_cpu(capsys, tmp_path):
    bench = load_benchmark("gpu")
    assert bench.main(["--preset", "tiny", "--iterations", "6", "--size", "128", "--device", "cpu",
                       "--out", str(tmp_path)]) == 0
    figures = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert figures["device"].startswith("cpu") and figures["precision"] == "fp32" and figures["compiled"] is False
    assert figures["iterations"] == 6 and figures["full_run_iterations"] == 4 and figures["it_per_s"] > 0
    assert {"train", "sample", "refine"} <= set(figures["stages_s"])  # the GAN path, not the cut
    assert figures["gan_crop"] is not None and figures["tile"] == [128, 128] and figures["peak_gib"] > 0
    assert json.loads((tmp_path / "gpu_tiny_128.json").read_text()) == figures
    assert (tmp_path / "gpu_tiny_128.png").stat().st_size > 1000


def test_the_steady_rate_leaves_out_the_first_half():
    bench = load_benchmark("gpu")
    # a slow start (compilation) then 100 it/s: the rate is the second half's
    assert bench.steady_rate([(10, 30.0), (20, 30.1), (30, 30.2), (40, 30.3)]) == pytest.approx(100.0)
    assert bench.steady_rate([(4, 2.0)]) == pytest.approx(2.0)
    assert bench.steady_rate([]) == 0.0


def test_a_missing_texture_folder_is_named(tmp_path):
    bench = load_benchmark("gpu")
    with pytest.raises(SystemExit, match="brick_base_gray.jpg is missing"):
        bench.load_stack(tmp_path, 64)
