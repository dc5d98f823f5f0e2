"""The verdict on real texture tiles: seams found where they are, none where there are none, and the
fidelity tolerance set by the source's own spread."""
from __future__ import annotations

import importlib
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd.metrics import outside_target, scale_ratio
from seamless_usd.pipeline.stackjob import on_tile_grid
from seamless_usd.verdict import Verdict, faithfulness, judge, scale_tolerance

TEXTURES = Path(__file__).resolve().parent.parent / "sample_assets" / "textures"


@pytest.fixture(scope="module")
def wood() -> np.ndarray:
    """The bundled tileable wood (a whole period of the MaterialX wood, 512 px), halved: network domain."""
    buf = oiio.ImageBuf(str(TEXTURES / "wood_tileable.jpg"))
    a = buf.get_pixels(oiio.FLOAT).reshape(512, 512, 3)
    a = a.reshape(256, 2, 256, 2, 3).mean(axis=(1, 3))  # exact 2 x 2 means: still periodic
    return 2.0 * a - 1.0


def _wrap_window(t: np.ndarray, y: int, x: int, size: int) -> np.ndarray:
    n = t.shape[0]
    return np.take(np.take(t, np.arange(y, y + size) % n, 0), np.arange(x, x + size) % n, 1)


@pytest.fixture(scope="module")
def source(wood) -> np.ndarray:
    """An off-grid window 1.3 periods long: holds every texel of the wood, does not tile."""
    return _wrap_window(wood, 37, 91, 333)


def test_a_tileable_texture_rolled_anywhere_is_seamless(wood, source):
    v = judge([np.roll(wood, (101, 57), (0, 1))], [source], [False], ["wood"])
    assert v.seamless and v.seams == [] and v.passed


def test_the_source_used_as_its_own_tile_is_seamed_at_its_wrap(source):
    window = source[:200, :200]  # not a whole period: its wrap joins texels 200 px apart
    v = judge([window], [source], [False], ["wood"])
    assert not v.passed and not v.seamless
    assert any(s.position == 0 for s in v.seams), [s.as_dict() for s in v.seams]
    assert any("(the wrap)" in r for r in v.reasons())


def test_a_planted_interior_seam_is_found_where_it_is(wood, source):
    tile = np.roll(wood, (11, 23), (0, 1)).copy()
    other = _wrap_window(wood, 140, 200, 256)  # the same wood from elsewhere
    tile[:, 96:160] = other[:, 96:160]  # a strip spliced in: seams at x = 96 and x = 160
    v = judge([tile], [source], [False], ["wood"])
    assert not v.seamless
    xs = sorted(s.position for s in v.seams if s.axis == "x")
    assert any(abs(x - 96) <= 4 for x in xs) and any(abs(x - 160) <= 4 for x in xs), xs
    assert all(s.end - s.start > 64 for s in v.seams if s.axis == "x")  # the splice runs the whole height


def test_a_half_roll_puts_the_seams_on_the_centre_lines(source):
    window = source[:200, :200]
    v = judge([np.roll(window, (100, 100), (0, 1))], [source], [False], ["wood"])
    assert not v.seamless
    assert any(abs(s.position - 100) <= 4 for s in v.seams), [s.as_dict() for s in v.seams]
    assert any("(the centre)" in r for r in v.reasons())


def test_judged_against_itself_a_tileable_texture_passes_and_a_window_does_not(wood, source):
    assert judge([np.roll(wood, (40, 170), (0, 1))], None, [False], ["wood"]).seamless
    v = judge([source[:200, :200]], None, [False], ["wood"])
    assert not v.seamless and v.reference == "itself" and v.figures == {}  # no fidelity without a source


def test_a_seam_in_one_map_of_a_stack_is_named_with_that_map(wood, source):
    grey = wood.mean(axis=-1, keepdims=True)
    tile_grey = np.roll(grey, (5, 9), (0, 1)).copy()
    tile_grey[:, 128:] = np.roll(grey, (90, 150), (0, 1))[:, 128:]  # only the second map is cut at x = 128 and 0
    v = judge([np.roll(wood, (5, 9), (0, 1)), tile_grey], [source, source.mean(-1, keepdims=True)],
              [False, False], ["colour", "grey"], fidelity=False)
    assert not v.seamless
    assert {s.map for s in v.seams} - {"stack"} == {"grey"}


def test_verdict_round_trips_through_its_dict(source):
    v = judge([source[:200, :200]], [source], [False], ["wood"])
    back = Verdict.from_dict(v.as_dict())
    assert back.as_dict() == v.as_dict() and back.passed is False and len(back.reasons()) == len(v.reasons())


# --------------------------------------------------------------------------------------------
# Fidelity tolerances
# --------------------------------------------------------------------------------------------


def test_scale_tolerance_widens_to_the_sources_own_spread():
    # a source whose left half is twice as fine as its right half: its halves read about 2 and 0.5
    rng = np.random.default_rng(0)
    fine = rng.normal(size=(128, 64))
    coarse = np.kron(rng.normal(size=(64, 32)), np.ones((2, 2)))
    low, high = scale_tolerance(np.concatenate([fine, coarse], axis=1))
    assert low < 0.8 and high > 1.25  # far outside the fixed 0.9-1.1
    assert scale_tolerance(rng.normal(size=(128, 128))) == pytest.approx((0.9, 1.1), abs=0.03)


def test_an_unmeasured_figure_is_outside_its_tolerance():
    assert outside_target("scale_ratio", None) and outside_target("patch_distance", None)
    rng = np.random.default_rng(1)
    figures, _, failing = faithfulness([rng.normal(size=(12, 12, 1))], [rng.normal(size=(64, 64, 1))], [False], ["m"])
    assert figures["m"]["scale_ratio"] is None and any("not measured" in f for f in failing)


def test_a_gan_tile_at_the_working_resolution_is_measured_on_its_own_grid():
    # a source with one feature size: random-phase waves 16 px long
    rng = np.random.default_rng(3)
    fy, fx = np.fft.fftfreq(256)[:, None], np.fft.fftfreq(256)[None, :]
    ring = np.abs(np.hypot(fx, fy) - 1 / 16) < 0.01
    source = np.real(np.fft.ifft2(ring * np.exp(2j * np.pi * rng.uniform(size=ring.shape))))
    source = (source / (3 * source.std()))[..., None].astype(np.float32)
    # the pure GAN tile (--refine off) lives on the working grid, a quarter of the source's: waves 4 px long
    working = source.reshape(64, 4, 64, 4, 1).mean(axis=(1, 3))
    tile = np.roll(working, (7, 3), (0, 1))  # as faithful as a tile of the working stack can be
    grid = on_tile_grid([source], [False], tile.shape[:2], (1.0, 1.0))[0]  # one tile covers the UV square
    assert grid.shape[:2] == (64, 64)
    assert scale_ratio(tile, grid) == pytest.approx(1.0, abs=0.15)
    assert scale_ratio(tile, source) > 2.5  # against the full-resolution source: about 4 (the defect)


def test_a_source_judged_again_is_not_refitted_and_gets_the_same_verdict(wood, source):
    """The calibration (classifier and reference) is kept by the content of the image it was fitted on."""
    judge_module = importlib.import_module("seamless_usd.verdict.judge")  # the package exports the function

    tile = np.roll(wood, (11, 23), (0, 1)).copy()
    tile[:, 96:160] = _wrap_window(wood, 140, 200, 256)[:, 96:160]
    tile += np.random.default_rng(3).normal(0, 0.02, tile.shape)  # not source texels: the classifier judges it
    judge_module._CALIBRATIONS.clear()
    first = judge([tile], [source], [False], ["wood"]).as_dict()
    assert len(judge_module._CALIBRATIONS) == 1  # the source's, at the working resolution
    again = judge([tile], [source.copy()], [False], ["wood"]).as_dict()  # equal content, another array
    assert again == first and len(judge_module._CALIBRATIONS) == 1
    nudged = source.copy()
    nudged[5, 5, 0] += 0.25  # one texel differs: another calibration
    judge([tile], [nudged], [False], ["wood"])
    assert len(judge_module._CALIBRATIONS) == 2
    assert first["method"] == "classifier" and not first["seamless"]  # the splice is found
    judge_module._CALIBRATIONS.clear()
    assert judge([tile], [source], [False], ["wood"]).as_dict() == first  # a fresh fit agrees


@pytest.mark.parametrize("periodic", [True, False])
def test_the_classifiers_blur_along_a_line_is_the_binomial_kernel(periodic):
    """[1 2 1] / 4 twice is [1 4 6 4 1] / 16 along the rows, the ends wrapped round or repeated: checked
    against numpy's convolution of the padded columns."""
    from seamless_usd.verdict.classifier import _blur_along

    a = np.random.default_rng(5).standard_normal((9, 4, 2))
    padded = np.pad(a, ((2, 2), (0, 0), (0, 0)), mode="wrap" if periodic else "edge")
    kernel = np.array([1, 4, 6, 4, 1]) / 16
    expected = np.apply_along_axis(lambda col: np.convolve(col, kernel, mode="valid"), 0, padded)
    got = _blur_along(a, periodic)
    if periodic:
        assert np.allclose(got, expected, atol=1e-12)
    else:  # the end row repeated in each pass: the kernel away from the ends, (10 5 1) / 16 at them
        assert np.allclose(got[2:-2], expected[2:-2], atol=1e-12)
        assert np.allclose(got[0], (10 * a[0] + 5 * a[1] + a[2]) / 16, atol=1e-12)
        assert np.allclose(got[-1], (10 * a[-1] + 5 * a[-2] + a[-3]) / 16, atol=1e-12)



def test_a_stack_one_of_whose_maps_was_cut_again_on_its_own_is_judged_as_copies_map_by_map():
    """The bundled brick's lattice cut (three maps), its albedo's right half then slid down 50 rows, the other maps
    left as they were (a written tile edited by hand): the maps together are no longer copies of the source stack,
    and the classifier passed it with its mortar broken at 1x. Each map is still made of its own source's texels, so
    each is judged as copies and the albedo's cuts are found."""
    from seamless_usd.synthesis import MapInput
    from seamless_usd.synthesis.candidates import check_cut

    def read(name: str, channels: int | None = None) -> np.ndarray:
        a = 2.0 * oiio.ImageBuf(str(TEXTURES / name)).get_pixels(oiio.FLOAT) - 1.0
        return a if channels is None else a[..., :channels]

    maps = [MapInput("albedo", read("brick_albedo.png")), MapInput("normal", read("brick_normal.png"), True),
            MapInput("rough", read("brick_roughness.png", 1))]
    cut = check_cut(maps, True)
    tiles, sources = [cut.tiles[m.name] for m in maps], [m.pixels for m in maps]
    normals, names = [m.is_normal for m in maps], [m.name for m in maps]
    assert cut.kind == "lattice" and judge(tiles, sources, normals, names).passed
    moved = tiles[0].copy()
    half = moved.shape[1] // 2
    moved[:, half:] = np.roll(moved[:, half:], 50, 0)
    v = judge([moved, *tiles[1:]], sources, normals, names)
    assert not v.seamless and v.method == "copies", v.reasons()
    assert {s.map for s in v.seams} == {"albedo"} and {s.position for s in v.seams} >= {0, half}
