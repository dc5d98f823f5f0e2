"""Imaging: read and write texture files, and move their values to and from the network domain.

Pixels in, pixels out; no USD and no torch here.

* :mod:`.io`: OpenImageIO reading (header limit, clean errors) and atomic writing by family.
* :mod:`.transfer`: sRGB (IEC 61966-2-1) / raw transfer functions.
* :mod:`.normals`: normal-map scale/bias and Y conventions.
* :mod:`.encoding`: :class:`MapEncoding`, :func:`decode_map`, :func:`encode_map`.
* :mod:`.finite`: the NaN / inf policy.
* :mod:`.resample`: :class:`WorkingResolution` and resampling.
* :mod:`.stack`: :func:`load_stack_pixels` -> :class:`StackPixels`.
* :mod:`.write`: :func:`write_map`.
* :mod:`.orientation`: how far a stack's lines are turned from the axes.
* :mod:`.perspective`: where lines that converge with perspective meet, and the maps rectified (``process --straighten``).
* :mod:`.straighten`: the maps turned back and cut to source texels (``process --straighten``).
"""
from __future__ import annotations

from seamless_usd.imaging.transfer import TRANSFER_FUNCTIONS, from_linear, to_linear
from seamless_usd.imaging.encoding import MapEncoding, Tone, ValueRange, decode_map, encode_map
from seamless_usd.imaging.finite import NonFinite, replace_nonfinite
from seamless_usd.imaging.io import (
    DEFAULT_MAX_PIXELS,
    output_dtype,
    output_extension,
    read_image,
    read_info,
)
from seamless_usd.imaging.normals import decode_normals, encode_normals, normal_scale_bias, renormalise
from seamless_usd.imaging.resample import FILTERS, WorkingResolution, resample
from seamless_usd.imaging.stack import StackPixels, load_stack_pixels
from seamless_usd.imaging.write import output_path, write_map, write_pixels

__all__ = [
    "DEFAULT_MAX_PIXELS",
    "FILTERS",
    "TRANSFER_FUNCTIONS",
    "MapEncoding",
    "NonFinite",
    "StackPixels",
    "Tone",
    "ValueRange",
    "WorkingResolution",
    "decode_map",
    "decode_normals",
    "encode_map",
    "encode_normals",
    "from_linear",
    "load_stack_pixels",
    "normal_scale_bias",
    "output_dtype",
    "output_extension",
    "output_path",
    "read_image",
    "read_info",
    "renormalise",
    "replace_nonfinite",
    "resample",
    "to_linear",
    "write_map",
    "write_pixels",
]
