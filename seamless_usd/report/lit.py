"""A lit preview of a material from its stack: albedo, normal, roughness, metallic, occlusion.

Seams in normal and roughness maps hardly show in pictures of the maps; they show as soon as the
surface is lit from a low angle. This module builds the shading inputs from the maps of one stack
and shades them with one grazing directional light, a GGX specular term and a little ambient
light, seen from the side where its specular reflection lies:

* **albedo** (``diffuseColor``, ``base_color``, ...) in linear light: sRGB maps are decoded with
  the sRGB EOTF, raw maps are taken as linear;
* **normals**: a normal map reaches the network domain as unit tangent-space vectors already
  decoded with the map's scale/bias and Y convention (a DirectX map, authored with a negative Y
  scale, arrives as OpenGL +Y), so they are used as they are; +Y points up the picture;
* **roughness** / **metallic** / **occlusion**: file values ``(x + 1) / 2`` of the channel each
  role reads (a packed ORM map is one map with three roles);
* missing inputs take neutral values (grey clay albedo, roughness 0.5, metallic 0, occlusion 1).

A stack with none of these roles (opacity, displacement or emission maps alone) has no lit
preview: its maps are shown as they are.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from seamless_usd.textures import NORMAL_ROLES, ColorSpace

__all__ = [
    "ALBEDO_ROLES", "ROUGHNESS_ROLES", "METALLIC_ROLES", "OCCLUSION_ROLES",
    "Light", "GRAZING_LIGHT", "ShadingInputs", "shading_inputs", "shade", "exposure_for", "to_display",
]

ALBEDO_ROLES = frozenset({"diffuseColor", "base_color", "baseColor", "basecolor", "albedo", "diffuse_color"})
ROUGHNESS_ROLES = frozenset({"roughness", "specular_roughness", "specularRoughness"})
METALLIC_ROLES = frozenset({"metallic", "metalness"})
OCCLUSION_ROLES = frozenset({"occlusion", "ambientOcclusion", "ambient_occlusion"})

_CLAY = 0.35  # linear albedo of a stack without a colour map
_ROUGHNESS = 0.5  # roughness of a stack without a roughness map


def _direction(azimuth: float, elevation: float) -> np.ndarray:
    az, el = np.radians(azimuth), np.radians(elevation)
    return np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])


@dataclass(frozen=True)
class Light:
    """A directional light and the viewer.

    ``azimuth`` (degrees, 0 = from the right, 90 = from the top of the picture) and ``elevation``
    above the surface (degrees; low = grazing) place the light; ``intensity`` is its irradiance at
    normal incidence, ``ambient`` the ambient fraction. The viewer looks from ``view_elevation``
    on the side opposite the light, where a flat surface's specular lobe lies, so roughness
    changes show (the picture itself stays laid out as the texture).
    """

    azimuth: float = 135.0
    elevation: float = 20.0
    intensity: float = 4.0
    ambient: float = 0.12
    view_elevation: float = 50.0

    @property
    def direction(self) -> np.ndarray:
        return _direction(self.azimuth, self.elevation)

    @property
    def view(self) -> np.ndarray:
        return _direction(self.azimuth + 180.0, self.view_elevation)


#: The report's light: from the top left, 20 degrees above the surface.
GRAZING_LIGHT = Light()


@dataclass
class ShadingInputs:
    """Per-pixel shading inputs on one grid; ``used`` names what came from the stack."""

    albedo: np.ndarray  # (H, W, 3) linear
    normal: np.ndarray  # (H, W, 3) unit tangent-space vectors
    roughness: np.ndarray  # (H, W)
    metallic: np.ndarray  # (H, W)
    occlusion: np.ndarray  # (H, W)
    used: list[str] = field(default_factory=list)


def _srgb_to_linear(v: np.ndarray) -> np.ndarray:
    v = np.clip(v, 0.0, 1.0)
    out = v / np.float32(12.92)
    curve = v > 0.04045
    out[curve] = np.power((v[curve] + np.float32(0.055)) / np.float32(1.055), np.float32(2.4))
    return out


def _role_channels(m, role_channels: str, values: np.ndarray) -> np.ndarray:
    """The network channels of ``values`` that a role reading ``role_channels`` sees."""
    used = m.channels_used or "rgba"[: values.shape[2]]
    idx = [min(used.index(c) if c in used else 0, values.shape[2] - 1) for c in role_channels]
    return values[..., idx]


def _normals(values: np.ndarray) -> np.ndarray:
    n = np.clip(values[..., :3], -1.0, 1.0)
    if n.shape[2] == 2:
        z = np.sqrt(np.clip(1.0 - n[..., 0] ** 2 - n[..., 1] ** 2, 0.0, None))
        n = np.concatenate([n, z[..., None]], axis=2)
    if n.shape[2] < 3:  # one channel: not a usable normal map
        return np.broadcast_to(np.array([0.0, 0.0, 1.0]), values.shape[:2] + (3,)).copy()
    length = np.sqrt(np.square(n).sum(axis=2, keepdims=True))
    return np.where(length > 1e-8, n / np.maximum(length, np.float32(1e-8)), np.array([0.0, 0.0, 1.0], n.dtype))


def shading_inputs(maps: Sequence, values: Sequence[np.ndarray]) -> ShadingInputs | None:
    """The shading inputs of a stack's maps, all on one grid (same ``(H, W)``), network domain.

    Parameters
    ----------
    maps : the stack's ``TextureMap``s (roles, channels, colour space, ``is_normal``).
    values : per map, ``(H, W, C)`` in ``[-1, 1]``: sRGB maps still sRGB-encoded, normal maps as
        decoded unit vectors.

    Returns
    -------
    ShadingInputs, or None when no map has an albedo, normal, roughness, metallic or occlusion role.
    """
    if not maps:
        return None
    shape = np.asarray(values[0]).shape[:2]
    f32 = np.float32  # preview pictures: single precision halves the time of every step
    out = ShadingInputs(
        albedo=np.full(shape + (3,), _CLAY, f32),
        normal=np.broadcast_to(np.array([0.0, 0.0, 1.0], f32), shape + (3,)).copy(),
        roughness=np.full(shape, _ROUGHNESS, f32), metallic=np.zeros(shape, f32), occlusion=np.ones(shape, f32),
    )
    for m, v in zip(maps, values):
        v = np.asarray(v, dtype=f32)
        if v.ndim == 2:
            v = v[..., None]
        if v.shape[:2] != shape:
            raise ValueError(f"maps must share one grid: {v.shape[:2]} vs {shape}")
        for r in m.roles:
            if r.role in NORMAL_ROLES:
                out.normal = _normals(v)
            elif r.role in ALBEDO_ROLES:
                c = (_role_channels(m, r.channels[:3] or "rgb", v) + 1.0) * 0.5
                if c.shape[2] < 3:
                    c = np.repeat(c[..., :1], 3, axis=2)
                linear = m.color_space in (ColorSpace.RAW, "raw")
                out.albedo = np.clip(c, 0.0, 1.0) if linear else _srgb_to_linear(c)
            elif r.role in ROUGHNESS_ROLES:
                out.roughness = np.clip((_role_channels(m, r.channels[:1] or "r", v)[..., 0] + 1.0) * 0.5, 0.0, 1.0)
            elif r.role in METALLIC_ROLES:
                out.metallic = np.clip((_role_channels(m, r.channels[:1] or "r", v)[..., 0] + 1.0) * 0.5, 0.0, 1.0)
            elif r.role in OCCLUSION_ROLES:
                out.occlusion = np.clip((_role_channels(m, r.channels[:1] or "r", v)[..., 0] + 1.0) * 0.5, 0.0, 1.0)
            else:
                continue
            out.used.append(r.role)
    return out if out.used else None


def shade(inputs: ShadingInputs, light: Light = GRAZING_LIGHT) -> np.ndarray:
    """Linear radiance ``(H, W, 3)`` under ``light``, seen from ``light.view``.

    Lambert diffuse plus GGX specular (Trowbridge-Reitz distribution, Smith-Schlick geometry,
    Schlick Fresnel with F0 = 0.04 for dielectrics and the albedo for metals), and an ambient term
    scaled by occlusion.

    Examples
    --------
    >>> flat = ShadingInputs(np.full((1, 1, 3), 0.5), np.array([[[0.0, 0.0, 1.0]]]),
    ...                      np.full((1, 1), 0.5), np.zeros((1, 1)), np.ones((1, 1)))
    >>> bool(shade(flat)[0, 0, 0] > 0)
    True
    """
    f32 = np.float32
    n = np.asarray(inputs.normal, dtype=f32)
    L = light.direction
    V = light.view
    H = (L + V) / np.linalg.norm(L + V)
    nl = np.clip(n @ L.astype(f32), 0.0, None)
    nv = np.clip(n @ V.astype(f32), 1e-4, None)
    nh = np.clip(n @ H.astype(f32), 0.0, None)
    vh = float(np.clip(V @ H, 0.0, 1.0))
    alpha = np.square(np.maximum(np.asarray(inputs.roughness, dtype=f32), f32(0.04)))
    a2 = np.square(alpha)
    d = np.square(nh, out=nh)  # float32 and in place: a report's pictures are shaded on every stack
    d *= a2 - 1.0
    d += 1.0
    np.square(d, out=d)
    d *= f32(np.pi)
    np.divide(a2, d, out=d)
    k = alpha * f32(0.5)
    g = nl / (nl * (1 - k) + k)
    g *= nv / (nv * (1 - k) + k)
    g *= d
    g /= np.maximum(f32(4.0) * nl * nv, f32(1e-4))  # d g / (4 nl nv): the specular term less its Fresnel
    albedo = np.asarray(inputs.albedo, dtype=f32)
    metal = np.asarray(inputs.metallic, dtype=f32)[..., None]
    schlick = f32((1 - vh) ** 5)
    f = f32(0.04) * (1 - metal) + albedo * metal  # F0
    f += (1 - f) * schlick
    out = (1 - f) * (1 - metal) * albedo
    out *= f32(1 / np.pi)
    out += f * g[..., None]
    out *= (light.intensity * nl)[..., None]
    out += f32(light.ambient) * albedo * (1 - f32(0.9) * metal) * np.asarray(inputs.occlusion, dtype=f32)[..., None]
    return out


def exposure_for(radiance: np.ndarray, mean: float = 0.22) -> float:
    """The exposure that brings the mean luminance of ``radiance`` to ``mean`` (within 1/4 to 16).

    Computed once from the source and applied to source and tile alike, so a dark albedo still
    shows its relief and the two pictures stay comparable.
    """
    lum = float(np.mean(np.asarray(radiance, dtype=np.float64) @ np.array([0.2126, 0.7152, 0.0722])))
    return float(np.clip(mean / max(lum, 1e-6), 0.25, 16.0))


def to_display(radiance: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Linear radiance times ``exposure`` to sRGB uint8, with a soft shoulder above 0.8 instead of a clip."""
    x = np.maximum(np.asarray(radiance, dtype=np.float32) * np.float32(exposure), np.float32(0.0))
    knee = np.float32(0.8)
    high = x > knee  # the shoulder only where it applies (few texels), the sRGB curve above its linear foot
    x[high] = knee + (1 - knee) * (1 - np.exp(-(x[high] - knee) / (1 - knee)))
    curve = x > np.float32(0.0031308)
    v = x * np.float32(12.92)
    v[curve] = np.float32(1.055) * np.power(x[curve], np.float32(1 / 2.4)) - np.float32(0.055)
    return (np.clip(v, 0.0, 1.0) * np.float32(255.0) + np.float32(0.5)).astype(np.uint8)
