"""The check timing benchmark, small: its labelled folder and one timed check from the command line."""
from __future__ import annotations

from benchscripts import load_benchmark


def test_check_time_labels_its_folder_and_times_a_check_from_the_command_line(tmp_path):
    bench = load_benchmark("check_time")
    seamless = bench.library(tmp_path / "library", 6)
    pictures = sorted((tmp_path / "library").glob("*.png"))
    assert seamless == 2 and len(pictures) == 6  # every third a whole texture made to tile, rolled
    seconds, payload = bench.timed([str(pictures[0])], 1)  # p0000: whole, seamless by construction
    [item] = payload["items"]
    assert seconds > 0 and item["name"].endswith("p0000.png") and "verdict" in item
