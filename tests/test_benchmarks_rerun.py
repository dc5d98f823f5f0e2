"""benchmarks/rerun.py on one small scene: the rerun is timed, takes its stack from the cache and needs no torch."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_rerun_benchmark_on_one_scene(tmp_path):
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "rerun.py"), "--scenes", "1", "--size", "128",
                          "--repeats", "1", "--out", str(tmp_path)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-3000:]
    figures = json.loads((tmp_path / "rerun.json").read_text())
    assert figures["warm_torch"] == [False] and figures["warm_origins"] == ["cache"]
    assert figures["per_stack_after_start_up_s"] < figures["warm_s"][0] < figures["cold_s"]
    assert "s a stack" in (tmp_path / "rerun.md").read_text()
