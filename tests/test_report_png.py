import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd.report.png import encode_png


@pytest.mark.parametrize("shape", [(5, 7), (5, 7, 1), (5, 7, 2), (5, 7, 3), (5, 7, 4)])
def test_png_round_trips_through_openimageio(tmp_path, shape):
    rng = np.random.default_rng(0)
    pixels = rng.integers(0, 256, size=shape, dtype=np.uint8)
    path = tmp_path / "p.png"
    path.write_bytes(encode_png(pixels))
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # PNG alpha is straight, keep it so
    back = oiio.ImageBuf(str(path), 0, 0, config).get_pixels(oiio.UINT8)
    assert back.shape[:2] == shape[:2]
    np.testing.assert_array_equal(back.reshape(pixels.shape), pixels)


def test_png_rejects_float_input():
    with pytest.raises(AssertionError, match="uint8"):
        encode_png(np.zeros((2, 2, 3), np.float32))
