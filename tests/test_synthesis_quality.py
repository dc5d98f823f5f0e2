"""Quality function Q and the crop-size search."""
from dataclasses import replace

import numpy as np
import pytest

from seamless_usd.synthesis import MapInput, get_preset, sample, train
from seamless_usd.synthesis.gan.quality import band_masks, quality
from seamless_usd.synthesis.gan.sample import crop_plan


pytestmark = pytest.mark.usefixtures("one_thread")  # tiny networks: fastest and steadiest on one thread


def test_bands_are_20_percent_through_the_centre():
    v, h = band_masks(20, 30)
    assert v.sum(1).tolist() == [6] * 20 and v[0, 12:18].all()
    assert h.sum(0).tolist() == [4] * 30 and h[8:12, 0].all()


def test_q_passes_when_the_bands_are_as_real_as_the_rest():
    d = np.full((20, 20), 0.8)
    d[0, 0] = 0.3  # the weakest patch lies outside the bands
    d[10, :] = 0.5  # a slightly darker seam, still above tau
    q = quality(d)
    assert q.passed and q.tau == pytest.approx(0.3) and q.band_min_horizontal == pytest.approx(0.5)


def test_q_fails_on_a_seam_the_discriminator_sees():
    d = np.full((20, 20), 0.8)
    d[:, 10] = 0.1  # vertical seam through the centre
    q = quality(d)
    assert not q.passed and q.band_min_vertical == pytest.approx(0.1) and q.tau == pytest.approx(0.8)
    assert q.margin < 0
    assert not quality(np.full((20, 20), 0.5), gamma=1.5).passed  # gamma scales tau


def test_crop_plan_one_whole_crop_then_three_per_size():
    cfg = get_preset("tiny").replace(c_min=100, crop_step=50, max_candidates=None)
    plan = list(crop_plan(200, 300, cfg, seed=0))
    sizes = [s for s, _ in plan]
    assert plan[0] == ((200, 300), (0, 0))
    assert sizes[1:4] == [(164, 248)] * 3 and sizes[4:7] == [(132, 200)] * 3  # multiples of 4
    assert min(min(s) for s in sizes) >= 100 and len(plan) == 1 + 3 * 3
    assert all(y + ch <= 200 and x + cw <= 300 for (ch, cw), (y, x) in plan)


@pytest.fixture(scope="module")
def trained():
    """A model shared by the module; tests change a copy's config, never this one."""
    rng = np.random.default_rng(0)
    maps = [MapInput("albedo", rng.uniform(-1, 1, (64, 64, 3)).astype(np.float32))]
    return train(maps, get_preset("tiny")), maps



def test_search_stops_at_the_first_pass(trained):
    trained_model, maps = trained
    model = replace(trained_model, config=trained_model.config.replace(gamma=0.0))  # tau = 0: every candidate passes
    result = sample(model, maps)
    assert result.q_passed and len(result.candidates) == 1 and result.crop_size == (64, 64)


def test_search_keeps_the_best_failing_candidate(trained):
    trained_model, maps = trained
    model = replace(trained_model, config=trained_model.config.replace(gamma=10.0, max_candidates=5))  # tau above any probability
    result = sample(model, maps)
    assert not result.q_passed and len(result.candidates) == 5
    best = max(result.candidates, key=lambda c: c.q.margin)
    assert result.q is best.q and result.crop_size == best.crop_size


def test_the_shared_model_keeps_its_config(trained):
    """Runs after the tests that sample with changed configs: they worked on copies."""
    model, _ = trained
    assert model.config == get_preset("tiny")
