"""The source as a stack's tile was made from it: turned until its lines run along the axes (``--straighten``,
:mod:`.imaging.straighten`), with its light levelled (:mod:`.imaging.level`) when the cut made of the levelled
maps is the one that passed, or with its drifting lattice evened (:mod:`.synthesis.lattice.drift`) when the
cut of the evened maps is. The tile is judged against the source made so, in ``process`` as in
``check``, and its UV scale is brought back to the source's texel density.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["straighten", "made_values", "as_made", "source_uv_scale", "on_tile_grid", "uv_turn_of"]


def straighten(pixels, normals: list[bool], uv_turn: bool = False):
    """(pixels, facts): the stack's maps rectified where their near-vertical lines converge with perspective
    (:mod:`.imaging.perspective`, ``facts["rectified"]``), then turned until their lines run along the axes, when
    they are turned (:func:`.imaging.orientation.dominant_orientation`), and what was found and done. ``uv_turn``:
    the turn is to be authored in the asset's UVs (``facts["uv_turn"]``), so normal maps keep the source's vectors;
    never for a rectified stack, whose keystone no UV transform undoes (it is written rectified)."""
    from seamless_usd.imaging.orientation import dominant_orientation
    from seamless_usd.imaging.perspective import find_keystone

    facts = {"degrees": 0.0, "source_size": list(pixels.working_size)}
    keystone = find_keystone(pixels.values)
    if keystone is not None:
        try:
            rectified = _with_values(pixels, made_values(pixels.values, normals, rectified=keystone))
        except ValueError:  # it keeps too little of a map of another size: the stack is left as it is
            rectified = None
        if rectified is not None:
            pixels = rectified
            facts.update(rectified=keystone.as_dict(), size=list(pixels.working_size))
            uv_turn = False
    found = dominant_orientation(pixels.values)
    facts["orientation"] = found.as_dict()
    if not found.straightens:
        return pixels, facts
    done = _with_values(pixels, made_values(pixels.values, normals, found.degrees, turn_vectors=not uv_turn))
    facts.update(degrees=found.degrees, size=list(done.working_size), **({"uv_turn": True} if uv_turn else {}))
    return done, facts


def made_values(values, normals: list[bool], degrees: float = 0.0, levelled: bool = False,
                evened: bool = False, turn_vectors: bool = True, rectified=None) -> list[np.ndarray]:
    """``values`` (the source's maps) made as the tile's source was: turned clockwise by ``degrees`` and cut to
    source texels (:mod:`.imaging.straighten`), then, with ``levelled``, their light levelled
    (:func:`.imaging.level.level_maps`), with ``evened``, their lattice evened
    (:func:`.synthesis.lattice.drift.even_lattice`); ``turn_vectors``: normal maps' vectors turn with the picture
    (not where the turn is authored in the asset's UVs); ``rectified`` (a :class:`.imaging.perspective.Keystone`):
    rectified first. ``process`` and ``check`` both make the source so."""
    out = list(values)
    if rectified is not None:
        from seamless_usd.imaging.perspective import rectify_maps

        out = rectify_maps(out, normals, rectified)
    if degrees:
        from seamless_usd.imaging.straighten import straighten_maps

        out = straighten_maps(out, normals, degrees, turn_vectors)
    if levelled:
        from seamless_usd.imaging.level import level_maps

        out = level_maps(out, normals)[0]
    if evened:
        from seamless_usd.synthesis.lattice.drift import even_lattice

        out = even_lattice(out, normals)[0]
    return out


def as_made(pixels, normals: list[bool], straightened_facts: dict | None, levelled_facts: dict | None,
            evened_facts: dict | None = None):
    """``pixels`` made as the tile's source was (:func:`made_values`), from the facts recorded: the turn when one
    was made, the levelling or the evening when it was."""
    turn = straightened_facts["degrees"] if straightened_facts and straightened_facts.get("size") else 0.0
    rectified = (straightened_facts or {}).get("rectified")
    if rectified:
        from seamless_usd.imaging.perspective import Keystone

        rectified = Keystone(*rectified["vanishing"], rectified["spread"])
    if not turn and not rectified and not levelled_facts and not evened_facts:
        return pixels
    vectors = not (straightened_facts or {}).get("uv_turn")
    return _with_values(pixels, made_values(pixels.values, normals, turn, bool(levelled_facts), bool(evened_facts),
                                            vectors, rectified))


def _with_values(pixels, values: list[np.ndarray]):
    """``pixels`` holding ``values``, its working size theirs."""
    h, w = values[0].shape[:2]
    return dataclasses.replace(pixels, values=tuple(values), working_size=(w, h))


def uv_turn_of(straightened_facts: dict | None) -> tuple[float, float] | None:
    """(degrees, the source's height over width) of the turn the asset's UVs give a straightened tile back; None
    when none is authored (not turned, ``--write-straight``, rectified, or a map whose UVs cannot turn)."""
    facts = straightened_facts or {}
    if not facts.get("uv_turn") or not facts.get("size") or not facts.get("degrees"):
        return None
    width, height = facts["source_size"]
    return float(facts["degrees"]), float(height) / float(width)


def source_uv_scale(uv_scale, straightened_facts: dict | None) -> tuple[float, float]:
    """The UV scale that keeps the source's texel density: ``uv_scale`` was read against the maps the tile was
    made from, which straightening cut smaller than the source (its texels keep their size)."""
    u, v = (float(x) for x in uv_scale)
    if straightened_facts and straightened_facts.get("size"):
        (sw, sh), (w, h) = straightened_facts["source_size"], straightened_facts["size"]
        u, v = u * sw / w, v * sh / h
    return (u, v)


def on_tile_grid(sources: list[np.ndarray], normals: list[bool], tile_hw: tuple[int, int],
                 uv_scale: tuple[float, float]) -> list[np.ndarray]:
    """The sources resampled to the texel grid of the tile (the UV square holds ``uv_scale`` tiles), so
    a tile at the GAN's working resolution is measured against a source at that resolution, not at full."""
    from seamless_usd.synthesis import MapInput, downsample_maps

    grid = (round(tile_hw[0] * uv_scale[1]), round(tile_hw[1] * uv_scale[0]))
    if grid == tuple(sources[0].shape[:2]):
        return sources
    maps = [MapInput(f"m{i}", s, n) for i, (s, n) in enumerate(zip(sources, normals))]
    return [m.pixels for m in downsample_maps(maps, grid)]
