"""Image headers without pixels: size, channels, bit depth, format and stated colour space.

Files inside ``.usdz`` packages are read through Ar (the USD asset resolver); OpenImageIO reads
only the header. ``oiio:ColorSpace`` is a guess for some formats (OpenImageIO calls every PNG and
JPEG sRGB), so the colour space a file *states* is read from the PNG chunks themselves and only
trusted from OpenImageIO for formats that store it.
"""
from __future__ import annotations

import io
import re
import struct
import tempfile
from pathlib import Path

import OpenImageIO as oiio
from pxr import Ar

from seamless_usd.discover.tokens import UDIM_TOKEN
from seamless_usd.discover.types import ImageInfo

__all__ = ["read_image_info", "is_package_path", "udim_tiles", "ImageReadError"]

# Formats whose reader fills "oiio:ColorSpace" with a default rather than from the file.
_GUESSED_COLORSPACE_FORMATS = frozenset({"png", "jpeg", "bmp", "targa", "gif", "webp", "ico"})
_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


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
    with open(resolved, "rb") as fh:
        return _read_header(resolved, fh)


def _read_through_ar(resolved: str) -> bytes:
    asset = Ar.GetResolver().OpenAsset(Ar.ResolvedPath(resolved))
    if asset is None:
        raise ImageReadError("cannot open it through the asset resolver")
    return bytes(asset.GetBuffer())


def _read_header(path: str, raw) -> ImageInfo:
    inp = oiio.ImageInput.open(path)
    if inp is None:
        lines = oiio.geterror().strip().splitlines()  # geterror() clears the message: read it once
        raise ImageReadError(lines[0] if lines else "unknown image format")
    try:
        spec = inp.spec()
        fmt = inp.format_name()
        if fmt == "png":
            stated = _png_color_space(raw)
        elif fmt in _GUESSED_COLORSPACE_FORMATS:
            stated = None
        else:
            stated = spec.get_string_attribute("oiio:ColorSpace") or None
        return ImageInfo(
            width=spec.width,
            height=spec.height,
            channels=spec.nchannels,
            dtype=str(spec.format),
            file_format=fmt,
            channel_names=tuple(spec.channelnames),
            color_space=stated,
        )
    finally:
        inp.close()


def _png_color_space(fh) -> str | None:
    """The colour space a PNG states in its ``sRGB``/``iCCP``/``cICP``/``gAMA`` chunks, if any."""
    if fh.read(8) != _PNG_SIGNATURE:
        return None
    found: dict[str, bytes] = {}
    while True:
        head = fh.read(8)
        if len(head) < 8:
            break
        length, kind = struct.unpack(">I4s", head)
        kind = kind.decode("latin-1")
        if kind in ("IDAT", "IEND"):
            break
        if kind in ("sRGB", "cICP", "gAMA"):
            found[kind] = fh.read(length)
            fh.seek(4, io.SEEK_CUR)
        else:
            found.setdefault(kind, b"")
            fh.seek(length + 4, io.SEEK_CUR)
    if "cICP" in found and len(found["cICP"]) >= 2:
        transfer = found["cICP"][1]
        if transfer == 13:
            return "srgb_rec709_scene"
        if transfer == 8:
            return "lin_rec709_scene"
    if "sRGB" in found or "iCCP" in found:
        return "srgb_rec709_scene"
    if "gAMA" in found and len(found["gAMA"]) == 4:
        gamma = 100000.0 / max(struct.unpack(">I", found["gAMA"])[0], 1)
        if abs(gamma - 1.0) < 0.05:
            return "lin_rec709_scene"
        if abs(gamma - 2.2) < 0.1:
            return "g22_rec709_scene"
    return None


def udim_tiles(absolute_pattern: str) -> list[str]:
    """Tiles on disk matching a ``<UDIM>`` path, as tile numbers (``["1001", "1002"]``)."""
    pattern = Path(absolute_pattern)
    folder = pattern.parent
    if not folder.is_dir():
        return []
    head, _, tail = pattern.name.partition(UDIM_TOKEN)
    rx = re.compile(re.escape(head) + r"(1\d{3})" + re.escape(tail) + "$")
    return sorted(m.group(1) for p in folder.iterdir() if (m := rx.match(p.name)))
