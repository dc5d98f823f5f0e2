"""Which colour encoding a map's stored values use, with the DESIGN.md precedence.

1. ``inputs:sourceColorSpace`` when ``sRGB`` or ``raw`` (UsdUVTexture);
2. ``colorSpace`` metadata on the file attribute;
3. MaterialX ``colorspace`` (on the input, inherited from its node, graph or document);
4. ``auto``: what the file header states, else sRGB for 8-bit 3/4-channel files, else raw
   (the UsdPreviewSurface specification).

A data role (roughness, normal, ...) whose map resolves to sRGB keeps that encoding (it is what the
renderer decodes, so the look is preserved) and is reported with a warning.
"""
from __future__ import annotations

from dataclasses import dataclass

from seamless_usd.discover.tokens import Codes, Roles
from seamless_usd.textures import ColorSpace, ImageInfo, RoleUse
from seamless_usd.findings import Finding, Severity

__all__ = ["Label", "classify", "resolve_color_space", "mismatch_finding", "is_color_role"]

_SRGB_PREFIXES = ("srgb", "g22", "g24", "g18", "gamma", "sRGB".lower())
_RAW_NAMES = frozenset({"raw", "data", "none", "non-color", "utility - raw", "acescg", "aces2065-1", "adx10", "adx16"})
_RAW_PREFIXES = ("lin", "scene-linear", "scene_linear", "aces", "acescg")


@dataclass(frozen=True)
class Label:
    """A colour-space name as found, and where it was found (for ``color_space_reason``)."""

    name: str
    source: str  # "inputs:sourceColorSpace", "colorSpace metadata", "MaterialX colorspace"
    understood: bool = True  # False: a value its input does not take (a renderer passes it over too)


def classify(name: str | None) -> ColorSpace | None:
    """Map a colour-space name (USD, MaterialX, OCIO, file header) to sRGB or raw; None if unknown.

    >>> classify("srgb_texture"), classify("lin_rec709"), classify("auto")
    (<ColorSpace.SRGB: 'sRGB'>, <ColorSpace.RAW: 'raw'>, None)
    """
    if not name:
        return None
    n = name.strip().lower()
    if n.startswith(_SRGB_PREFIXES):
        return ColorSpace.SRGB
    if n in _RAW_NAMES or n.startswith(_RAW_PREFIXES) or n == "linear":
        return ColorSpace.RAW
    return None


def is_color_role(role: str) -> bool:
    return role in Roles.COLOR


def resolve_color_space(
    labels: list[Label], image: ImageInfo | None
) -> tuple[ColorSpace, str, list[str]]:
    """Apply the precedence; ``labels`` in precedence order (``auto`` and empty names are skipped).

    Returns the colour space, the reason, and the names that were not understood (each reported
    by the caller, then passed over).
    """
    unknown: list[str] = []
    for label in labels:
        if not label.name or label.name.lower() == "auto":
            continue
        cs = classify(label.name) if label.understood else None
        if cs is None:
            unknown.append(label.name)
            continue
        return cs, f"{label.source} ({label.name})", unknown
    if image is not None:
        stated = classify(image.color_space)
        if stated is not None:
            return stated, f"auto: file header ({image.color_space})", unknown
        if image.dtype == "uint8" and image.channels in (3, 4):
            return ColorSpace.SRGB, f"auto: 8-bit {'RGB' if image.channels == 3 else 'RGBA'}", unknown
        return ColorSpace.RAW, f"auto: {image.dtype} {image.channels}-channel", unknown
    return ColorSpace.RAW, "auto: no header", unknown


def mismatch_finding(roles: tuple[RoleUse, ...], cs: ColorSpace, reason: str, where: str) -> Finding | None:
    """A warning when a data role reads a colour channel of a map that resolves to sRGB (the sRGB curve applies to
    red, green and blue only: opacity read from alpha is not affected)."""
    if cs is not ColorSpace.SRGB:
        return None
    data = [r.role for r in roles if not is_color_role(r.role) and set(r.channels) - {"a"}]
    if not data:
        return None
    return Finding(
        Severity.WARNING,
        Codes.COLORSPACE_MISMATCH,
        where,
        f"data role {', '.join(sorted(set(data)))} reads a map decoded as sRGB ({reason}); "
        "kept as declared: set the source colour space to raw if that is wrong",
    )
