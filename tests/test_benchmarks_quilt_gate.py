"""The quilt-gate experiment (benchmarks/experiments/quilt_gate.py) on two small synthetic items: the stripes'
quilt hides its joins and passes, the stones' quilt passes the verdict with two-tone stones and is not written
as passed."""
from __future__ import annotations

import json

from benchscripts import load_benchmark


def test_the_quilt_gate_benchmark_tells_hidden_joins_from_false_passes(tmp_path):
    gate = load_benchmark("experiments/quilt_gate")
    assert gate.main(["--items", "stripes_160_7,cells_256_2", "--out", str(tmp_path)]) == 0
    rows = {r["item"]: r for r in json.loads((tmp_path / "quilt_gate.json").read_text())}
    assert set(rows) == {"stripes_160_7/difference", "stripes_160_7/lines", "cells_256_2/difference", "cells_256_2/lines"}
    clean, false_pass = rows["stripes_160_7/difference"], rows["cells_256_2/difference"]
    assert clean["verdict_passed"] and clean["hides"] and clean["seamless_by_eye"]
    assert false_pass["verdict_passed"] and not false_pass["hides"] and false_pass["seamless_by_eye"] is False
    for item in rows:  # the pictures the labels were given from
        assert (tmp_path / "quilt_gate" / f"{item.replace('/', '__')}.jpg").stat().st_size > 1000
    md = (tmp_path / "quilt_gate.md").read_text()
    assert "Passed with seams: 1 without the gate, 0 with it (written as passed: 1" in md
