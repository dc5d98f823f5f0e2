"""Reading image files with OpenImageIO (file values in; :mod:`.write` writes them out), and the output family
a source's tile is written in.

Pixels are handled as float32 arrays of *file values*, shape ``(H, W, C)``: integer files are
normalised to [0, 1] (``code / 255`` or ``code / 65535``), half and float files are returned as
stored. Alpha is read and written *unassociated* (straight), exactly as PNG/TIFF/TGA store it, so
colour values come back bit-exact; OpenImageIO would otherwise premultiply them.

Every failure a user can cause (missing, corrupt, truncated, enormous or unwritable file) is an
:class:`~seamless_usd.errors.InputError` naming the file as ``@path@`` and saying what to do.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd.textures import ImageInfo
from seamless_usd.errors import InputError, UndecodableImage
from seamless_usd.findings import asset_ref
from seamless_usd.pngchunks import png_stated_color_space

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "GUESSED_COLORSPACE_FORMATS",
    "OUTPUT_FAMILIES",
    "associated_alpha",
    "sample_type",
    "read_info",
    "read_image",
    "output_extension",
    "output_dtype",
    "alpha_channel",
    "norm_ext",
    "oiio_name",
    "reader_config",
]

DEFAULT_MAX_PIXELS = 1 << 28  # 268 Mpx (16k x 16k): larger headers are refused before decoding

# Output format family per source sample type: (extension, written sample type).
# 8-bit sources -> PNG, 16-bit -> 16-bit PNG (TIFF when the source is TIFF), signed and 32-bit integers -> TIFF of
# the same type (PNG holds neither), half / float -> OpenEXR keeping half vs float.
OUTPUT_FAMILIES: dict[str, tuple[str, str]] = {
    "uint8": (".png", "uint8"),
    "int8": (".tif", "int8"),
    "uint16": (".png", "uint16"),
    "int16": (".tif", "int16"),
    "uint32": (".tif", "uint32"),
    "int32": (".tif", "int32"),
    "half": (".exr", "half"),
    "float": (".exr", "float"),
    "double": (".exr", "float"),
}

#: Formats whose reader fills "oiio:ColorSpace" with a default rather than from the file.
GUESSED_COLORSPACE_FORMATS = frozenset({"png", "jpeg", "bmp", "targa", "gif", "webp", "ico"})

#: OpenImageIO's names for 32-bit integers, as the rest of the project spells them.
_SAMPLE_TYPES = {"uint": "uint32", "int": "int32"}


def sample_type(spec: oiio.ImageSpec) -> str:
    """The sample type of a header: OpenImageIO's base type name, 32-bit integers as ``uint32`` / ``int32``."""
    name = str(spec.format)
    return _SAMPLE_TYPES.get(name, name)


def associated_alpha(spec: oiio.ImageSpec, file_format: str) -> bool:
    """Whether a header read with :func:`reader_config` stores colour multiplied by its alpha where the format
    can say either (TIFF): such a file is written back so (OpenEXR's colour always is; PNG's never)."""
    return (file_format == "tiff" and spec.alpha_channel >= 0
            and spec.get_int_attribute("oiio:UnassociatedAlpha", 0) != 1)


def reader_config() -> oiio.ImageSpec:
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # keep straight alpha as stored
    return config


def oiio_name(path: str | Path) -> str:
    """``path`` as the image library takes it; :class:`InputError` naming it when its name is not valid UTF-8
    (bytes the file system holds but text cannot: the library cannot open such a file)."""
    name = str(path)
    try:
        name.encode("utf-8")
    except UnicodeEncodeError:
        raise InputError(f"{asset_ref(name)}: its file name is not valid "
                         "UTF-8 text, so the image library cannot open it; rename the file") from None
    return name


def _open(path: Path) -> oiio.ImageInput:
    if not path.is_file():
        raise InputError(
            f"{asset_ref(path)}: image file not found; check the asset path or restore the file"
        )
    if path.stat().st_size == 0:
        raise InputError(f"{asset_ref(path)}: the file is empty (0 bytes): an export or copy that did not finish; "
                         "re-export it")
    inp = oiio.ImageInput.open(oiio_name(path), reader_config())
    if inp is None:
        reason = " ".join((oiio.geterror() or "unknown format").split())
        raise InputError(
            f"{asset_ref(path)}: cannot read this image ({reason}); it may be corrupt or in an "
            "unsupported format: re-export it as PNG, TIFF or OpenEXR"
        )
    return inp


def _info_from(inp: oiio.ImageInput, path: Path) -> ImageInfo:
    color_space = None
    if inp.format_name() == "png":  # OpenImageIO reports sRGB for every PNG; only a chunk says so
        try:
            with open(path, "rb") as fh:
                color_space = png_stated_color_space(fh)
        except OSError:
            color_space = None
    return header_info(inp, color_space, parts=_parts(inp, inp.spec()))


def header_info(inp: oiio.ImageInput, png_color_space: str | None, parts: int = 1) -> ImageInfo:
    """What the header of the open file ``inp`` says; ``png_color_space``: what a PNG's chunks state (OpenImageIO
    reports sRGB for every PNG), ignored for other formats."""
    spec = inp.spec()
    fmt = inp.format_name()
    if fmt == "png":
        color_space = png_color_space
    elif fmt in GUESSED_COLORSPACE_FORMATS:
        color_space = None
    else:
        color_space = spec.get_string_attribute("oiio:ColorSpace") or None
    types = tuple(_SAMPLE_TYPES.get(str(t), str(t)) for t in spec.channelformats)
    return ImageInfo(
        width=spec.width,
        height=spec.height,
        channels=spec.nchannels,
        dtype=sample_type(spec),
        file_format=fmt,
        channel_names=tuple(spec.channelnames),
        texture=bool(spec.get_string_attribute("textureformat")) and spec.tile_width > 0,
        color_space=color_space,
        associated_alpha=associated_alpha(spec, fmt),
        parts=parts,
        channel_types=types if len(set(types)) > 1 else (),
        compression=(spec.get_string_attribute("compression") or None) if fmt in ("openexr", "tiff") else None,
    )


def _parts(inp: oiio.ImageInput, spec: oiio.ImageSpec) -> int:
    """How many subimages the open file holds (OpenEXR parts, TIFF pages); it is left on the first."""
    stated = spec.get_int_attribute("oiio:subimages", 0)
    if stated > 0:
        return stated
    count = 1
    while count < 64 and inp.seek_subimage(count, 0):
        count += 1
    inp.geterror()  # the failed seek past the last one leaves an error the next read would report: cleared
    inp.seek_subimage(0, 0)
    return count


def _check_size(info: ImageInfo, path: Path, max_pixels: int | None) -> None:
    if info.width <= 0 or info.height <= 0 or info.channels <= 0:
        raise InputError(
            f"{asset_ref(path)}: the header claims {info.width}x{info.height} pixels with "
            f"{info.channels} channels; the file is corrupt: re-export it"
        )
    if max_pixels is not None and info.width * info.height > max_pixels:
        raise InputError(
            f"{asset_ref(path)}: the header claims {info.width}x{info.height} "
            f"= {info.width * info.height} pixels, more than the limit of {max_pixels}; "
            "downscale the image or raise the pixel limit if it is genuine"
        )


def read_info(path: str | os.PathLike, *, max_pixels: int | None = DEFAULT_MAX_PIXELS) -> ImageInfo:
    """What the file header says, without decoding pixels.

    Parameters
    ----------
    path
        An image file in any format OpenImageIO reads.
    max_pixels
        Refuse files whose header claims more than this many pixels (``width * height``);
        ``None`` for no limit.

    Returns
    -------
    ImageInfo
        Size, channel count and names, sample type (``uint8``, ``uint16``, ``half``, ``float``),
        format name and the colour space the file declares (``None`` when it declares none; for
        PNG only an sRGB/gAMA/iCCP/cICP chunk counts).

    Raises
    ------
    InputError
        Missing, unreadable or corrupt file, or a header above ``max_pixels``.

    Examples
    --------
    >>> read_info("sample_assets/textures/brick_roughness16.png").dtype  # doctest: +SKIP
    'uint16'
    """
    p = Path(path)
    inp = _open(p)
    try:
        info = _info_from(inp, p)
    finally:
        inp.close()
    _check_size(info, p, max_pixels)
    return info


def image_count(path: str | os.PathLike) -> int:
    """How many images (parts, pages: OpenImageIO's subimages, not MIP levels) the file holds; 0 when unreadable."""
    try:
        inp = _open(Path(path))
    except InputError:
        return 0
    count = 1
    try:
        while inp.seek_subimage(count, 0):
            count += 1
    finally:
        inp.close()
    oiio.geterror()  # the seek past the last one is not an error
    return count


def read_image(
    path: str | os.PathLike, *, max_pixels: int | None = DEFAULT_MAX_PIXELS, min_side: int | None = None,
    stored: bool = False,
) -> tuple[np.ndarray, ImageInfo]:
    """Decode an image's first subimage into float32 file values (``stored``: in the file's own sample type, an
    8-bit picture a quarter of the memory, not normalised).

    The header is checked against ``max_pixels`` before any pixel is decoded. CMYK JPEGs come
    back as RGB (OpenImageIO converts them). Non-finite float values (NaN, inf) are returned as
    stored; see :func:`seamless_usd.imaging.finite.replace_nonfinite`.

    Parameters
    ----------
    path
        An image file in any format OpenImageIO reads.
    max_pixels
        As in :func:`read_info`.
    min_side
        Decode the smallest MIP level (of a tiled, MIP-mapped file such as a ``.tx``) whose longest side is
        still at least this; None: the full resolution.

    Returns
    -------
    pixels : np.ndarray
        ``(H, W, C)`` float32: integer files normalised to [0, 1], float files as stored.
    info : ImageInfo
        The header of the full resolution, as :func:`read_info` returns it.

    Raises
    ------
    InputError
        Missing, corrupt or truncated file, or a header above ``max_pixels``.
    """
    p = Path(path)
    inp = _open(p)
    try:
        info = _info_from(inp, p)
        _check_size(info, p, max_pixels)
        level = 0
        while min_side is not None and inp.seek_subimage(0, level + 1) and \
                max(inp.spec().width, inp.spec().height) >= min_side:
            level += 1  # a smaller MIP level still at least min_side: cheaper to decode
        inp.seek_subimage(0, level)
        pixels = inp.read_image(0, 0, 0, info.channels, oiio.UNKNOWN if stored else oiio.FLOAT)
        expected = (inp.spec().height, inp.spec().width, info.channels)
        # A truncated JPEG decodes "successfully" (the missing rows grey) with only an error
        # message left behind: any error recorded while decoding makes the pixels untrustworthy.
        error = " ".join(inp.geterror().split())
    finally:
        inp.close()
    if pixels is None or not isinstance(pixels, np.ndarray) or error:
        raise UndecodableImage(
            f"{asset_ref(p)}: the image data cannot be decoded ({error or 'read failed'}); "
            "the file is truncated or corrupt: re-export or re-download it", p)
    pixels = np.asarray(pixels) if stored else np.asarray(pixels, dtype=np.float32)
    if pixels.ndim == 2:
        pixels = pixels[..., None]
    if pixels.ndim == 4:  # volume images: first slice
        pixels = pixels[0]
    if pixels.shape != expected:
        raise InputError(
            f"{asset_ref(p)}: decoded {pixels.shape} pixels but the header says {expected}; "
            "the file is corrupt: re-export it"
        )
    return pixels, info


def output_dtype(info: ImageInfo) -> str:
    """The sample type an output for a source like ``info`` is written with.

    ``uint8`` for 8-bit sources, ``uint16`` for deeper integers, ``half`` or ``float`` for
    floating-point sources.

    Raises
    ------
    ValueError
        For a sample type with no output family.
    """
    try:
        return OUTPUT_FAMILIES[info.dtype][1]
    except KeyError:
        raise ValueError(
            f"no output format for {info.dtype!r} images; known: {', '.join(OUTPUT_FAMILIES)}"
        ) from None


def output_extension(info: ImageInfo) -> str:
    """File extension of the output family for a source like ``info``.

    8-bit sources give ``.png``, 16-bit ``.png`` (``.tif`` when the source is TIFF or has more
    than 4 channels), half and float give ``.exr``; a ``.tx`` texture (a tiled, MIP-mapped TIFF) gives ``.tx``.

    Examples
    --------
    >>> from seamless_usd.textures import ImageInfo
    >>> output_extension(ImageInfo(8, 8, 3, "uint8", "jpeg"))
    '.png'
    >>> output_extension(ImageInfo(8, 8, 1, "uint16", "tiff"))
    '.tif'
    >>> output_extension(ImageInfo(8, 8, 3, "half", "openexr"))
    '.exr'
    >>> output_extension(ImageInfo(8, 8, 3, "uint8", "tiff", texture=True))
    '.tx'
    """
    output_dtype(info)  # validates
    if info.texture and info.file_format == "tiff":  # a .tx texture stays one (tiled, MIP-mapped)
        return ".tx"
    ext = OUTPUT_FAMILIES[info.dtype][0]
    if info.dtype == "uint32" and info.file_format == "openexr":  # OpenEXR holds 32-bit unsigned integers too
        return ".exr"
    if ext == ".png" and (info.channels > 4 or info.associated_alpha
                          or (info.file_format == "tiff" and info.dtype != "uint8")):
        return ".tif"
    return ext


def alpha_channel(info: ImageInfo) -> int | None:
    """Index of the alpha channel: one named A/alpha, else the 2nd of 2 or the 4th of 4."""
    for i, name in enumerate(info.channel_names):
        if name.lower() in ("a", "alpha"):
            return i
    return {2: 1, 4: 3}.get(info.channels)


def norm_ext(ext: str) -> str:
    """Lower-case extension with `.tiff` spelled `.tif`, for comparing extensions."""
    ext = ext.lower()
    return {".tiff": ".tif"}.get(ext, ext)
