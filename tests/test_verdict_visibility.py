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


def _seamed_photo(scale: float) -> np.ndarray:
    """A real photo's luminance (the sample wood), a window of it that does not wrap, rolled by half so its seams run
    through the middle, as a height map spanning ``scale`` about zero (network units where 8 bits span 2)."""
    from pathlib import Path

    import OpenImageIO as oiio

    path = Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "wood_color.png"
    grey = oiio.ImageBuf(str(path)).get_pixels(oiio.FLOAT)[..., :3].mean(axis=-1)
    window = grey[:192, :192]
    rolled = np.roll(window, (96, 96), axis=(0, 1))
    return (scale * (rolled - rolled.mean()) / np.ptp(rolled))[..., None]


@pytest.mark.parametrize("scale", [0.004, 0.02])
def test_a_seam_in_a_float_height_map_of_small_span_is_seen(scale):
    """A displacement map in scene units spans a centimetre (0.01 of a float): against 8-bit codes it is flat and its
    seam read as nothing, though the shader's scale shows it. Stored finer than 8 bits, its floor is its own span's."""
    m = _seamed_photo(scale)
    assert judge([m], None, [False], ["height"], fidelity=False).seamless  # read as if stored in 8 bits
    float_verdict = judge([m], None, [False], ["height"], fidelity=False, codes=[0.0])
    assert not float_verdict.seamless
    assert {s.position for s in float_verdict.seams} & {95, 96, 97}
    assert judge([m * 100], None, [False], ["height"], fidelity=False, codes=[0.0]).seamless == float_verdict.seamless


def test_a_band_one_code_value_off_in_a_flat_16_bit_map_is_still_no_seam():
    code = 2 / 65535
    m = np.full((256, 256, 1), 0.2)
    m[100:110] += code
    assert judge([m], None, [False], ["roughness"], fidelity=False, codes=[code]).seamless
    m[100:110] += 4 * code  # a step the file holds many of: the floor is the map's own span
    verdict = judge([m], None, [False], ["roughness"], fidelity=False, codes=[code])
    assert not verdict.seamless and {s.position for s in verdict.seams if s.axis == "y"} >= {100, 110}


def test_check_sees_the_seam_of_a_float_displacement_file_spanning_a_centimetre(tmp_path):
    import OpenImageIO as oiio

    from seamless_usd.pipeline.check import check_paths

    values = (_seamed_photo(0.02) / 2).astype(np.float32)  # file values: +-0.005 about zero
    for name, kind in (("disp.exr", oiio.FLOAT), ("disp_half.exr", oiio.HALF)):
        out = oiio.ImageOutput.create(str(tmp_path / name))
        assert out.open(str(tmp_path / name), oiio.ImageSpec(192, 192, 1, kind)) and out.write_image(values)
        out.close()
    items = check_paths([tmp_path / "disp.exr", tmp_path / "disp_half.exr"]).items
    assert [i.passed for i in items] == [False, False], [i.verdict for i in items]
