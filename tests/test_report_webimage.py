"""The report's pictures: lossy WebP (through Pillow, at libwebp's default effort) or JPEG that decodes back
to the picture."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio
import pytest

from seamless_usd.report import webimage

SAMPLE = "sample_assets/textures/brick_albedo.png"


def _picture() -> np.ndarray:
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / SAMPLE
    pixels = oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)[..., :3]
    return np.ascontiguousarray(np.tile(pixels, (2, 2, 1))[:384, :384])


def _decode(data: bytes, suffix: str, tmp_path) -> np.ndarray:
    path = tmp_path / f"picture.{suffix}"
    path.write_bytes(data)
    return oiio.ImageBuf(str(path)).get_pixels(oiio.UINT8)[..., :3]


@pytest.mark.parametrize("fmt,suffix,magic", [("webp", "webp", b"RIFF"), ("jpeg", "jpg", b"\xff\xd8")])
def test_a_picture_decodes_back_close_to_itself(fmt, suffix, magic, tmp_path):
    picture = _picture()
    mime, data = webimage.encode_image(picture, fmt)
    assert mime == webimage.MIME[fmt] and data[: len(magic)] == magic
    back = _decode(data, suffix, tmp_path).astype(np.int16)
    assert back.shape == picture.shape
    assert np.abs(back - picture).mean() < 6  # quality 85: a few codes, not a different picture
    assert len(data) < picture.nbytes / 4  # and compressed
