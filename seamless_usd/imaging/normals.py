"""Normal maps: file values <-> unit vectors with the map's UsdUVTexture scale and bias.

A renderer reads ``n = value * scale + bias`` per channel. The conventional tangent-space map
has scale (2, 2, 2) and bias (-1, -1, -1); a map in the other Y convention (DirectX style) is
declared with a negative Y scale, (2, -2, 2) and (-1, 1, -1). Decoding applies the declared
numbers, so every normal map reaches the network in the shader's convention, and encoding
inverts them, so the output is stored in the source's convention.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["DEFAULT_NORMAL_SCALE", "DEFAULT_NORMAL_BIAS", "normal_scale_bias", "renormalise", "stored_unit_tolerance",
           "decode_normals", "encode_normals"]

DEFAULT_NORMAL_SCALE = (2.0, 2.0, 2.0)
DEFAULT_NORMAL_BIAS = (-1.0, -1.0, -1.0)
_FLAT = np.array([0.0, 0.0, 1.0])


def normal_scale_bias(
    scale: tuple[float, ...], bias: tuple[float, ...]
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """The xyz scale and bias a normal map is decoded with.

    The identity (scale 1, bias 0: nothing authored, or a MaterialX ``normalmap`` node, which
    applies ``2 * value - 1`` itself) means the conventional (2, 2, 2) / (-1, -1, -1).

    Raises
    ------
    ValueError
        When a scale component is 0 (the map could not be inverted).

    Examples
    --------
    >>> normal_scale_bias((1, 1, 1, 1), (0, 0, 0, 0))
    ((2.0, 2.0, 2.0), (-1.0, -1.0, -1.0))
    >>> normal_scale_bias((2, -2, 2, 1), (-1, 1, -1, 0))
    ((2.0, -2.0, 2.0), (-1.0, 1.0, -1.0))
    """
    s = tuple(float(v) for v in scale[:3])
    b = tuple(float(v) for v in bias[:3])
    if s == (1.0, 1.0, 1.0) and b == (0.0, 0.0, 0.0):
        return DEFAULT_NORMAL_SCALE, DEFAULT_NORMAL_BIAS
    if any(v == 0.0 for v in s):
        raise ValueError(f"normal map scale {s} has a zero component; it cannot be inverted")
    return s, b  # type: ignore[return-value]


def renormalise(vectors: np.ndarray, keep_within: float = 0.0) -> np.ndarray:
    """Unit vectors along the last axis (length 3); zero-length vectors become (0, 0, 1).

    Vectors whose length is within ``keep_within`` of 1 are kept as they are: a unit vector stored in a
    file is that far off at most (:func:`stored_unit_tolerance`), and a texel copied from the source
    then encodes back to its own stored codes instead of moving by a step.

    Examples
    --------
    >>> renormalise(np.array([[0.0, 0.0, 2.0], [0.0, 0.0, 0.0]])).tolist()
    [[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]
    >>> renormalise(np.array([[0.0, 0.0, 1.001], [0.0, 0.0, 1.01]]), keep_within=0.002).tolist()
    [[0.0, 0.0, 1.001], [0.0, 0.0, 1.0]]
    """
    v = np.asarray(vectors, dtype=np.float64)
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    tiny = length < 1e-12
    kept = np.abs(length - 1.0) <= keep_within
    return np.where(tiny, _FLAT, v / np.where(tiny | kept, 1.0, length))


def stored_unit_tolerance(file_step: float, scale) -> float:
    """How far from 1 the length of a unit normal can be once stored: each component rounded by half a
    ``file_step`` (the stored values' spacing, linear), times the scale that maps them to the vector.

    >>> round(stored_unit_tolerance(1 / 65535, (2.0, 2.0, 2.0)), 7)
    2.64e-05
    """
    return math.sqrt(3.0) * file_step / 2.0 * max(abs(float(v)) for v in scale)


def decode_normals(values: np.ndarray, scale, bias, keep_within: float = 0.0) -> np.ndarray:
    """Linear file values ``(..., 3)`` -> unit vectors ``value * scale + bias``, renormalised
    (``keep_within`` as in :func:`renormalise`)."""
    v = np.asarray(values, dtype=np.float64)
    return renormalise(v * np.asarray(scale, np.float64) + np.asarray(bias, np.float64), keep_within)


def encode_normals(vectors: np.ndarray, scale, bias, keep_within: float = 0.0) -> np.ndarray:
    """Vectors ``(..., 3)`` -> linear file values: renormalise (``keep_within`` as in
    :func:`renormalise`), then ``(n - bias) / scale``."""
    n = renormalise(vectors, keep_within)
    return (n - np.asarray(bias, np.float64)) / np.asarray(scale, np.float64)


def encoding_doubt(values: np.ndarray, scale, bias) -> str | None:
    """Why the xyz file values ``(H, W, 3)`` do not read as a tangent-space normal map with this scale and bias
    (None when they do): decoded, a normal map's vectors are near unit length and face the surface (z > 0).
    A signed float map read with the 0-1 scale and bias, a colour or height map wired as a normal, or a wrong
    bias shows as lengths far from 1 or many vectors facing away. Read on at most 64 x 64 texels."""
    v = np.asarray(values, dtype=np.float64)
    step = max(1, max(v.shape[:2]) // 64)
    v = v[::step, ::step].reshape(-1, 3) * np.asarray(scale, np.float64) + np.asarray(bias, np.float64)
    v = v[np.isfinite(v).all(axis=1)]
    if not len(v):
        return None
    length = float(np.median(np.linalg.norm(v, axis=1)))
    away = float((v[:, 2] < 0).mean())
    if 0.8 <= length <= 1.25 and away <= 0.2:
        return None
    return (f"does not read as a tangent-space normal map with scale {tuple(round(float(s), 3) for s in scale)} "
            f"and bias {tuple(round(float(b), 3) for b in bias)}: decoded, its vectors' median length is "
            f"{length:.2f} (a normal map's is 1) and {100 * away:.0f} % face away (z < 0); check the "
            "inputs' scale and bias, and that a normal map is connected")


def signed_as_stored(scale, bias, dtype: str, values: np.ndarray) -> bool:
    """Whether a normal map is read as stored (scale 1, bias 0): nothing authored (the identity, which otherwise
    means the conventional 2 and -1) on a float file whose xyz hold negative values, as a signed map does."""
    identity = all(float(v) == 1.0 for v in scale[:3]) and all(float(v) == 0.0 for v in bias[:3])
    if not identity or dtype not in ("half", "float", "double"):
        return False
    xyz = np.asarray(values)[..., :3]
    return xyz.shape[-1] == 3 and float(np.nanmin(xyz)) < -0.01
