"""Image headers without pixels: size, channels, bit depth, format and stated colour space.

Files inside ``.usdz`` packages are read through Ar (the USD asset resolver); OpenImageIO reads
only the header. ``oiio:ColorSpace`` is a guess for some formats (OpenImageIO calls every PNG and
JPEG sRGB), so the colour space a file *states* is read from the PNG chunks themselves and only
trusted from OpenImageIO for formats that store it.
"""
from __future__ import annotations

import io
import os
import re
import tempfile
from pathlib import Path

import OpenImageIO as oiio
from pxr import Ar

from seamless_usd.discover.tokens import TILE_TOKENS, tile_token
from seamless_usd.textures import ImageInfo
from seamless_usd.pngchunks import png_stated_color_space

__all__ = ["IMAGE_SUFFIXES", "read_image_info", "is_package_path", "udim_tiles", "ImageReadError"]

#: The file suffixes read as pictures (``check`` on a folder, and a picture given where a stage is wanted).
IMAGE_SUFFIXES = frozenset({".png", ".jpg", ".jpeg", ".exr", ".tif", ".tiff", ".tx", ".tga", ".bmp", ".hdr", ".webp"})



class ImageReadError(Exception):
    """The file exists (or should) but its header cannot be read."""


def is_package_path(resolved: str) -> bool:
    """True for Ar package-relative paths such as ``/x/scene.usdz[textures/a.png]``."""
    return bool(resolved) and Ar.IsPackageRelativePath(resolved)


def read_image_info(resolved: str) -> ImageInfo:
    """Read the header of ``resolved`` (a file path or an Ar package-relative path).

    >>> read_image_info("sample_assets/textures/cloth.png").width
    200
    """
    if is_package_path(resolved):
        data = _read_through_ar(resolved)
        inner = Ar.SplitPackageRelativePathInner(resolved)[1]
        with tempfile.TemporaryDirectory(prefix="seamless-usd-") as tmp:
            path = Path(tmp) / Path(inner).name
            path.write_bytes(data)
            return _read_header(str(path), io.BytesIO(data))
    if os.path.getsize(resolved) == 0:
        raise ImageReadError("the file is empty (0 bytes): an export or copy that did not finish; re-export it")
    with open(resolved, "rb") as fh:
        return _read_header(resolved, fh)


def _read_through_ar(resolved: str) -> bytes:
    asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved))
    if asset is None:
        raise ImageReadError("cannot open it through the asset resolver")
    return bytes(asset.GetBuffer())


def _read_header(path: str, raw) -> ImageInfo:
    from seamless_usd.imaging.io import header_info, reader_config

    inp = oiio.ImageInput.open(path, reader_config())
    if inp is None:
        lines = oiio.geterror().strip().splitlines()  # geterror() clears the message: read it once
        raise ImageReadError(lines[0] if lines else "unknown image format")
    try:
        return header_info(inp, png_stated_color_space(raw) if inp.format_name() == "png" else None)
    finally:
        inp.close()


def udim_tiles(absolute_pattern: str) -> list[str]:
    """Tiles on disk matching a ``<UDIM>`` path (or another of :data:`.tokens.TILE_TOKENS`), as their numbers
    (``["1001", "1002"]``, ``["u1_v1"]``)."""
    pattern = Path(absolute_pattern)
    folder = pattern.parent
    token = tile_token(pattern.name)
    if not folder.is_dir() or token is None:
        return []
    head, _, tail = pattern.name.partition(token)
    rx = re.compile(re.escape(head) + f"({TILE_TOKENS[token]})" + re.escape(tail) + "$")
    return sorted(m.group(1) for p in folder.iterdir() if (m := rx.match(p.name)))
