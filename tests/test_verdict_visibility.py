"""A seam must be seen: on a nearly flat map (a roughness, metallic or opacity map of one value) a row or a patch one
8-bit code value off read millions of units above the map's other lines, all of them exactly flat, and the map was
called seamed; a step of a few code values is still a seam."""
from __future__ import annotations

import numpy as np
import pytest

from seamless_usd.verdict import judge
from seamless_usd.verdict.visibility import VISIBLE, step_across


def _code(value: float) -> float:
    return value / 127.5 - 1.0  # an 8-bit code value in the network domain


def _flat_with_band(step: float) -> np.ndarray:
    m = np.full((256, 256, 1), _code(200.0))
    m[100:110] = _code(200.0 + step)
    return m


def test_a_row_one_code_value_off_on_a_flat_map_is_no_seam():
    verdict = judge([_flat_with_band(1)], None, [False], ["roughness"], fidelity=False)
    assert verdict.seamless and not verdict.seams
    assert verdict.strongest <= verdict.margin  # no figure of millions left over a pass


def test_a_patch_one_code_value_off_in_an_opacity_map_is_no_seam():
    alpha = np.full((256, 256, 1), _code(255.0))
    alpha[60:90, 100:130] = _code(254.0)
    assert judge([alpha], None, [False], ["opacity"], fidelity=False).seamless


def test_a_step_of_a_few_code_values_is_still_read():
    verdict = judge([_flat_with_band(6)], None, [False], ["roughness"], fidelity=False)
    assert not verdict.seamless
    assert {s.position for s in verdict.seams if s.axis == "y"} >= {100, 110}


@pytest.mark.parametrize("codes", [1, 3])
def test_the_step_across_a_line_is_read_in_code_values(codes):
    m = _flat_with_band(codes)
    step = step_across(m, "y", 100, 0, 255)
    assert step == pytest.approx(codes * 2 / 255, rel=1e-6)
    assert (step >= VISIBLE) == (codes >= 2)
    assert step_across(m, "y", 50, 0, 255) == 0.0
