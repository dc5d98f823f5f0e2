"""The tone lever's benchmark on the bundled brick sample: levelled, its texels are no longer copies the
verdict can place, which is why the lever is not kept."""
from __future__ import annotations

import json

from benchscripts import load_benchmark


def test_levelling_the_tone_leaves_the_verdict_few_copies_to_place(tmp_path):
    tone = load_benchmark("lattice_tone")
    assert tone.main(["--items", "brick", "--out", str(tmp_path)]) == 0
    row = json.loads((tmp_path / "lattice_tone.json").read_text())["rows"][0]
    assert row["cut"] == "lattice" and row["plain"]["passed"]
    assert row["plain"]["changed"] == 0 and row["plain"]["placed"] > 0.99
    assert row["matched"]["changed"] > 0.9 and row["matched"]["placed"] < 0.5
    assert (tmp_path / "lattice_tone" / "brick.jpg").stat().st_size > 1000
    assert "| brick | lattice |" in (tmp_path / "lattice_tone.md").read_text()
