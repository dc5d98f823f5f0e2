"""File values <-> the network domain [-1, 1]: :class:`MapEncoding`, :func:`decode_map`, :func:`encode_map`.

What a map's encoding records, and how each network channel is made:

* **channels**: the network sees the file channels the map's roles read (``r``, ``g``, ``b``,
  ``a``; a 1- or 2-channel file answers ``r``/``g``/``b`` with its first channel), plus the alpha
  channel whenever the file has one (alpha is kept, so the output keeps it). A map with no roles
  uses all channels. File channels left out are written back as a constant (``fill``: the
  source channel's mean).
* **colour**: the value channels of an sRGB map stay sRGB-encoded in the network domain
  (``perceptual=True``, the default): the GAN, its L1 and its Gram losses work best in a
  perceptually uniform domain, as with the paper's ordinary sRGB images, and dark albedo keeps
  its tonal resolution. ``perceptual=False`` decodes them to linear with the sRGB EOTF
  (IEC 61966-2-1). Raw maps are taken as they are; alpha is always linear.
* **normals**: the xyz channels of a normal map become unit vectors with the map's scale and bias
  (negative Y scale = the other Y convention), and go to the network as they are (already in
  [-1, 1]). Encoding renormalises, then inverts scale and bias. A vector already unit to the precision
  of the source's sample type is left as it is both ways, so a copied texel is stored exactly as in
  the source.
* **range**: other channels are mapped affinely from ``[lo, hi]`` to [-1, 1]. Integer files use
  [0, 1]. Float files get a range fitted to their pixels, ``lo = min(0, min)``,
  ``hi = max(1, max)``; when values leave [-1, 1] (HDR, e.g. emission above 1) the ``log`` tone
  is used: ``sign(x) * log1p(|x|)`` before the affine map, which is invertible, keeps detail in
  [0, 1] and brings large values into range. ``encode_map(decode_map(x)) == x`` up to float
  rounding, so nothing is lost before quantisation.

Non-finite input is refused (``ValueError``): replace it first with
:func:`seamless_usd.imaging.finite.replace_nonfinite`, which :func:`load_stack_pixels` does and
reports.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from seamless_usd.textures import ColorSpace, ImageInfo, TextureMap
from seamless_usd.imaging.transfer import file_codes, from_linear, linear_table, to_linear
from seamless_usd.imaging.io import alpha_channel
from seamless_usd.imaging.valuerange import Tone, ValueRange
from seamless_usd.imaging.normals import (decode_normals, encode_normals, encoding_doubt, normal_scale_bias,
                                         signed_as_stored, stored_unit_tolerance)

__all__ = ["Tone", "ValueRange", "MapEncoding", "decode_map", "encode_map"]

_INTEGER_TYPES = ("uint8", "uint16", "int8", "int16", "uint32", "int32")
_SIGNED_TYPES = ("int8", "int16", "int32")  # read as [-1, 1]: their range is fitted to the data, as a float file's


@dataclass(frozen=True)
class MapEncoding:
    """How one map's file values become network values and back (see the module docstring).

    Build it with :meth:`for_map` (from discovery) or :meth:`for_image` (from a bare header).
    """

    color_space: ColorSpace
    dtype: str  # source sample type: "uint8", "uint16", "half", "float"
    file_channels: int
    channels: tuple[int, ...]  # file channel indices the network sees, in network order
    alpha: int | None = None  # file index of the alpha channel (always kept when present)
    normal: tuple[int, int, int] | None = None  # file indices of a normal map's x, y, z
    normal_scale: tuple[float, float, float] = (2.0, 2.0, 2.0)
    normal_bias: tuple[float, float, float] = (-1.0, -1.0, -1.0)
    value_range: ValueRange = ValueRange()  # colour / data channels
    alpha_range: ValueRange = ValueRange()
    fill: tuple[float, ...] = ()  # per file channel: the value written where a channel is not kept
    perceptual: bool = True  # sRGB value channels stay sRGB-encoded for the network (see module docstring)
    notes: tuple[str, ...] = field(default=(), compare=False)  # what was decided and why
    warnings: tuple[str, ...] = field(default=(), compare=False)  # what the user should look at

    @property
    def value_transfer(self) -> ColorSpace:
        """Transfer between file values and the network's value channels."""
        return ColorSpace.RAW if self.perceptual else self.color_space

    @property
    def network_channels(self) -> int:
        """How many channels the network sees for this map."""
        return len(self.channels)

    @property
    def is_integer(self) -> bool:
        return self.dtype in _INTEGER_TYPES

    @property
    def network_code(self) -> float:
        """One code value of the file in network units: how finely it stores its values (2 / 255 for 8 bits,
        2 / 65535 for 16); 0 for half and float files, whose steps are finer than any seam."""
        if not self.is_integer:
            return 0.0
        file_step = 1.0 / float(np.iinfo(np.dtype(self.dtype)).max)  # the reader's values: a code over the largest
        return 2.0 * file_step / (self.value_range.hi - self.value_range.lo)

    @classmethod
    def for_map(
        cls, texture_map: TextureMap, info: ImageInfo, pixels: np.ndarray | None = None
    ) -> MapEncoding:
        """The encoding of a discovered map.

        Parameters
        ----------
        texture_map
            Gives the colour space, the channels its roles read, whether it is a normal map and
            its scale/bias.
        info
            The file header (channel count and names, sample type).
        pixels
            The file values ``(H, W, C)``, finite. Needed for float files so the range covers
            their values (HDR); also gives the fill values of unused channels. Without them a
            float map uses [0, 1] and values outside it leave [-1, 1] in the network domain.

        Raises
        ------
        ValueError
            A normal map whose scale has a zero component, or roles that read only channels the
            file does not have (alpha of a file without alpha).
        """
        scale_bias = None
        if texture_map.is_normal:
            scale_bias = normal_scale_bias(texture_map.scale, texture_map.bias)
            if pixels is not None and signed_as_stored(texture_map.scale, texture_map.bias, info.dtype, pixels):
                scale_bias = ((1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
        return cls.for_image(
            info,
            texture_map.color_space,
            channels_used=texture_map.channels_used,
            normal_scale_bias=scale_bias,
            pixels=pixels,
        )

    @classmethod
    def for_image(
        cls,
        info: ImageInfo,
        color_space: ColorSpace | str,
        *,
        channels_used: str = "",
        normal_scale_bias: tuple[tuple[float, float, float], tuple[float, float, float]] | None = None,
        pixels: np.ndarray | None = None,
        perceptual: bool = True,
    ) -> MapEncoding:
        """The encoding of an image used with the given channels (``""`` = all channels).

        ``normal_scale_bias`` marks a normal map (its xyz scale and bias, see
        :func:`~seamless_usd.imaging.normals.normal_scale_bias`). ``pixels`` as in :meth:`for_map`.

        Examples
        --------
        >>> info = ImageInfo(4, 4, 4, "uint8", "png", ("R", "G", "B", "A"))
        >>> MapEncoding.for_image(info, "sRGB", channels_used="rgb").channels
        (0, 1, 2, 3)
        """
        cs = ColorSpace(color_space)
        n = info.channels
        alpha = alpha_channel(info)
        notes: list[str] = []
        warnings: list[str] = []

        def index(letter: str) -> int | None:
            if letter == "a":
                return alpha
            if n <= 2:
                return 0  # grey (+ alpha): r, g and b all read the grey channel
            return "rgb".index(letter)

        if channels_used:
            unknown = set(channels_used) - set("rgba")
            if unknown:
                raise ValueError(f"unknown channel letters {sorted(unknown)} in {channels_used!r}; use r, g, b, a")
            kept = {index(c) for c in channels_used} - {None}
            if "a" in channels_used and alpha is None:
                warnings.append("a role reads alpha but the file has none (the shader sees 1)")
        else:
            kept = set(range(n))
        if alpha is not None and alpha not in kept:
            kept.add(alpha)
            notes.append("alpha kept although no role reads it")
        channels = tuple(sorted(kept))
        if not channels:
            raise ValueError(
                f"the roles read channels {channels_used!r} but the file has {n} channel(s) and no alpha"
            )

        normal = None
        scale, bias = (2.0, 2.0, 2.0), (-1.0, -1.0, -1.0)
        if normal_scale_bias is not None:
            if n >= 3 and {0, 1, 2} <= kept and alpha not in (0, 1, 2):
                normal = (0, 1, 2)
                scale, bias = normal_scale_bias
            else:
                warnings.append("normal map without three xyz channels: treated as plain values")

        value_range = alpha_range = ValueRange()
        fill = tuple(1.0 if i == alpha else 0.0 for i in range(n))
        if pixels is not None:
            p = np.asarray(pixels)
            if p.ndim == 2:
                p = p[..., None]
            if p.shape[-1] != n:
                raise ValueError(f"pixels have {p.shape[-1]} channels, the header says {n}")
            fill = tuple(float(np.nanmean(p[..., i], dtype=np.float64)) if p[..., i].size else 0.0 for i in range(n))
            doubt = None if normal is None else encoding_doubt(p[..., list(normal)], scale, bias)
            if doubt:
                warnings.append(doubt)
            if info.dtype not in _INTEGER_TYPES or info.dtype in _SIGNED_TYPES:  # float files: fit the range
                values = [i for i in channels if i != alpha and (normal is None or i not in normal)]
                if values:
                    linear = to_linear(p[..., values], ColorSpace.RAW if perceptual else cs, info.dtype)
                    value_range = ValueRange.fit(linear)
                if alpha is not None:
                    alpha_range = ValueRange.fit(p[..., alpha])
                if value_range.tone is Tone.LOG:
                    notes.append(
                        f"values in [{value_range.lo:g}, {value_range.hi:g}]: log-encoded (HDR)"
                    )
        return cls(
            color_space=cs,
            dtype=info.dtype,
            file_channels=n,
            channels=channels,
            alpha=alpha,
            normal=normal,
            normal_scale=tuple(float(v) for v in scale),  # type: ignore[arg-type]
            normal_bias=tuple(float(v) for v in bias),  # type: ignore[arg-type]
            value_range=value_range,
            alpha_range=alpha_range,
            fill=fill,
            perceptual=perceptual,
            notes=tuple(notes),
            warnings=tuple(warnings),
        )

    def channel_groups(self) -> tuple[list[int], list[int], list[int]]:
        """Network positions of the (value, normal, alpha) channels, three lists."""
        values, normals, alphas = [], [], []
        for j, f in enumerate(self.channels):
            if f == self.alpha:
                alphas.append(j)
            elif self.normal is not None and f in self.normal:
                normals.append(j)
            else:
                values.append(j)
        return values, normals, alphas

    def to_dict(self) -> dict:
        """JSON form for reports."""
        d = asdict(self)
        d["color_space"] = self.color_space.value
        for key in ("value_range", "alpha_range"):
            d[key]["tone"] = getattr(self, key).tone.value
        d["channels"] = list(self.channels)
        d["notes"] = list(self.notes)
        d["warnings"] = list(self.warnings)
        return d


def _as_hwc(array: np.ndarray, channels: int, what: str) -> np.ndarray:
    a = np.asarray(array)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[2] != channels:
        raise ValueError(f"{what}: expected (H, W) or (H, W, {channels}), got {np.shape(array)}")
    if not np.isfinite(a).all():
        raise ValueError(
            f"{what} contain NaN or inf; replace them first (imaging.finite.replace_nonfinite)"
        )
    return a


#: The spacing of stored values in [0, 1] (linear): integer codes, or half floats just below 1.
_FILE_STEP = {"uint8": 1 / 255, "uint16": 1 / 65535, "half": 2.0 ** -11, "float": 2.0 ** -24}


def _stored_unit(encoding: MapEncoding) -> float:
    """Normals whose length is this close to 1 are unit as the source stores them, and are neither
    renormalised on decoding nor on encoding: a copied texel is written back to its own codes."""
    step = _FILE_STEP.get(encoding.dtype, 0.0)
    if encoding.color_space == ColorSpace.SRGB:
        step *= 2.4 / 1.055  # the sRGB curve's steepest slope, linear per stored unit (at 1)
    return stored_unit_tolerance(step, encoding.normal_scale)


def decode_map(pixels: np.ndarray, encoding: MapEncoding) -> np.ndarray:
    """File values -> network values in [-1, 1].

    Parameters
    ----------
    pixels
        ``(H, W, C_file)`` file values (or ``(H, W)`` for a 1-channel file), finite.
    encoding
        The map's :class:`MapEncoding`.

    Returns
    -------
    np.ndarray
        ``(H, W, encoding.network_channels)`` float32.

    Raises
    ------
    ValueError
        Wrong shape, or NaN / inf in ``pixels``.

    Examples
    --------
    >>> info = ImageInfo(1, 1, 1, "uint8", "png")
    >>> enc = MapEncoding.for_image(info, "raw")
    >>> decode_map(np.array([[0.0]]), enc).tolist()
    [[[-1.0]]]
    """
    p = _as_hwc(pixels, encoding.file_channels, "pixels")
    out = np.empty(p.shape[:2] + (encoding.network_channels,), dtype=np.float64)
    values, normals, alphas = encoding.channel_groups()
    if values:
        idx = [encoding.channels[j] for j in values]
        codes = file_codes(p[..., idx], encoding.dtype)
        if codes is not None:  # integer file: one table lookup per texel
            table = encoding.value_range.to_network(linear_table(encoding.value_transfer, encoding.dtype))
            out[..., values] = np.take(table, codes)
        else:
            linear = to_linear(p[..., idx], encoding.value_transfer, encoding.dtype)
            out[..., values] = encoding.value_range.to_network(linear)
    if normals:
        linear = to_linear(p[..., list(encoding.normal)], encoding.color_space, encoding.dtype)
        out[..., normals] = decode_normals(linear, encoding.normal_scale, encoding.normal_bias, _stored_unit(encoding))
    if alphas:
        out[..., alphas] = encoding.alpha_range.to_network(p[..., [encoding.alpha]].astype(np.float64))
    return out.astype(np.float32)


def encode_map(values: np.ndarray, encoding: MapEncoding) -> np.ndarray:
    """Network values -> file values, with the file's full channel layout.

    Normals are renormalised first; channels the network does not see get ``encoding.fill``.
    Integer files' values are clipped to [0, 1] ([-1, 1] signed; the writer rounds them to codes); float values
    are returned unclipped.

    Parameters
    ----------
    values
        ``(H, W, encoding.network_channels)`` network values (``(H, W)`` for one channel), finite.
    encoding
        The map's :class:`MapEncoding`.

    Returns
    -------
    np.ndarray
        ``(H, W, encoding.file_channels)`` float32 file values.

    Raises
    ------
    ValueError
        Wrong shape, or NaN / inf in ``values`` (e.g. a diverged model).
    """
    v = _as_hwc(values, encoding.network_channels, "network values").astype(np.float64, copy=False)
    out = np.empty(v.shape[:2] + (encoding.file_channels,), dtype=np.float64)
    out[...] = np.asarray(encoding.fill or [0.0] * encoding.file_channels, dtype=np.float64)
    groups_values, normals, alphas = encoding.channel_groups()
    if groups_values:
        idx = [encoding.channels[j] for j in groups_values]
        linear = encoding.value_range.from_network(v[..., groups_values])
        out[..., idx] = from_linear(linear, encoding.value_transfer, encoding.dtype)
    if normals:
        linear = encode_normals(v[..., normals], encoding.normal_scale, encoding.normal_bias, _stored_unit(encoding))
        out[..., list(encoding.normal)] = from_linear(linear, encoding.color_space, encoding.dtype)
    if alphas:
        out[..., [encoding.alpha]] = encoding.alpha_range.from_network(v[..., alphas])
    if encoding.is_integer:
        np.clip(out, -1.0 if encoding.dtype in _SIGNED_TYPES else 0.0, 1.0, out=out)
    return out.astype(np.float32)
