"""The GAN-layout experiment (benchmarks/experiments/gan_layout.py) runs end to end on a bundled sample with the
test preset."""
from __future__ import annotations

import json

from benchscripts import load_benchmark


def test_the_gan_layout_benchmark_prints_its_figures_and_writes_its_picture(tmp_path, capsys, one_thread):
    gan = load_benchmark("experiments/gan_layout")
    assert gan.main(["--stack", "cloth", "--preset", "tiny", "--iterations", "4", "--out", str(tmp_path)]) == 0
    row = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert row["stack"] == "cloth" and row["iterations"] == 4 and row["layout_structure"] > 0
    assert set(row["layout_scale"]) == {"color"} and row["written"] in ("gan", "random", "lattice", "window", "quilt")
    assert (tmp_path / "gan_layout_cloth_4.jpg").stat().st_size > 1000
