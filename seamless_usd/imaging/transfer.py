"""Colour transfer functions: file values <-> linear values, per :class:`ColorSpace`.

The functions come from colour-science (``eotf_sRGB`` / ``eotf_inverse_sRGB``, IEC 61966-2-1).
They are chosen from one mapping, :data:`TRANSFER_FUNCTIONS`, by colour space. For integer files
the decoding is a table of the colour-science function sampled at every code (256 or 65536
entries): the same numbers, without evaluating powers per pixel.
"""
from __future__ import annotations

import warnings
from collections.abc import Callable
from functools import lru_cache

import numpy as np

from seamless_usd.discover.types import ColorSpace

with warnings.catch_warnings():  # colour-science warns about optional plotting packages
    warnings.simplefilter("ignore")
    from colour.models import eotf_inverse_sRGB, eotf_sRGB

__all__ = ["TRANSFER_FUNCTIONS", "to_linear", "from_linear"]


def _identity(values: np.ndarray) -> np.ndarray:
    return np.asarray(values, dtype=np.float64)


# colour space -> (file value -> linear, linear -> file value)
TRANSFER_FUNCTIONS: dict[ColorSpace, tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]] = {
    ColorSpace.SRGB: (eotf_sRGB, eotf_inverse_sRGB),
    ColorSpace.RAW: (_identity, _identity),
}

_CODE_MAX = {"uint8": 255, "uint16": 65535}


def _colour_space(color_space: ColorSpace | str) -> ColorSpace:
    try:
        return ColorSpace(color_space)
    except ValueError:
        valid = ", ".join(c.value for c in TRANSFER_FUNCTIONS)
        raise ValueError(f"unknown colour space {color_space!r}; valid: {valid}") from None


def _functions(color_space: ColorSpace | str):
    return TRANSFER_FUNCTIONS[_colour_space(color_space)]


@lru_cache(maxsize=None)
def _decode_table(color_space: ColorSpace, code_max: int) -> np.ndarray:
    codes = np.arange(code_max + 1, dtype=np.float64) / code_max
    return np.asarray(_functions(color_space)[0](codes), dtype=np.float64)


def to_linear(values: np.ndarray, color_space: ColorSpace | str, dtype: str | None = None) -> np.ndarray:
    """File values -> linear values (float64).

    Parameters
    ----------
    values
        File values, any shape; integer files normalised to [0, 1].
    color_space
        ``sRGB`` (colour-science sRGB EOTF, extended linearly below 0) or ``raw`` (unchanged).
    dtype
        The file's sample type; for ``uint8`` / ``uint16`` values are snapped to their code grid
        and decoded by table.

    Returns
    -------
    np.ndarray
        Linear values, same shape, float64.

    Examples
    --------
    >>> float(to_linear(np.array(0.5), "sRGB").round(6))
    0.214041
    """
    cs = _colour_space(color_space)
    if cs is ColorSpace.RAW:
        return np.asarray(values, dtype=np.float64)
    code_max = _CODE_MAX.get(dtype or "")
    if code_max is not None:
        codes = np.rint(np.clip(np.asarray(values, dtype=np.float64), 0.0, 1.0) * code_max).astype(np.int64)
        return _decode_table(cs, code_max)[codes]
    return np.asarray(_functions(cs)[0](np.asarray(values, dtype=np.float64)), dtype=np.float64)


def from_linear(values: np.ndarray, color_space: ColorSpace | str) -> np.ndarray:
    """Linear values -> file values (float64); the inverse of :func:`to_linear`.

    Examples
    --------
    >>> float(from_linear(to_linear(np.array(0.5), "sRGB"), "sRGB").round(12))
    0.5
    """
    return np.asarray(_functions(color_space)[1](np.asarray(values, dtype=np.float64)), dtype=np.float64)
