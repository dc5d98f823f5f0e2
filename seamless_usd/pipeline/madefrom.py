"""The source as a stack's tile was made from it: turned until its lines run along the axes (``--straighten``,
:mod:`.imaging.straighten`), with its light levelled (:mod:`.imaging.level`) when the cut made of the levelled
maps is the one that passed, or with its drifting lattice evened (:mod:`.synthesis.lattice.drift`) when the
cut of the evened maps is. The tile is judged against the source made so, in ``process`` as in
``check``, and its UV scale is brought back to the source's texel density.
"""
from __future__ import annotations

import dataclasses

import numpy as np

__all__ = ["straighten", "made_values", "as_made", "source_uv_scale", "on_tile_grid", "uv_turn_of", "made_fields",
           "tile_record", "recorded_maps"]


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


def rectified_of(straightened: dict | None) -> tuple[float, float, float]:
    """(vx, vy, spread) of the source's rectification (:mod:`.imaging.perspective`); zeros when it was not."""
    rectified = (straightened or {}).get("rectified")
    if not rectified:
        return (0.0, 0.0, 0.0)
    return (*(float(v) for v in rectified["vanishing"]), float(rectified["spread"]))


def made_fields(straightened: dict | None, levelled: dict | None, evened: dict | None) -> dict:
    """The provenance fields (:class:`.authoring.Provenance`) that say how the source was made before the tile was
    cut from it, from the facts recorded (the turn, the levelling, the evening)."""
    return {"straightened": float((straightened or {}).get("degrees", 0.0)),
            "levelled": float((levelled or {}).get("moved", 0.0)),
            "evened": float((evened or {}).get("moved", 0.0)),
            "rectified": rectified_of(straightened)}


def tile_record(m, out_dir, uv_scale, facts: tuple, stack_files: list[str]) -> dict | None:
    """What the tile of map ``m`` written into ``out_dir`` records in its file (:mod:`.imaging.tag`): its source
    (the path from ``out_dir`` and its SHA-256), how the source's values are read, how it was made before the tile
    was cut (``facts``: the straightened, levelled and evened facts; ``uv_scale`` read against the made maps, brought
    back to the source's texel density), and the file names of its stack's tiles, in order (the stack is judged
    together). None for a source that is no file of its own (inside a package)."""
    import os

    from seamless_usd.naming import source_digest

    digest = source_digest(m.resolved)
    if not digest:
        return None
    straightened, levelled, evened = facts
    turned = uv_turn_of(straightened)
    made = {**made_fields(straightened, levelled, evened), "uv_scale": list(source_uv_scale(uv_scale, straightened)),
            "uv_turn": turned[0] if turned else 0.0}
    made["rectified"] = list(made["rectified"])
    return {"source": os.path.relpath(m.resolved, out_dir).replace(os.sep, "/"), "sha256": digest,
            "map": {"color_space": m.color_space.value, "roles": [[r.role, r.channels] for r in m.roles],
                    "scale": list(m.scale), "bias": list(m.bias), "normal_y_flip": m.normal_y_flip},
            "made": made, "stack": list(stack_files)}


def recorded_maps(tile_path, record: dict):
    """(tile, source, provenance) from a tile's :func:`tile_record`: the tile and its source file as maps read the
    way the tile's source was read, and the provenance that says how the source was made. Raises ``ValueError``
    on a record that does not hold what :func:`tile_record` writes."""
    from pathlib import Path

    from seamless_usd.authoring.types import Provenance
    from seamless_usd.textures import AuthoredAt, ColorSpace, Origin, RoleUse, TextureMap

    try:
        read, made = record["map"], record["made"]
        source = (Path(tile_path).parent / record["source"]).resolve()

        def texture(path: Path) -> TextureMap:
            return TextureMap(
                material="", node="", node_type="", origin=Origin.USD, asset=str(path), resolved=str(path),
                file_at=AuthoredAt("", "", ""), roles=tuple(RoleUse(str(r), str(c), "") for r, c in read["roles"]),
                color_space=ColorSpace(read["color_space"]), color_space_reason="recorded in the tile",
                scale=tuple(float(v) for v in read["scale"]), bias=tuple(float(v) for v in read["bias"]),
                normal_y_flip=bool(read.get("normal_y_flip", False)))

        prov = Provenance(source_asset=record["source"], crop_size=(0, 0),
                          uv_scale=tuple(float(v) for v in made["uv_scale"]), q_passed=None, q_tau=0.0,
                          q_band_min=(0.0, 0.0), model_hash="", tool_version="",
                          straightened=float(made["straightened"]), levelled=float(made["levelled"]),
                          evened=float(made["evened"]), uv_turn=float(made["uv_turn"]),
                          rectified=tuple(float(v) for v in made["rectified"]))
        return texture(Path(tile_path)), texture(source), prov
    except (KeyError, TypeError, ValueError) as exc:
        raise ValueError(f"its record of how it was made cannot be read ({exc})") from exc
