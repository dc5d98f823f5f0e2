"""Evening a drifting lattice: the drift read off a real photo of a tiled floor, every map resampled through one
field, the evened cut that passes where the cut of whole periods jogs its joints, and ``process`` / ``check`` end
to end on that photo."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
from pxr import Usd, UsdShade

from seamless_usd.synthesis.lattice.cut import find_lattice
from seamless_usd.synthesis.lattice.drift import DRIFT_MAX, even_lattice, lattice_drift
from seamless_usd_cli.main import main
from scenes import ground_scene

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))


@pytest.fixture(scope="module")
def floor() -> np.ndarray:
    """A 512 px window of a real photo of white floor tiles (benchmarks/photos, CC0), network domain: its grid
    of joints wanders 2-3 texels from an even spacing across the window."""
    from photos import load_photo

    return load_photo(ROOT / "benchmarks" / "photos" / "tiles_floor_white_1.jpg", 512, window=True)


def test_the_floor_drifts_and_evened_its_lattice_is_even(floor):
    lattice = find_lattice([floor])
    assert lattice.found and all(p is not None for p in lattice.period)
    dy, dx = lattice_drift([floor], lattice.period)
    for d, p in zip((dy, dx), lattice.period):
        inner = d[32:-32, 32:-32]
        assert 1.0 < float(np.ptp(inner)) < DRIFT_MAX * 2 * p, (np.ptp(inner), p)
    (even,), facts = even_lattice([floor], [False], lattice)
    assert 1.0 < facts["moved"] <= DRIFT_MAX * min(lattice.period)
    # the evened floor's lattice is even: its drift is a fraction of what it was (that its cut then passes, where
    # the cut of whole periods of the photo as it is jogs its joints, is the end-to-end test's)
    for before, after in zip((dy, dx), lattice_drift([even], lattice.period)):
        spread = lambda d: float(d[32:-32, 32:-32].std())  # noqa: E731
        assert spread(after) < 0.5 * spread(before), (spread(after), spread(before))


def test_every_map_moves_through_one_field_normals_stay_unit_and_no_lattice_is_left_alone(floor):
    grey = floor.mean(-1, keepdims=True)
    ny, nx = np.gradient(grey[..., 0])
    normal = np.dstack([-4 * nx, 4 * ny, np.ones_like(nx)])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    (colour, grey_out, normal_out), facts = even_lattice([floor, grey, normal.astype(np.float32)],
                                                          [False, False, True])
    assert facts["moved"] > 1.0
    # one field for every map: the grey map moved exactly as the colour map's mean did
    assert np.allclose(grey_out[4:-4, 4:-4], colour.mean(-1, keepdims=True)[4:-4, 4:-4], atol=0.02)
    assert np.allclose(np.linalg.norm(normal_out, axis=-1), 1.0, atol=1e-5)
    assert colour.min() >= floor.min() and colour.max() <= floor.max()  # no overshoot
    gravel = np.random.default_rng(0).uniform(-1, 1, (128, 128, 3)).astype(np.float32)  # nothing repeats
    (same,), none = even_lattice([gravel], [False])
    assert none["moved"] == 0.0 and np.array_equal(same, gravel)


def test_process_evens_the_drifting_floor_records_it_and_check_agrees(tmp_path, capsys, model_cache, floor):
    scene = ground_scene(tmp_path, (floor + 1) / 2, "floor.png", "Floor")
    code = main(["process", str(scene), "--preset", "tiny", "--cache-dir", str(model_cache), "--json",
                 "--report", str(tmp_path / "report.html")])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "passed" and code == 0, stack.get("message")
    facts = stack["resampled"]["evened"]  # tried only where the cut of the photo as it is did not pass
    assert facts["moved"] > 1.0 and stack["resampled"]["gan"]["layout"] == "lattice"
    assert not stack["model_hash"]  # a cut: no GAN trained
    layer = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    prim = layer.GetPrimAtPath("/World/Looks/Floor/diffuseColorTex")
    assert prim.GetAttribute("seamless:evened").Get() == pytest.approx(facts["moved"])
    assert "drifting lattice was evened before the cut" in (tmp_path / "report.html").read_text()
    assert Path(UsdShade.Shader(prim).GetInput("file").Get().resolvedPath).is_file()
    # check judges the tile against its source evened the same way: one answer
    main(["check", str(tmp_path / "scene.seamless.usda"), "--json"])
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert item["verdict"]["passed"]
    assert item["verdict"]["strongest"] == pytest.approx(stack["verdict"]["strongest"], abs=0.05)
