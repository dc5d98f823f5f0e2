"""Test helper: the bundled sample textures, read as the network sees them."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def load_texture(name: str) -> np.ndarray:
    """``sample_assets/textures/<name>`` as float32 (H, W, C) in the network domain [-1, 1] (file codes
    scaled, no colour conversion)."""
    pixels = oiio.ImageBuf(str(TEXTURES / name)).get_pixels(oiio.FLOAT)
    return np.ascontiguousarray(pixels * 2.0 - 1.0, dtype=np.float32)
