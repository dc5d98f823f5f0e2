"""The straightening benchmark, small: a photo's orientation row and the table written from rows."""
from __future__ import annotations

from benchscripts import load_benchmark


def test_a_stochastic_photo_reads_no_turn_and_the_table_names_every_photo_turned():
    bench = load_benchmark("straighten")
    gravel = bench.photo_row(bench.HERE / "photos" / "gravel_1.jpg")
    assert gravel["photo"] == "gravel_1.jpg" and not gravel["straightens"] and gravel["strength"] < 6
    floor = bench.photo_row(bench.HERE / "photos" / "tiles_floor_white_1.jpg")
    assert abs(floor["degrees"]) < 0.5 and floor["strength"] > 100 and not floor["straightens"]
    cut = {"kind": "lattice", "passed": True, "strongest": 0.4, "seconds": 1.0}
    stack = {"stack": "rot23_brick_2048", "size": [2048, 2048], "truth": -23.0, "degrees": -23.0, "strength": 60.0,
             "straighten_s": 8.0, "straightened_size": [1555, 1555], "as_is": {"kind": None, "seconds": 2.0},
             "straightened": cut}
    turned = {**gravel, "photo": "deck.jpg", "degrees": 31.0, "strength": 12.0, "straightens": True}
    table = bench.markdown([stack], [gravel, turned], (0.5, 1.0))
    assert "| rot23_brick_2048 | 2048x2048 | -23 | -23 | 60 |" in table
    assert "no cut" in table and "lattice passed 0.40, 1.0 s" in table
    assert "1 of 2 would be turned: deck.jpg (31 degrees, strength 12)" in table
