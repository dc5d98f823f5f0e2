"""Colour transfer functions: file values <-> linear values, per :class:`ColorSpace`.

The sRGB pair is IEC 61966-2-1's piecewise curve (linear toe below 0.04045 / 0.0031308, a 2.4 power
above), extended to negative values the way colour-science extends it (linear toe, sign-preserving
power); the tests hold it to colour-science's ``eotf_sRGB`` / ``eotf_inverse_sRGB``. It is written
out here because importing colour-science costs every run half a second. The functions are chosen
from one mapping, :data:`TRANSFER_FUNCTIONS`, by colour space. For integer files the decoding is a
table of the function sampled at every code (256 or 65536 entries): the same numbers, without
evaluating powers per pixel.
"""
from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

import numpy as np

from seamless_usd.textures import ColorSpace

__all__ = ["TRANSFER_FUNCTIONS", "to_linear", "from_linear", "file_codes", "linear_table", "eotf_srgb",
           "eotf_inverse_srgb"]

_SRGB_LINEAR_KNEE = 0.0031308  # linear value where the toe meets the power curve
_SRGB_FILE_KNEE = _SRGB_LINEAR_KNEE * 12.92  # the same point as a file value (0.04045)


def _signed_power(values: np.ndarray, power: float) -> np.ndarray:
    return np.sign(values) * np.abs(values) ** power


def eotf_srgb(values: np.ndarray) -> np.ndarray:
    """sRGB file values -> linear values (float64)."""
    v = np.asarray(values, dtype=np.float64)
    return np.where(v <= _SRGB_FILE_KNEE, v / 12.92, _signed_power((v + 0.055) / 1.055, 2.4))


def eotf_inverse_srgb(values: np.ndarray) -> np.ndarray:
    """Linear values -> sRGB file values (float64)."""
    v = np.asarray(values, dtype=np.float64)
    return np.where(v <= _SRGB_LINEAR_KNEE, v * 12.92, 1.055 * _signed_power(v, 1 / 2.4) - 0.055)


def _identity(values: np.ndarray) -> np.ndarray:
    return np.asarray(values, dtype=np.float64)


# colour space -> (file value -> linear, linear -> file value)
TRANSFER_FUNCTIONS: dict[ColorSpace, tuple[Callable[[np.ndarray], np.ndarray], Callable[[np.ndarray], np.ndarray]]] = {
    ColorSpace.SRGB: (eotf_srgb, eotf_inverse_srgb),
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
    table = np.asarray(_functions(color_space)[0](codes), dtype=np.float64)
    table.setflags(write=False)
    return table


def file_codes(values: np.ndarray, dtype: str) -> np.ndarray | None:
    """Integer codes of normalised integer-file values (``None`` for float sample types)."""
    code_max = _CODE_MAX.get(dtype)
    if code_max is None:
        return None
    scaled = np.asarray(values, dtype=np.float32) * np.float32(code_max)
    return np.clip(np.rint(scaled), 0, code_max).astype(np.int32)


def linear_table(color_space: ColorSpace | str, dtype: str) -> np.ndarray | None:
    """Linear value of every code of an integer sample type (``None`` for float types)."""
    code_max = _CODE_MAX.get(dtype)
    return None if code_max is None else _decode_table(_colour_space(color_space), code_max)


def to_linear(values: np.ndarray, color_space: ColorSpace | str, dtype: str | None = None) -> np.ndarray:
    """File values -> linear values (float64).

    Parameters
    ----------
    values
        File values, any shape; integer files normalised to [0, 1].
    color_space
        ``sRGB`` (IEC 61966-2-1 EOTF, extended linearly below 0) or ``raw`` (unchanged).
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
    codes = file_codes(values, dtype or "")
    if codes is not None:
        return np.take(linear_table(cs, dtype), codes)
    return np.asarray(_functions(cs)[0](np.asarray(values, dtype=np.float64)), dtype=np.float64)


@lru_cache(maxsize=None)
def _code_thresholds(color_space: ColorSpace, code_max: int) -> np.ndarray:
    """Linear values at the code midpoints ``(k + 0.5) / code_max``, k = 0 .. code_max - 1."""
    mid = (np.arange(code_max, dtype=np.float64) + 0.5) / code_max
    return np.asarray(_functions(color_space)[0](mid), dtype=np.float64)


def from_linear(values: np.ndarray, color_space: ColorSpace | str, dtype: str | None = None) -> np.ndarray:
    """Linear values -> file values (float64); the inverse of :func:`to_linear`.

    Parameters
    ----------
    values
        Linear values, any shape.
    color_space
        ``sRGB`` or ``raw``.
    dtype
        The output file's sample type. For ``uint8`` / ``uint16`` the result is already the
        nearest code, ``k / code_max`` in [0, 1]: the code whose interval (between the
        EOTF of the code midpoints) holds the value, which is what rounding the
        inverse EOTF gives, found by table search.

    Returns
    -------
    np.ndarray
        File values, same shape, float64.

    Examples
    --------
    >>> float(from_linear(to_linear(np.array(0.5), "sRGB"), "sRGB").round(12))
    0.5
    >>> float(from_linear(np.array(0.2), "sRGB", "uint8") * 255)
    124.0
    """
    cs = _colour_space(color_space)
    v = np.asarray(values, dtype=np.float64)
    code_max = _CODE_MAX.get(dtype or "")
    if code_max is not None and cs is not ColorSpace.RAW:
        codes = np.searchsorted(_code_thresholds(cs, code_max), v, side="right")
        return codes / float(code_max)
    return np.asarray(_functions(cs)[1](v), dtype=np.float64)
