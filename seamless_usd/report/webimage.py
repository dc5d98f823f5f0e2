"""Compressed pictures for the HTML report: WebP where it can be written, else JPEG, as data URIs.

The report is one self-contained file, so every picture is embedded. Lossy WebP or JPEG keeps a
page for a 3-map 512 px stack well under 2 MB (PNG previews were about 1 MB per 256 px stack).
Pictures with few flat colours and hard edges (the discriminator map) stay PNG
(:mod:`seamless_usd.report.png`).
"""
from __future__ import annotations

import base64
import functools
import io
import os
import tempfile

import numpy as np

from seamless_usd.report.png import encode_png

__all__ = ["FORMATS", "QUALITY", "MIME", "web_format", "encode_image", "image_data_uri"]

#: Lossy formats in order of preference (first one OpenImageIO can write wins).
FORMATS: tuple[str, ...] = ("webp", "jpeg")

#: Quality of lossy pictures (0-100): block artefacts stay below what a seam looks like.
QUALITY = 85

#: libwebp's effort for WebP (0-6): its own default. OpenImageIO's WebP writer always uses 6, which took
#: 62 ms for a 384 px texture picture against 17 ms here, for files 8 % smaller; Pillow writes WebP
#: with the effort chosen (OpenImageIO stays the writer when Pillow lacks WebP, and for JPEG).
WEBP_METHOD = 4

MIME = {"webp": "image/webp", "jpeg": "image/jpeg", "png": "image/png"}
_EXTENSION = {"webp": "webp", "jpeg": "jpg"}


def _writes(fmt: str) -> bool:
    """Whether ``fmt`` can be written here (an 8x8 trial image is encoded)."""
    try:
        data = _encode_lossy(np.full((8, 8, 3), 128, np.uint8), fmt, QUALITY)
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


def _encode_pillow_webp(rgb: np.ndarray, quality: int) -> bytes | None:
    """WebP at :data:`WEBP_METHOD` through Pillow; None when Pillow has no WebP."""
    try:
        from PIL import Image, features
    except ImportError:
        return None
    if not features.check("webp"):
        return None
    buf = io.BytesIO()
    Image.fromarray(rgb, "RGB").save(buf, "WEBP", quality=int(quality), method=WEBP_METHOD)
    return buf.getvalue()


def _encode_lossy(rgb: np.ndarray, fmt: str, quality: int) -> bytes:
    if fmt == "webp":
        data = _encode_pillow_webp(rgb, quality)
        if data is not None:
            return data
    return _encode_oiio(rgb, fmt, quality)


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
    return MIME[fmt], _encode_lossy(_rgb(pixels), fmt, quality)


def image_data_uri(pixels: np.ndarray, fmt: str | None = None, quality: int = QUALITY) -> str:
    """``data:`` URI of :func:`encode_image`'s result, for an ``<img src>``."""
    mime, data = encode_image(pixels, fmt, quality)
    return f"data:{mime};base64," + base64.b64encode(data).decode("ascii")
