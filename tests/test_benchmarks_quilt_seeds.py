"""The quilt-seeds benchmark on two small synthetic items: every seed's worst join is listed, the product's
choice among its first seeds is the one ``best_quilt`` makes, and more seeds never choose a worse join."""
from __future__ import annotations

from benchscripts import load_benchmark


def test_the_quilt_seeds_benchmark_weighs_the_products_seeds_against_more(tmp_path):
    seeds = load_benchmark("quilt_seeds")
    gate = load_benchmark("quilt_gate")
    from seamless_usd.synthesis.lattice.quilt import best_quilt
    from seamless_usd.synthesis.tile import QUILT_CELLS, QUILT_TRIES

    assert seeds.main(["--items", "stripes_160_7,cells_160_6", "--seeds", "5", "--out", str(tmp_path)]) == 0
    md = (tmp_path / "quilt_seeds.md").read_text()
    assert "| stripes_160_7 | 160x160 |" in md and "| cells_160_6 | 160x160 |" in md
    row = seeds.run_item("cells_160_6", 5)
    assert len(row["seeds"]) == 5 and row["all"] <= row["product"] and min(row["seeds"]) <= row["all"] + 0.01
    stack = gate.stack_for("cells_160_6")
    maps = [stack[k][0] for k in stack]
    _, kept = best_quilt(maps, maps[0].shape[:2], QUILT_CELLS, QUILT_TRIES)
    assert row["product"] == kept["difference_worst"]
    assert "Joins hide, best of 3: stripes_160_7." in md  # its quilt passes and was seen seamless (quilt_gate.md)
