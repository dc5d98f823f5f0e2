"""Writing a synthesised map: network values -> file values -> an atomically written file.

The output keeps the source's format family and bit depth (8-bit -> PNG, 16-bit -> 16-bit PNG or
TIFF, half / float -> OpenEXR half / float; see :func:`~seamless_usd.imaging.io.output_extension`),
its channel count and layout (channels the network did not see are filled with a constant),
its alpha as stored (straight, or colour multiplied by it in a TIFF that says so), the colour encoding the stage
declares for the map (recorded in the file's colour metadata, for a linear or data map only where the source's
header names a space), and the source's embedded ICC colour profile where the output
format holds one (PNG, TIFF; not OpenEXR): the tile's texels are in the source's encoding, so an image editor
shows its colours as it shows the source's.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write
from seamless_usd.findings import asset_ref
from seamless_usd.textures import ColorSpace, ImageInfo
from seamless_usd.imaging.encoding import MapEncoding, encode_map
from seamless_usd.imaging.io import alpha_channel, norm_ext, output_dtype, output_extension, reader_config

__all__ = ["write_map", "write_pixels", "output_path", "kept_attributes", "KEPT_ATTRIBUTES"]

_OIIO_TYPES = {"uint8": oiio.UINT8, "int8": oiio.INT8, "uint16": oiio.UINT16, "int16": oiio.INT16,
               "uint32": oiio.UINT32, "int32": oiio.INT32, "half": oiio.HALF, "float": oiio.FLOAT}
_NUMPY_TYPES = {"uint8": np.uint8, "int8": np.int8, "uint16": np.uint16, "int16": np.int16, "uint32": np.uint32,
                "int32": np.int32, "half": np.float16, "float": np.float32}
_COLORSPACE_NAMES = {ColorSpace.SRGB: "srgb_rec709_scene", ColorSpace.RAW: "lin_rec709_scene"}


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
    path: str | os.PathLike, values: np.ndarray, encoding: MapEncoding, like: ImageInfo, record: dict | None = None,
    keep_from: str | os.PathLike | None = None,
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
    keep_from
        The source file, whose embedded colour profile the tile keeps (:data:`KEPT_ATTRIBUTES`), or None.

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
    return write_pixels(target, pixels, like, encoding.color_space, record, keep_from)


#: Header attributes a tile keeps from its source file: the embedded colour profile (how an image editor reads its
#: colours; renderers go by the stage's colour space), and an OpenEXR file's primaries and colour space (an ACEScg
#: map stays ACEScg: relabelled Rec.709, a reader of the header shifts its hues).
KEPT_ATTRIBUTES = ("ICCProfile", "chromaticities", "colorInteropID", "oiio:ColorSpace")
_KEPT_BY_FORMAT = {".png": ("ICCProfile",), ".tif": ("ICCProfile",), ".tx": ("ICCProfile",),
                   ".exr": ("chromaticities", "colorInteropID", "oiio:ColorSpace")}


def kept_attributes(source: str | os.PathLike) -> list[tuple[str, object, object]]:
    """(name, type, value) of the :data:`KEPT_ATTRIBUTES` in ``source``'s header (none when it cannot be read:
    the tile is written without them)."""
    inp = oiio.ImageInput.open(str(source), reader_config())
    if inp is None:
        oiio.geterror()  # cleared: a missing profile is not an error
        return []
    try:
        return [(pv.name, pv.type, pv.value) for pv in inp.spec().extra_attribs if pv.name in KEPT_ATTRIBUTES]
    finally:
        inp.close()


def _same_encoding(name: str, color_space: ColorSpace) -> bool:
    """Whether a source's colour-space name says the encoding ``color_space`` does (linear or sRGB-encoded)."""
    low = name.lower().replace(" ", "")
    if low.startswith("lin") or any(k in low for k in ("linear", "acescg", "aces2065", "raw")):
        return ColorSpace(color_space) is ColorSpace.RAW
    if "srgb" in low or "g22" in low:
        return ColorSpace(color_space) is ColorSpace.SRGB
    return False  # a name not known here: the tile's own is written


def write_pixels(
    path: str | os.PathLike,
    pixels: np.ndarray,
    like: ImageInfo,
    color_space: ColorSpace,
    record: dict | None = None,
    keep_from: str | os.PathLike | None = None,
) -> Path:
    """Write float file values atomically in the output family of ``like``; ``record``: what the file
    records of how it was made (:mod:`.tag`); ``keep_from``: the source file whose colour profile is kept.

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
    types = like.channel_types if ext == ".exr" and len(like.channel_types) == like.channels else ()
    data = _quantise(pixels, dtype, types)
    h, w, c = data.shape
    spec = oiio.ImageSpec(w, h, c, _OIIO_TYPES[dtype])
    if types:  # each channel in its own sample type, as the source stores it (half colour, float alpha)
        spec.channelformats = tuple(_OIIO_TYPES[t] for t in types)
    if len(like.channel_names) == c:
        spec.channelnames = tuple(like.channel_names)
    named = any(n.lower() in ("a", "alpha") for n in like.channel_names)
    alpha = alpha_channel(like) if named or len(like.channel_names) != c else None
    if alpha is not None:
        spec.alpha_channel = alpha
    # a linear or data map's tile is labelled only where its source's header names a space (the source's name is kept
    # below where it says the same encoding): a label the source did not have would change how viewers show the
    # tile (a PNG's gAMA) or contradict the stage's own name (ACEScg). An unlabelled PNG gets sRGB chunks from the
    # writer; "raw" writes none
    if ColorSpace(color_space) is ColorSpace.SRGB or like.color_space is not None:
        spec.attribute("oiio:ColorSpace", _COLORSPACE_NAMES[ColorSpace(color_space)])
    elif ext == ".png":
        spec.attribute("oiio:ColorSpace", "raw")
    if ext != ".exr" and not like.associated_alpha:  # values are stored as the source stores them: straight, or multiplied
        spec.attribute("oiio:UnassociatedAlpha", 1)
    if ext in (".exr", ".tif", ".tx"):  # the source's compression where it is of the same family, else lossless zip
        same_family = like.file_format == ("openexr" if ext == ".exr" else "tiff")
        spec.attribute("compression", like.compression if same_family and like.compression else "zip")
    if keep_from is not None:
        kept = kept_attributes(keep_from)
        named = {name: value for name, _, value in kept if name in ("colorInteropID", "oiio:ColorSpace")}
        for name, kind, value in kept:
            if name not in _KEPT_BY_FORMAT.get(norm_ext(ext), ()):
                continue
            if name in named and not _same_encoding(str(value), ColorSpace(color_space)):
                continue  # a name for another encoding than the tile's values are in: the tile's own is written
            spec.attribute(name, kind, value)
    if record is not None:
        from seamless_usd.imaging.tag import tag_attributes

        for name, text in tag_attributes(ext, record):
            spec.attribute(name, text)

    def writer(tmp: Path) -> None:
        if ext == ".tx" or (ext == ".exr" and like.texture):  # a tiled, MIP-mapped texture stays one
            _write_texture(tmp, target, data, spec)
            return
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


def _write_texture(tmp: Path, target: Path, data: np.ndarray, spec: oiio.ImageSpec) -> None:
    """``data`` written to ``tmp`` as a tiled, MIP-mapped texture (what ``maketx`` makes), its header (colour space,
    record) kept; its first level holds ``data`` exactly."""
    buf = oiio.ImageBuf(spec)
    if not buf.set_pixels(oiio.ROI(0, spec.width, 0, spec.height, 0, 1, 0, spec.nchannels), data):
        raise InputError(f"{asset_ref(target)}: the tile's pixels cannot be set ({buf.geterror()})")
    config = oiio.ImageSpec()
    config.attribute("maketx:filtername", "lanczos3")
    config.attribute("wrapmodes", "periodic,periodic")  # a tile repeats: its header says so, its MIP levels wrap
    config.attribute("compression", spec.get_string_attribute("compression", "zip"))
    if not oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, buf, str(tmp), config):
        raise InputError(f"{asset_ref(target)}: writing the texture failed ({' '.join(oiio.geterror().split())}); "
                         "check free disk space and permissions")
    _check_written(tmp, target, data.shape)


def _check_written(tmp: Path, target: Path, shape: tuple[int, ...]) -> None:
    """Read the new file back before it replaces anything.

    Some writers (OpenImageIO's PNG writer among them) report success on a full disk and leave
    a short or empty file; decoding it is the one check that catches every such case.
    """
    inp = oiio.ImageInput.open(str(tmp), reader_config())
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


def _quantise(pixels: np.ndarray, dtype: str, types: tuple[str, ...] = ()) -> np.ndarray:
    """``pixels`` as ``dtype`` samples; ``types``: each channel's own sample type (a float output whose half
    channels are held to the half range)."""
    if types:
        return np.stack([_quantise(pixels[..., i], t).astype(np.float32) for i, t in enumerate(types)], axis=-1)
    values = pixels.astype(np.float64, copy=False)
    if dtype in _NUMPY_TYPES and np.issubdtype(_NUMPY_TYPES[dtype], np.integer):
        top = float(np.iinfo(_NUMPY_TYPES[dtype]).max)  # signed: [-1, 1] as the reader gives it
        low = -1.0 if np.issubdtype(_NUMPY_TYPES[dtype], np.signedinteger) else 0.0
        return np.rint(np.clip(values, low, 1.0) * top).astype(_NUMPY_TYPES[dtype])
    if dtype == "half":
        return np.clip(values, -65504.0, 65504.0).astype(np.float16)
    return values.astype(np.float32)
