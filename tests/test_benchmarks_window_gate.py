"""The window-gate experiment (benchmarks/experiments/window_gate.py) runs on the bundled samples: the weave's
window is offered, the wood's is not."""
from __future__ import annotations

import json

from benchscripts import load_benchmark


def test_the_window_gate_benchmark_offers_the_weave_and_not_the_wood(tmp_path):
    gate = load_benchmark("experiments/window_gate")
    assert gate.main(["--items", "cloth,wood", "--out", str(tmp_path)]) == 0
    rows = {r["item"]: r for r in json.loads((tmp_path / "window_gate.json").read_text())}
    assert rows["cloth"]["offered"] and rows["cloth"]["seamless_by_eye"]
    assert not rows["wood"]["offered"] and not rows["wood"]["seamless_by_eye"]
    assert max(rows["wood"]["lag_difference"].values()) > 0.3 > max(rows["cloth"]["lag_difference"].values())
    for name in rows:  # the pictures the labels were given from
        assert (tmp_path / "window_gate" / f"{name}.jpg").stat().st_size > 1000
    md = (tmp_path / "window_gate.md").read_text()
    assert "| cloth | tuning | 160x160 |" in md and "| tuning | 2 | 2/2 |" in md
