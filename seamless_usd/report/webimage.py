"""Compressed pictures for the HTML report: WebP where OpenImageIO writes it, else JPEG, as data URIs.

The report is one self-contained file, so every picture is embedded. Lossy WebP or JPEG keeps a
page for a 3-map 512 px stack well under 2 MB (PNG previews were about 1 MB per 256 px stack).
Pictures with few flat colours and hard edges (the discriminator map) stay PNG
(:mod:`seamless_usd.report.png`).
"""
from __future__ import annotations

import base64
import functools
import os
import tempfile

import numpy as np

from seamless_usd.report.png import encode_png

__all__ = ["FORMATS", "QUALITY", "MIME", "web_format", "encode_image", "image_data_uri"]

#: Lossy formats in order of preference (first one OpenImageIO can write wins).
FORMATS: tuple[str, ...] = ("webp", "jpeg")

#: Quality of lossy pictures (0-100): block artefacts stay below what a seam looks like.
QUALITY = 85

MIME = {"webp": "image/webp", "jpeg": "image/jpeg", "png": "image/png"}
_EXTENSION = {"webp": "webp", "jpeg": "jpg"}


def _writes(fmt: str) -> bool:
    """Whether this OpenImageIO build writes ``fmt`` (an 8x8 trial image is written and read back)."""
    try:
        data = _encode_oiio(np.full((8, 8, 3), 128, np.uint8), fmt, QUALITY)
    except (ImportError, RuntimeError, OSError):
        return False
    return len(data) > 0


@functools.cache
def web_format() -> str:
    """The lossy format used for report pictures: ``"webp"``, ``"jpeg"``, or ``"png"`` when neither works.

    ``SEAMLESS_USD_REPORT_FORMAT`` (``webp``, ``jpeg`` or ``png``) forces one.
    """
    forced = os.environ.get("SEAMLESS_USD_REPORT_FORMAT", "").strip().lower()
    if forced in ("webp", "jpeg", "png"):
        return forced
    return next((f for f in FORMATS if _writes(f)), "png")


def _rgb(pixels: np.ndarray) -> np.ndarray:
    p = np.asarray(pixels)
    assert p.dtype == np.uint8, f"expected uint8 pixels, got {p.dtype}"
    if p.ndim == 2:
        p = p[..., None]
    assert p.ndim == 3 and 1 <= p.shape[2] <= 4, f"expected (H, W) or (H, W, 1..4), got {p.shape}"
    if p.shape[2] in (1, 2):  # grey (+ alpha): shown as grey
        p = np.repeat(p[..., :1], 3, axis=2)
    return np.ascontiguousarray(p[..., :3])


def _encode_oiio(rgb: np.ndarray, fmt: str, quality: int) -> bytes:
    import OpenImageIO as oiio

    h, w, c = rgb.shape
    spec = oiio.ImageSpec(w, h, c, oiio.UINT8)
    spec.attribute("compression", f"{fmt}:{int(quality)}")
    with tempfile.TemporaryDirectory(prefix="seamless-usd-report-") as folder:
        path = os.path.join(folder, f"picture.{_EXTENSION[fmt]}")
        out = oiio.ImageOutput.create(path)
        if out is None:
            raise RuntimeError(f"OpenImageIO cannot write {fmt}: {oiio.geterror()}")
        ok = out.open(path, spec) and out.write_image(rgb)
        out.close()
        if not ok:
            raise RuntimeError(f"OpenImageIO failed to write {fmt}: {out.geterror()}")
        with open(path, "rb") as f:
            return f.read()


def encode_image(pixels: np.ndarray, fmt: str | None = None, quality: int = QUALITY) -> tuple[str, bytes]:
    """Encode uint8 pixels ``(H, W)`` or ``(H, W, C)`` for the web; returns ``(mime type, bytes)``.

    Parameters
    ----------
    pixels : uint8 array; grey is shown as grey, alpha is dropped for lossy formats.
    fmt : ``"webp"``, ``"jpeg"`` or ``"png"``; default :func:`web_format`.
    quality : lossy quality, 0-100.

    Examples
    --------
    >>> encode_image(np.zeros((4, 4, 3), np.uint8), "png")[0]
    'image/png'
    """
    fmt = fmt or web_format()
    if fmt == "png":
        return MIME["png"], encode_png(np.asarray(pixels))
    if fmt not in _EXTENSION:
        raise ValueError(f"unknown picture format {fmt!r}; valid: webp, jpeg, png")
    return MIME[fmt], _encode_oiio(_rgb(pixels), fmt, quality)


def image_data_uri(pixels: np.ndarray, fmt: str | None = None, quality: int = QUALITY) -> str:
    """``data:`` URI of :func:`encode_image`'s result, for an ``<img src>``."""
    mime, data = encode_image(pixels, fmt, quality)
    return f"data:{mime};base64," + base64.b64encode(data).decode("ascii")
