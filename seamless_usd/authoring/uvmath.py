"""2D affine maps of texture coordinates: UsdTransform2d, MaterialX place2d, scales.

A UV chain is a composition of affine maps ``uv -> M uv + t``. The UV scale that keeps the
pattern's real-world size is applied after the whole chain: ``uv_new = S (M uv + t)`` with
``S = diag(W / 2c_w, H / 2c_h)``, so texel offsets in working pixels are unchanged:
``(uv_new(p) - uv_new(q)) * 2c = (uv_old(p) - uv_old(q)) * (W, H)``.

A tile made from the source turned clockwise by ``d`` degrees (``process --straighten``) is turned back in texel
units: ``uv_new = S P^-1 R(-d) P (M uv + t)`` with ``P = diag(1, H / W)`` (v in units of the source's width, so
the turn keeps texels square) and ``R(-d)`` the UVs turned clockwise by ``d``, which shows the tile turned
counter-clockwise by ``d``, as the source ran. Two nodes make it: the turn ``R(-d) P`` and the scale
``S P^-1``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["Affine2", "transform2d", "place2d", "scale2d", "turned_scale", "turn_inputs", "turn_of_inputs",
           "scale_node_value", "total_from_node", "composed_turn"]


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


def turned_scale(scale: tuple[float, float], degrees: float, aspect: float) -> Affine2:
    """The whole UV edit of a tile at UV ``scale`` turned back by ``degrees`` (the source, ``aspect`` = H / W texels,
    was turned clockwise by them before it was tiled): the turn, then the scale (module docstring)."""
    return transform2d((1.0, aspect), -degrees).then(scale2d((scale[0], scale[1] / aspect)))


def turn_inputs(degrees: float, aspect: float, place: bool) -> tuple[tuple[float, float], float]:
    """(scale, rotation) of the turn node: a UsdTransform2d's (scale multiplies, ``rotation`` turns counter-clockwise)
    or, with ``place``, a place2d's (scale divides, ``rotate`` turns clockwise)."""
    if place:
        return (1.0, 1.0 / aspect), float(degrees)
    return (1.0, float(aspect)), -float(degrees)


def turn_of_inputs(scale: tuple[float, float], rotation: float, place: bool) -> tuple[float, float]:
    """(degrees, aspect) of a turn node holding ``scale`` and ``rotation`` (:func:`turn_inputs` undone)."""
    if place:
        return float(rotation), 1.0 / float(scale[1])
    return -float(rotation), float(scale[1])


def scale_node_value(total: tuple[float, float], aspect: float, place: bool) -> tuple[float, float]:
    """The scale input of the UV scale node for a ``total`` UV scale after a turn in units of ``aspect`` (1: no
    turn); a place2d divides."""
    u, v = float(total[0]), float(total[1]) / aspect
    return (1.0 / u, 1.0 / v) if place else (u, v)


def total_from_node(value: tuple[float, float], aspect: float, place: bool) -> tuple[float, float]:
    """The total UV scale a scale node holding ``value`` applies (:func:`scale_node_value` undone)."""
    u, v = (1.0 / value[0], 1.0 / value[1]) if place else (float(value[0]), float(value[1]))
    return (u, v * aspect)


def composed_turn(prior: tuple[float, float, float, float], scale: tuple[float, float], turn, from_source: bool
                  ) -> tuple[tuple[float, float], float, float]:
    """(total UV scale, degrees, aspect) the UV nodes a run before inserted must hold now: ``prior`` is what they
    hold (total scale u, v, degrees, aspect), ``scale`` and ``turn`` (a :class:`.types.UVTurn` or None) this run's.
    Made from the source, this run's replace them; made from an earlier tile, they compose: the scales multiply
    and the turns add, in the first source's texel units (its aspect is the tile's times the first scale's ratio).
    No turn: aspect 1."""
    pu, pv, prior_degrees, prior_aspect = prior
    total = scale if from_source else (pu * scale[0], pv * scale[1])
    degrees, aspect = (turn.degrees, turn.aspect) if turn else (0.0, 1.0)
    if not from_source and (prior_degrees or degrees):
        degrees += prior_degrees
        aspect = prior_aspect if prior_degrees else aspect * pv / pu
    return total, degrees, (aspect if degrees else 1.0)
