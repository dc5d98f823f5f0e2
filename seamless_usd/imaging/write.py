"""Writing a synthesised map: network values -> file values -> an atomically written file.

The output keeps the source's format family and bit depth (8-bit -> PNG, 16-bit -> 16-bit PNG or
TIFF, half / float -> OpenEXR half / float; see :func:`~seamless_usd.imaging.io.output_extension`),
its channel count and layout (channels the network did not see are filled with a constant),
straight alpha, and the colour encoding the stage declares for the map (the map's colour space,
also recorded in the file's colour metadata).
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from seamless_usd.textures import ImageInfo
from seamless_usd.findings import asset_ref
from seamless_usd.imaging.encoding import MapEncoding, encode_map
from seamless_usd.imaging.io import norm_ext, output_extension, write_pixels

__all__ = ["write_map", "output_path"]


def output_path(path: str | os.PathLike, like: ImageInfo) -> Path:
    """``path`` with the extension of ``like``'s output family.

    A path without extension gets it; a path with the right one (any case, ``.tiff`` for
    ``.tif``) is kept; any other extension is refused.

    Raises
    ------
    ValueError
        The path's extension belongs to another format family.

    Examples
    --------
    >>> info = ImageInfo(8, 8, 3, "uint8", "jpeg")
    >>> output_path("out/brick", info).name, output_path("out/brick.PNG", info).name
    ('brick.png', 'brick.PNG')
    """
    p = Path(path)
    ext = output_extension(like)
    if not p.suffix:
        return p.with_name(p.name + ext)
    if norm_ext(p.suffix) != norm_ext(ext):
        raise ValueError(
            f"{asset_ref(p)}: a {like.dtype} {like.file_format} source is written as {ext}, "
            f"not {p.suffix}; use output_extension() to name outputs"
        )
    return p


def write_map(
    path: str | os.PathLike, values: np.ndarray, encoding: MapEncoding, like: ImageInfo, record: dict | None = None
) -> Path:
    """Encode network values and write them atomically in the source's format family.

    Parameters
    ----------
    path
        Target file, with the extension of :func:`output_extension` ``(like)`` or none (then it
        is added). The folder must exist.
    values
        ``(H, W, encoding.network_channels)`` network values in [-1, 1] (any H, W: a tile may be
        larger than the source); ``(H, W)`` for one channel. Normals are renormalised.
    encoding
        The map's encoding (from :class:`~seamless_usd.imaging.stack.StackPixels`).
    like
        The source's header: sample type, channel count and names.
    record
        What the tile records in its file of how it was made (:mod:`.tag`), or None.

    Returns
    -------
    Path
        The written file.

    Raises
    ------
    ValueError
        Wrong extension, wrong channel count, or NaN / inf values.
    InputError
        The file cannot be written.
    """
    target = output_path(path, like)
    if like.channels != encoding.file_channels:
        raise ValueError(
            f"{asset_ref(target)}: the encoding is for {encoding.file_channels} file channels, "
            f"the source has {like.channels}"
        )
    pixels = encode_map(values, encoding)
    return write_pixels(target, pixels, like, encoding.color_space, record)
