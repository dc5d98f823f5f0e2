"""Reading and writing image files with OpenImageIO: file values in, file values out.

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

from seamless_usd.textures import ColorSpace, ImageInfo
from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write
from seamless_usd.findings import asset_ref
from seamless_usd.pngchunks import png_stated_color_space

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "OUTPUT_FAMILIES",
    "read_info",
    "read_image",
    "write_pixels",
    "output_extension",
    "output_dtype",
    "alpha_channel",
    "norm_ext",
    "oiio_name",
]

DEFAULT_MAX_PIXELS = 1 << 28  # 268 Mpx (16k x 16k): larger headers are refused before decoding

# Output format family per source sample type: (extension, written sample type).
# 8-bit sources -> PNG, deeper integers -> 16-bit PNG (TIFF when the source is TIFF),
# half / float -> OpenEXR keeping half vs float.
OUTPUT_FAMILIES: dict[str, tuple[str, str]] = {
    "uint8": (".png", "uint8"),
    "int8": (".png", "uint8"),
    "uint16": (".png", "uint16"),
    "int16": (".png", "uint16"),
    "uint32": (".png", "uint16"),
    "int32": (".png", "uint16"),
    "half": (".exr", "half"),
    "float": (".exr", "float"),
    "double": (".exr", "float"),
}

_OIIO_TYPES = {"uint8": oiio.UINT8, "uint16": oiio.UINT16, "half": oiio.HALF, "float": oiio.FLOAT}
_NUMPY_TYPES = {"uint8": np.uint8, "uint16": np.uint16, "half": np.float16, "float": np.float32}
_COLORSPACE_NAMES = {ColorSpace.SRGB: "srgb_rec709_scene", ColorSpace.RAW: "lin_rec709_scene"}


def _input_config() -> oiio.ImageSpec:
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
    inp = oiio.ImageInput.open(oiio_name(path), _input_config())
    if inp is None:
        reason = " ".join((oiio.geterror() or "unknown format").split())
        raise InputError(
            f"{asset_ref(path)}: cannot read this image ({reason}); it may be corrupt or in an "
            "unsupported format: re-export it as PNG, TIFF or OpenEXR"
        )
    return inp


def _info_from(inp: oiio.ImageInput, path: Path) -> ImageInfo:
    spec = inp.spec()
    fmt = inp.format_name()
    color_space = spec.get_string_attribute("oiio:ColorSpace") or None
    if fmt == "png":  # OpenImageIO reports sRGB for every PNG; only a chunk says so
        try:
            with open(path, "rb") as fh:
                color_space = png_stated_color_space(fh)
        except OSError:
            color_space = None
    return ImageInfo(
        width=spec.width,
        height=spec.height,
        channels=spec.nchannels,
        dtype=str(spec.format),
        file_format=fmt,
        channel_names=tuple(spec.channelnames),
        color_space=color_space,
    )


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


def read_image(
    path: str | os.PathLike, *, max_pixels: int | None = DEFAULT_MAX_PIXELS, min_side: int | None = None
) -> tuple[np.ndarray, ImageInfo]:
    """Decode an image's first subimage into float32 file values.

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
        pixels = inp.read_image(0, 0, 0, info.channels, oiio.FLOAT)
        expected = (inp.spec().height, inp.spec().width, info.channels)
        # A truncated JPEG decodes "successfully" (the missing rows grey) with only an error
        # message left behind: any error recorded while decoding makes the pixels untrustworthy.
        error = " ".join(inp.geterror().split())
    finally:
        inp.close()
    if pixels is None or not isinstance(pixels, np.ndarray) or error:
        raise InputError(
            f"{asset_ref(p)}: the image data cannot be decoded ({error or 'read failed'}); "
            "the file is truncated or corrupt: re-export or re-download it"
        )
    pixels = np.asarray(pixels, dtype=np.float32)
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
    than 4 channels), half and float give ``.exr``.

    Examples
    --------
    >>> from seamless_usd.textures import ImageInfo
    >>> output_extension(ImageInfo(8, 8, 3, "uint8", "jpeg"))
    '.png'
    >>> output_extension(ImageInfo(8, 8, 1, "uint16", "tiff"))
    '.tif'
    >>> output_extension(ImageInfo(8, 8, 3, "half", "openexr"))
    '.exr'
    """
    output_dtype(info)  # validates
    ext = OUTPUT_FAMILIES[info.dtype][0]
    if ext == ".png" and (info.channels > 4 or (info.file_format == "tiff" and info.dtype != "uint8")):
        return ".tif"
    return ext


def write_pixels(
    path: str | os.PathLike,
    pixels: np.ndarray,
    like: ImageInfo,
    color_space: ColorSpace,
    record: dict | None = None,
) -> Path:
    """Write float file values atomically in the output family of ``like``; ``record``: what the file
    records of how it was made (:mod:`.tag`).

    Parameters
    ----------
    path
        Target file; its extension must be :func:`output_extension` of ``like`` (``.tiff`` and
        ``.tif`` are the same).
    pixels
        ``(H, W, C)`` or ``(H, W)`` float file values, ``C == like.channels``. Integer outputs are
        clipped to [0, 1] and rounded to the nearest code; half outputs are clipped to the half
        range (+-65504).
    like
        The source header: sample type, channel count and names are copied.
    color_space
        The encoding the values are in, recorded as ``oiio:ColorSpace`` (sRGB -> an sRGB chunk
        in PNG; raw -> linear).

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        Wrong extension or channel count.
    InputError
        The file cannot be written (folder missing or read-only, disk full).
    """
    target = Path(path)
    ext = output_extension(like)
    if norm_ext(target.suffix) != norm_ext(ext):
        raise ValueError(f"{asset_ref(target)}: a {like.dtype} {like.file_format} source is written as {ext}")
    pixels = np.asarray(pixels)
    if pixels.ndim == 2:
        pixels = pixels[..., None]
    if pixels.ndim != 3 or pixels.shape[2] != like.channels:
        raise ValueError(f"expected (H, W, {like.channels}) pixels for {asset_ref(target)}, got {pixels.shape}")
    dtype = output_dtype(like)
    data = _quantise(pixels, dtype)
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, _OIIO_TYPES[dtype])
    if len(like.channel_names) == c:
        spec.channelnames = tuple(like.channel_names)
    named = any(n.lower() in ("a", "alpha") for n in like.channel_names)
    alpha = alpha_channel(like) if named or len(like.channel_names) != c else None
    if alpha is not None:
        spec.alpha_channel = alpha
    spec.attribute("oiio:ColorSpace", _COLORSPACE_NAMES[ColorSpace(color_space)])
    if ext == ".exr":
        spec.attribute("compression", "zip")
    else:
        spec.attribute("oiio:UnassociatedAlpha", 1)  # values are straight alpha, store as is
        if ext == ".tif":
            spec.attribute("compression", "zip")
    if record is not None:
        from seamless_usd.imaging.tag import tag_attributes

        for name, text in tag_attributes(ext, record):
            spec.attribute(name, text)

    def writer(tmp: Path) -> None:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None:
            raise InputError(f"{asset_ref(target)}: no image writer for {ext} ({oiio.geterror()})")
        try:
            if not out.open(str(tmp), spec) or not out.write_image(data):
                raise InputError(
                    f"{asset_ref(target)}: writing failed ({' '.join(out.geterror().split())}); "
                    "check free disk space and permissions"
                )
        finally:
            out.close()
        _check_written(tmp, target, data.shape)

    return atomic_write(target, writer)


def _check_written(tmp: Path, target: Path, shape: tuple[int, ...]) -> None:
    """Read the new file back before it replaces anything.

    Some writers (OpenImageIO's PNG writer among them) report success on a full disk and leave
    a short or empty file; decoding it is the one check that catches every such case.
    """
    inp = oiio.ImageInput.open(str(tmp), _input_config())
    error = "" if inp is not None else " ".join((oiio.geterror() or "unreadable").split())
    if inp is not None:
        try:
            spec = inp.spec()
            pixels = inp.read_image(0, 0, 0, spec.nchannels, oiio.FLOAT)
            error = " ".join(inp.geterror().split())
            if not error and (pixels is None or (spec.height, spec.width, spec.nchannels) != tuple(shape)):
                error = "incomplete image"
        finally:
            inp.close()
    if error:
        raise InputError(
            f"{asset_ref(target)}: the written file does not read back ({error}); "
            "check free disk space and permissions"
        )


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


def _quantise(pixels: np.ndarray, dtype: str) -> np.ndarray:
    values = pixels.astype(np.float64, copy=False)
    if dtype in ("uint8", "uint16"):
        top = float(np.iinfo(_NUMPY_TYPES[dtype]).max)
        return np.rint(np.clip(values, 0.0, 1.0) * top).astype(_NUMPY_TYPES[dtype])
    if dtype == "half":
        return np.clip(values, -65504.0, 65504.0).astype(np.float16)
    return values.astype(np.float32)
