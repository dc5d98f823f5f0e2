"""A minimal PNG encoder for report previews (8-bit grey, grey+alpha, RGB or RGBA).

Previews are embedded in the self-contained HTML report as data URIs; encoding them here keeps
the report free of temporary files.
"""
from __future__ import annotations

import base64
import struct
import zlib

import numpy as np

__all__ = ["encode_png", "png_data_uri"]

_COLOR_TYPE = {1: 0, 2: 4, 3: 2, 4: 6}  # channels -> PNG colour type


def _chunk(kind: bytes, data: bytes) -> bytes:
    crc = zlib.crc32(kind + data) & 0xFFFFFFFF
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)


def encode_png(pixels: np.ndarray) -> bytes:
    """Encode a uint8 array (H, W) or (H, W, C) with C in 1..4 as PNG bytes.

    >>> encode_png(np.zeros((2, 3), np.uint8))[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
    True
    """
    if pixels.ndim == 2:
        pixels = pixels[..., None]
    assert pixels.ndim == 3 and pixels.shape[2] in _COLOR_TYPE, f"expected (H, W, 1..4), got {pixels.shape}"
    assert pixels.dtype == np.uint8, f"expected uint8 pixels, got {pixels.dtype}"
    h, w, c = pixels.shape
    rows = np.concatenate([np.zeros((h, 1), np.uint8), pixels.reshape(h, w * c)], axis=1)
    header = struct.pack(">IIBBBBB", w, h, 8, _COLOR_TYPE[c], 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
        + _chunk(b"IEND", b"")
    )


def png_data_uri(pixels: np.ndarray) -> str:
    return "data:image/png;base64," + base64.b64encode(encode_png(pixels)).decode("ascii")
