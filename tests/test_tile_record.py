"""What a tile records in its own file about how it was made (``seamless_usd.imaging.tag``): kept by every format
the tool writes tiles in (PNG, OpenEXR, TIFF), and read back as written."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd.imaging.write import write_pixels
from seamless_usd.imaging.tag import read_tag
from seamless_usd.textures import ColorSpace, ImageInfo

RECORD = {"source": "../textures/brick albedo.png", "sha256": "ab" * 32, "stack": ["a.tile.png", "b.tile.png"],
          "map": {"color_space": "sRGB", "roles": [["diffuseColor", "rgb"]], "scale": [1, 1, 1, 1],
                  "bias": [0, 0, 0, 0], "normal_y_flip": False},
          "made": {"uv_scale": [1.0, 1.0], "straightened": 0.0, "levelled": 0.12, "evened": 0.0, "uv_turn": 0.0,
                   "rectified": [0.0, 0.0, 0.0]}}


@pytest.mark.parametrize("ext, fmt, dtype", [(".png", "jpeg", "uint8"), (".png", "png", "uint16"),
                                             (".exr", "openexr", "half"), (".exr", "tiff", "float"),
                                             (".tif", "tiff", "uint16")])
def test_a_tile_keeps_its_record_in_each_format(tmp_path, ext, fmt, dtype):
    like = ImageInfo(width=16, height=16, channels=3, dtype=dtype, file_format=fmt)
    pixels = np.random.default_rng(0).random((16, 16, 3))
    path = write_pixels(tmp_path / f"tile{ext}", pixels, like, ColorSpace.SRGB, RECORD)
    assert read_tag(path) == RECORD
    plain = write_pixels(tmp_path / f"plain{ext}", pixels, like, ColorSpace.SRGB)
    assert read_tag(plain) is None


def test_a_picture_that_only_looks_like_a_tile_is_not_read_as_one(tmp_path):
    """An image description of another tool, a record that is not JSON or lacks its parts: no record."""
    for i, text in enumerate(["a photo of bricks", "seamless-usd madefrom {not json", 'seamless-usd madefrom {"a": 1}']):
        path = tmp_path / f"p{i}.jpg"
        out = oiio.ImageOutput.create(str(path))
        spec = oiio.ImageSpec(8, 8, 3, oiio.UINT8)
        spec.attribute("ImageDescription", text)
        assert out.open(str(path), spec) and out.write_image(np.zeros((8, 8, 3), np.uint8))
        out.close()
        assert read_tag(path) is None
    assert read_tag(tmp_path / "missing.png") is None
