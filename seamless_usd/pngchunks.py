"""PNG colour chunks: what colour space a PNG file states, read from the chunks before its pixels."""
from __future__ import annotations

import io
import struct
from typing import BinaryIO

__all__ = ["png_stated_color_space", "PNG_SIGNATURE"]

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_stated_color_space(fh: BinaryIO) -> str | None:
    """The colour space a PNG states in its ``sRGB``/``iCCP``/``cICP``/``gAMA`` chunks, if any.

    ``fh`` is a binary file positioned at the start of the PNG. Returns an OpenImageIO colour
    space name (``srgb_rec709_scene``, ``lin_rec709_scene``, ``g22_rec709_scene``) or None when the
    file states nothing (or is no PNG): OpenImageIO itself reports sRGB for every PNG, so only
    the chunks say what a file really declares.
    """
    if fh.read(8) != PNG_SIGNATURE:
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
