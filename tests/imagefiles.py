"""Test helper: write image files exactly as given, with OpenImageIO (no conversion)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio

OIIO_TYPES = {np.uint8: oiio.UINT8, np.uint16: oiio.UINT16, np.float16: oiio.HALF, np.float32: oiio.FLOAT}


def write_raw_image(path: Path, data: np.ndarray, names: tuple[str, ...] | None = None,
                    color_space: str | None = None, icc_profile: bytes | None = None) -> Path:
    """Write ``data`` (H, W) or (H, W, C) as stored; its dtype decides the file's sample type.
    ``color_space`` is recorded as the file's ``oiio:ColorSpace``; ``icc_profile`` embedded."""
    if data.ndim == 2:
        data = data[..., None]
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, OIIO_TYPES[data.dtype.type])
    if names:
        spec.channelnames = names
    spec.attribute("oiio:UnassociatedAlpha", 1)
    if color_space:
        spec.attribute("oiio:ColorSpace", color_space)
    if icc_profile:
        spec.attribute("ICCProfile", oiio.TypeDesc(f"uint8[{len(icc_profile)}]"), np.frombuffer(icc_profile, np.uint8))
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec), out.geterror()
    assert out.write_image(np.ascontiguousarray(data)), out.geterror()
    out.close()
    return Path(path)
