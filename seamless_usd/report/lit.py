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
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


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
    length = np.linalg.norm(n, axis=2, keepdims=True)
    return np.where(length > 1e-8, n / np.maximum(length, 1e-8), np.array([0.0, 0.0, 1.0]))


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
    out = ShadingInputs(
        albedo=np.full(shape + (3,), _CLAY), normal=np.broadcast_to(np.array([0.0, 0.0, 1.0]), shape + (3,)).copy(),
        roughness=np.full(shape, _ROUGHNESS), metallic=np.zeros(shape), occlusion=np.ones(shape),
    )
    for m, v in zip(maps, values):
        v = np.asarray(v, dtype=np.float64)
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
    n = inputs.normal
    L = light.direction
    V = light.view
    H = (L + V) / np.linalg.norm(L + V)
    nl = np.clip(n @ L, 0.0, None)[..., None]
    nv = np.clip(n @ V, 1e-4, None)[..., None]
    nh = np.clip(n @ H, 0.0, None)[..., None]
    vh = float(np.clip(V @ H, 0.0, 1.0))
    alpha = np.maximum(inputs.roughness, 0.04)[..., None] ** 2
    a2 = alpha ** 2
    d = a2 / (np.pi * (nh ** 2 * (a2 - 1.0) + 1.0) ** 2)
    k = alpha / 2.0
    g = (nl / (nl * (1 - k) + k)) * (nv / (nv * (1 - k) + k))
    metal = inputs.metallic[..., None]
    f0 = 0.04 * (1 - metal) + inputs.albedo * metal
    f = f0 + (1 - f0) * (1 - vh) ** 5
    specular = d * g * f / np.maximum(4.0 * nl * nv, 1e-4)
    diffuse = (1 - f) * (1 - metal) * inputs.albedo / np.pi
    direct = (diffuse + specular) * light.intensity * nl
    ambient = light.ambient * inputs.albedo * (1 - 0.9 * metal) * inputs.occlusion[..., None]
    return direct + ambient


def exposure_for(radiance: np.ndarray, mean: float = 0.22) -> float:
    """The exposure that brings the mean luminance of ``radiance`` to ``mean`` (within 1/4 to 16).

    Computed once from the source and applied to source and tile alike, so a dark albedo still
    shows its relief and the two pictures stay comparable.
    """
    lum = float(np.mean(np.asarray(radiance, dtype=np.float64) @ np.array([0.2126, 0.7152, 0.0722])))
    return float(np.clip(mean / max(lum, 1e-6), 0.25, 16.0))


def to_display(radiance: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Linear radiance times ``exposure`` to sRGB uint8, with a soft shoulder above 0.8 instead of a clip."""
    x = np.maximum(np.asarray(radiance, dtype=np.float64) * exposure, 0.0)
    knee = 0.8
    x = np.where(x <= knee, x, knee + (1 - knee) * (1 - np.exp(-(x - knee) / (1 - knee))))
    v = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0.0031308), 1 / 2.4) - 0.055)
    return (np.clip(v, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
