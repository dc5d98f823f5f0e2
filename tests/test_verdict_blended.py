"""The verdict on a tile of copies whose joins were blended (the refinement's gradient-domain band): the
band's texels are placed by inference and judged by their steps against the source's (see
:mod:`seamless_usd.verdict.copies`)."""
from __future__ import annotations

import numpy as np

from seamless_usd.synthesis.refinement.blend import blend_band
from seamless_usd.verdict import judge
from seamless_usd.verdict.copies import COPY_THRESHOLD, continuation, copy_origins
from seamless_usd.verdict.joins import join_stats

SIDE = 64


def _periodic_noise(seed: int, period: int, shape: tuple[int, int]) -> np.ndarray:
    """Smoothish noise repeating every ``period`` texels both ways, tiled to ``shape``."""
    rng = np.random.default_rng(seed)
    base = rng.normal(size=(period, period))
    f = np.fft.fft2(base) / (1.0 + np.hypot(*np.meshgrid(np.fft.fftfreq(period), np.fft.fftfreq(period))) * 12)
    cell = np.real(np.fft.ifft2(f))
    cell = 0.25 * cell / cell.std()
    reps = (-(-shape[0] // period), -(-shape[1] // period))
    return np.tile(cell, reps)[: shape[0], : shape[1]]


def _two_blocks_field(dy: int, dx: int) -> np.ndarray:
    """A 64 x 64 field: columns 0-31 copy from (10 + r, 10 + c), columns 32-63 the same moved by (dy, dx)."""
    r, c = np.meshgrid(np.arange(SIDE), np.arange(SIDE), indexing="ij")
    field = np.stack([r + 10, c + 10], -1)
    field[:, 32:] += np.array([dy, dx])
    return field


def _tone_source(step: float) -> np.ndarray:
    """Noise repeating every 64 texels under a left-to-right tone ramp rising by ``step`` every 64 texels:
    two copies 64 texels apart differ by tone alone."""
    noise = _periodic_noise(1, SIDE, (100, 220))
    ramp = step * np.arange(220)[None, :] / SIDE
    return np.clip(noise + ramp - 0.8, -1, 1)[..., None]


def _unit(source: np.ndarray) -> float:
    return float(np.mean(np.linalg.norm(np.diff(source, axis=1), axis=-1)))


def test_a_blended_bands_origins_are_inferred_from_the_copies_either_side():
    source = _tone_source(0.4)
    field = _two_blocks_field(0, SIDE)
    (tile,), band = blend_band([source], field, 3)
    exact_only, share = copy_origins(tile, source)
    assert share < 0.85  # the band's texels are new values: the lookup alone does not place them
    assert (exact_only[band, 0] < 0).mean() > 0.8
    origin, same_share = copy_origins(tile, source, infer=8)
    assert same_share >= share  # the share is of exact finds only (placed by their exact values)
    # every band texel placed where its own block copies from (or where the source repeats that: it
    # repeats every 64 rows)
    assert np.all(origin[..., 0] >= 0)
    assert np.array_equal(source[origin[..., 0], origin[..., 1]], source[field[..., 0], field[..., 1]])


def test_a_tone_step_spread_over_the_band_is_no_copy_seam_where_the_hard_step_is_but_a_step_of_tone():
    source = _tone_source(0.4)
    unit = _unit(source)
    field = _two_blocks_field(0, SIDE)
    hard = source[field[..., 0], field[..., 1]]
    (soft,), band = blend_band([source], field, 3)
    step = 0.4 / unit  # the tone step at column 32 in units (twice that at the wrap)
    assert 1.5 < step < 2.5
    hard_err = continuation(hard, source, copy_origins(hard, source, 8)[0], 1, unit)
    soft_err = continuation(soft, source, copy_origins(soft, source, 8)[0], 1, unit)
    # copies: the whole step on the join's line, nothing on the others
    assert abs(np.median(hard_err[:, 32]) - step) < 0.1 * step
    assert np.median(hard_err[:, 31]) == 0.0 and np.median(hard_err[:, 35]) == 0.0
    # blended: every line of the band carries a share of it, none more than half the step
    assert np.median(soft_err[:, 32]) < 0.5 * step
    assert np.all(np.median(soft_err[:, 29:36], axis=0) > 0.05 * step)
    assert np.median(soft_err[:, 16]) == 0.0  # away from the band the copies are exact and coherent
    # the continuation error finds the hard step's joins and not the soft one's; both tiles step in tone by
    # 0.4 (a fifth of the range) along their joins, far more than the source's ramp ever does there, which
    # the broad tone rule reads (seamless_usd.verdict.tone)
    for tile, continues in ((hard, False), (soft, True)):
        verdict = judge([tile], [source], [False], ["tone"], fidelity=False)
        assert verdict.method == "copies" and not verdict.seamless
        assert all(s.kind == "tone" for s in verdict.seams) is continues, verdict.reasons()
        assert {s.position for s in verdict.seams if s.kind == "tone"} <= {0, 31, 32, 33}
    hard_joins = join_stats([hard], [source], [False], ["tone"])["maps"]["stack"]["count"]
    soft_joins = join_stats([soft], [source], [False], ["tone"])["maps"]["stack"]["count"]
    assert hard_joins >= 2 and soft_joins == 0


def test_stripes_that_jump_half_a_period_stay_a_seam_when_blended():
    """Horizontal dark lines every 16 rows, the right half copied 8 rows down: the lines jump. Blending
    smears each jump into a ramp; the source has no such step across its columns."""
    y = np.arange(120)[:, None] * np.ones((1, 220))
    stripes = np.where((y % 16) < 3, -0.8, 0.4)
    source = np.clip(stripes + 0.3 * _periodic_noise(2, SIDE, (120, 220)), -1, 1)[..., None]
    field = _two_blocks_field(8, 0)
    hard = source[field[..., 0], field[..., 1]]
    (soft,), band = blend_band([source], field, 3)
    assert band.mean() > 0.15
    for tile in (hard, soft):
        verdict = judge([tile], [source], [False], ["stripes"], fidelity=False)
        assert verdict.method == "copies"
        assert not verdict.seamless
        assert {s.position for s in verdict.seams if s.axis == "x"} & {30, 31, 32, 33, 34}, verdict.reasons()
        assert verdict.strongest > COPY_THRESHOLD + 1.0


def test_a_window_used_as_its_own_tile_is_still_judged_on_its_wrap():
    """Inference must not hide a real wrap seam: the plain window of a non-repeating source."""
    rng = np.random.default_rng(3)
    source = np.cumsum(rng.normal(size=(90, 90, 1)) * 0.05, axis=1).clip(-1, 1)
    tile = source[5:69, 5:69]
    verdict = judge([tile], [source], [False], ["walk"], fidelity=False)
    assert verdict.method == "copies" and not verdict.seamless
