"""2D affine maps of texture coordinates: UsdTransform2d, MaterialX place2d, scales.

A UV chain is a composition of affine maps ``uv -> M uv + t``. The UV scale that keeps the
pattern's real-world size is applied after the whole chain: ``uv_new = S (M uv + t)`` with
``S = diag(W / 2c_w, H / 2c_h)``, so texel offsets in working pixels are unchanged:
``(uv_new(p) - uv_new(q)) * 2c = (uv_old(p) - uv_old(q)) * (W, H)``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Affine2", "transform2d", "place2d", "scale2d"]


@dataclass(frozen=True)
class Affine2:
    """``(x, y) -> (a x + b y + tx, c x + d y + ty)``."""

    a: float = 1.0
    b: float = 0.0
    c: float = 0.0
    d: float = 1.0
    tx: float = 0.0
    ty: float = 0.0

    def __call__(self, uv: tuple[float, float]) -> tuple[float, float]:
        x, y = uv
        return (self.a * x + self.b * y + self.tx, self.c * x + self.d * y + self.ty)

    def then(self, after: "Affine2") -> "Affine2":
        """The map that applies ``self`` first, then ``after``."""
        o = after
        return Affine2(
            a=o.a * self.a + o.b * self.c,
            b=o.a * self.b + o.b * self.d,
            c=o.c * self.a + o.d * self.c,
            d=o.c * self.b + o.d * self.d,
            tx=o.a * self.tx + o.b * self.ty + o.tx,
            ty=o.c * self.tx + o.d * self.ty + o.ty,
        )

    def close_to(self, other: "Affine2", tol: float = 1e-9) -> bool:
        return all(
            abs(x - y) <= tol * max(1.0, abs(x), abs(y))
            for x, y in zip(self.astuple(), other.astuple())
        )

    def astuple(self) -> tuple[float, ...]:
        return (self.a, self.b, self.c, self.d, self.tx, self.ty)


def scale2d(scale: tuple[float, float]) -> Affine2:
    """``uv -> (sx u, sy v)``."""
    return Affine2(a=float(scale[0]), d=float(scale[1]))


def transform2d(
    scale: tuple[float, float] = (1.0, 1.0),
    rotation: float = 0.0,
    translation: tuple[float, float] = (0.0, 0.0),
) -> Affine2:
    """UsdTransform2d: scale, then rotate counter-clockwise by ``rotation`` degrees, then translate."""
    r = math.radians(rotation)
    cs, sn = math.cos(r), math.sin(r)
    sx, sy = scale
    return Affine2(a=cs * sx, b=-sn * sy, c=sn * sx, d=cs * sy, tx=translation[0], ty=translation[1])


def place2d(
    pivot: tuple[float, float] = (0.0, 0.0),
    scale: tuple[float, float] = (1.0, 1.0),
    rotate: float = 0.0,
    offset: tuple[float, float] = (0.0, 0.0),
    operation_order: int = 0,
) -> Affine2:
    """MaterialX ``place2d`` (stdlib NG_place2d_vector2).

    Order 0 (SRT): ``rot((uv - pivot) / scale) - offset + pivot``; order 1 (TRS):
    ``rot(uv - pivot - offset) / scale + pivot``. ``scale`` divides, and MaterialX ``rotate2d``
    turns clockwise by ``rotate`` degrees.
    """
    r = math.radians(rotate)
    cs, sn = math.cos(r), math.sin(r)
    rot = Affine2(a=cs, b=sn, c=-sn, d=cs)
    px, py = pivot
    to_pivot = Affine2(tx=-px, ty=-py)
    inv_scale = scale2d((1.0 / scale[0], 1.0 / scale[1]))
    back = Affine2(tx=px, ty=py)
    off = Affine2(tx=-offset[0], ty=-offset[1])
    if operation_order == 0:
        return to_pivot.then(inv_scale).then(rot).then(off).then(back)
    return to_pivot.then(off).then(rot).then(inv_scale).then(back)
