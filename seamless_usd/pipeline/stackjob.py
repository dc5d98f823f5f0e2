"""One stack job: load pixels, train (or reuse the cache), sample, write the tiles, measure them.

This is what runs on a worker: it takes and returns plain picklable values and never edits a
stage or document (the client does that after the job returns).
"""
from __future__ import annotations

import dataclasses
import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from seamless_usd.textures import TextureStack
from seamless_usd.errors import InputError
from seamless_usd.fileio import confine
from seamless_usd.findings import asset_ref
from seamless_usd.imaging.io import DEFAULT_MAX_PIXELS
from seamless_usd.pipeline.cache import StackCache, stack_key
from seamless_usd.pipeline.madefrom import (as_made, on_tile_grid, source_uv_scale, straighten, tile_record,
                                            uv_turn_of)
from seamless_usd.pipeline.outcome import MapOutcome, StackOutcome, map_identity, outcome_from_record
from seamless_usd.naming import stack_tile_filenames
from seamless_usd.pipeline.rerun import changed_words, judged_key, load_judged, save_judged
from seamless_usd.report.previews import stack_previews
from seamless_usd.verdict import Reading, Reference, judge_reading
from seamless_usd.verdict.joins import inside_figures, join_stats

__all__ = ["JobSettings", "StackJob", "run_stack", "on_tile_grid"]

@dataclass(frozen=True)
class JobSettings:
    """The part of the options a worker needs (picklable, no callables)."""

    preset: str = "default"
    iterations: int | None = None
    seeds: int | None = None
    seed: int = 0
    device: str | None = None
    max_size: int | None = None
    cache_dir: Path | None = None
    max_pixels: int | None = DEFAULT_MAX_PIXELS  # header limit per image file (width * height)
    refine: str = "on"  # refinement or lattice cut ("gan": no lattice cut; "off": the pure GAN tile)
    tile_size: str = "source"  # "source" (same pixel size as the source) or "paper" (2c x 2c)
    straighten: bool = False  # turn the stack's lines onto the axes before tiling (imaging.straighten)
    uv_turn: bool = False  # straighten, the turn authored in the asset's UVs (normal vectors keep theirs)

    def tile_key(self) -> str:
        """The settings that change a tile, where they differ from the defaults ("" for none): carried by the tiles'
        names (:func:`.naming.stack_tile_filenames`), so tiles made otherwise never replace those a layer names."""
        plain, kept = JobSettings(), ("cache_dir", "device", "max_pixels")  # these three change no tile
        changed = {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                   if f.name not in kept and getattr(self, f.name) != getattr(plain, f.name)}
        return json.dumps(changed, sort_keys=True, default=str) if changed else ""

    @classmethod
    def from_options(cls, options, threads: int | None = None) -> "JobSettings":
        """The settings of ``options`` for a job with ``threads`` CPU threads (None: unknown): seeds not asked for
        are the preset's that run side by side there (:func:`.synthesis.config.side_by_side_seeds`), so the
        cache keys the seeds a job trains."""
        from seamless_usd.synthesis.config import PRESETS, side_by_side_seeds

        seeds, preset = options.seeds, PRESETS.get(options.preset)
        if seeds is None and preset is not None:
            fit = side_by_side_seeds(preset.seeds, threads)
            seeds = fit if fit != preset.seeds else None  # None: the preset's, the same job as before
        return cls(
            preset=options.preset, iterations=options.iterations, seeds=seeds, seed=options.seed,
            device=options.device, max_size=options.max_size, cache_dir=options.cache_dir,
            max_pixels=options.max_pixels, refine=options.refine, tile_size=options.tile_size,
            straighten=options.straighten or options.write_straight,
            uv_turn=options.straighten and not options.write_straight,
        )


class RunStopped(Exception):
    """The run a job belongs to was stopped before the job wrote its tiles (:func:`run_stack`'s ``stopped``)."""


@dataclass(frozen=True)
class StackJob:
    stack: TextureStack
    settings: JobSettings
    output_dir: Path


#: The longest side (px) a written map and its source are read at for the report's figures (2 x 2 box means until
#: it is at most this). Read at full resolution they took about 40 s a 2K map and 8 minutes a 4K stack of three maps,
#: with several GiB of temporaries; the verdict, which decides the status, still reads every map at full resolution.
REPORT_SIDE = 1024


def _report_figures(tile: np.ndarray, source: np.ndarray, is_normal: bool) -> dict[str, dict]:
    """The report's figures of a written map (``metrics``) and of its source tiled as it is (``source_metrics``),
    both read at most :data:`REPORT_SIDE` px a side."""
    from seamless_usd import metrics
    from seamless_usd.imaging.normals import renormalise
    from seamless_usd.synthesis.scale import box_downsample

    def read(a: np.ndarray) -> np.ndarray:
        small = box_downsample(np.asarray(a, dtype=np.float32).reshape(*a.shape[:2], -1), REPORT_SIDE)[0]
        if is_normal and small.shape[-1] >= 3:
            small = np.concatenate([renormalise(small[..., :3]), small[..., 3:]], axis=-1)
        return small

    t, s = read(tile), read(source)
    return {"metrics": metrics.map_metrics(t, s, is_normal=is_normal),
            "source_metrics": metrics.map_metrics(s, None, is_normal=is_normal)}


def run_stack(job: StackJob, progress: Callable[[str, Any], None] | None = None,
              stopped: Callable[[], bool] | None = None) -> StackOutcome:
    """Run one stack job end to end (see module docstring). ``stopped``: whether the run was stopped meanwhile (a
    job on a remote worker, which nothing can end from outside): asked before any tile is written, and a
    :class:`RunStopped` raised instead, so that the disk keeps agreeing with the stopped run's report."""
    from seamless_usd import imaging, synthesis

    emit = progress or (lambda kind, detail: None)
    stack, settings = job.stack, job.settings
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    policy = imaging.WorkingResolution(max_size=settings.max_size)
    pixels = imaging.load_stack_pixels(list(stack.maps), policy, max_pixels=settings.max_pixels)
    authored = pixels.values[0]  # the first map as the asset shows it today (the report's view of a UV turn)
    timings["load"] = time.perf_counter() - t0
    _check_size(pixels, settings.max_size)

    names = [f"m{i}" for i in range(len(stack.maps))]
    inputs = [
        synthesis.MapInput(name=n, pixels=p, is_normal=m.is_normal, code=e.network_code)
        for n, p, m, e in zip(names, pixels.values, stack.maps, pixels.encodings)
    ]
    config = synthesis.get_preset(settings.preset)
    if settings.iterations is not None:
        config = dataclasses.replace(config, iterations=settings.iterations)
    if settings.seeds is not None:
        config = dataclasses.replace(config, seeds=settings.seeds)
    refine_config = None if settings.refine == "off" else synthesis.RefineConfig(lattice=settings.refine == "on")
    # the turn goes back in the UVs only where every map's UVs can turn: else the tile is written straight, its
    # normal vectors turned with it (a normal map is right on the asset only one way or the other)
    unturned = [m.node for m in stack.maps if not m.uv_turns]
    uv_turn = settings.uv_turn and not unturned
    key = stack_key(
        (
            (n, p.pixels, f"{m.channels_used}|{m.color_space.value}|{m.is_normal}|{sorted(r.role for r in m.roles)}")
            for n, p, m in zip(names, inputs, stack.maps)
        ),
        {**dataclasses.asdict(config), "tile_size": settings.tile_size,
         "refine": None if refine_config is None else dataclasses.asdict(refine_config),
         **({"straighten": True} if settings.straighten else {}),
         **({"uv_turn": True if uv_turn else "refused"} if settings.uv_turn else {})},
        settings.seed,
    )
    entry = StackCache(settings.cache_dir).entry(key)
    with entry.guard() as writable:
        cached = entry.load()
        if cached is None and not writable:
            raise InputError(f"the cache folder {asset_ref(entry.root.parent.parent)} cannot be written and holds no "
                             "result for this stack; choose a writable one with --cache-dir")
        if cached is None:
            straightened = None
            if settings.straighten:  # from here on the straightened maps are the stack's source
                t1 = time.perf_counter()
                pixels, straightened = straighten(pixels, [m.is_normal for m in stack.maps], uv_turn)
                if settings.uv_turn and unturned and straightened.get("degrees") and not straightened.get("rectified"):
                    straightened["uv_turn_refused"] = unturned
                inputs = [dataclasses.replace(i, pixels=p) for i, p in zip(inputs, pixels.values)]
                timings["straighten"] = time.perf_counter() - t1
            _drop_unusable_checkpoint(entry.checkpoint_dir, config.seeds)
            made = synthesis.make_tile(
                inputs, config, refine_config=refine_config, tile_size=settings.tile_size, seed=settings.seed,
                device=settings.device, checkpoint_dir=entry.checkpoint_dir, progress=emit,
            )
            meta = {
                **_gan_facts(made),
                "q": _q_dict(made),  # of the written tile; empty when Q never ran
                "timings": {**timings, **made.timings},
                "uv_scale": list(made.uv_scale),
                "straightened": straightened,  # the turn found (and made) before the tile, found once
                "levelled": made.levelled or None,  # the light levelled: the cut of the levelled maps passed
                "evened": made.evened or None,  # the lattice evened: the cut of the evened maps passed
                "scale": {
                    "structure_px": round(made.structure_px, 1),
                    "working_factor": made.working_factor,
                    "gan_working_size": [made.working_size[1], made.working_size[0]],
                    "refined": made.refined,
                    "layout_used": made.layout_used,
                    "layout": made.layout_kind,  # "gan", "random", "lattice", "window", "mend" or "quilt"
                    "lattice": made.lattice,
                    "layout_scale": {m.asset: made.layout_scale.get(n) for n, m in zip(names, stack.maps)},
                    "refine_levels": made.refine_levels,
                    "seeds": made.seeds,  # with several seeds: each one's figures, and the one kept
                    "level_pictures": [caption for caption, _ in made.level_pictures],
                },
            }
            discriminator = _discriminator_preview(made)
            tiles = dict(made.maps)
            if discriminator is not None:
                tiles["__discriminator__"] = discriminator.astype(np.float32)
            for i, (_, picture) in enumerate(made.level_pictures):
                tiles[f"__level{i}__"] = picture
            entry.store(tiles, meta)
        else:
            tiles, meta = cached
    straightened, levelled, evened = meta.get("straightened"), meta.get("levelled"), meta.get("evened")
    out_dir = Path(job.output_dir)
    normals = [m.is_normal for m in stack.maps]
    if cached is not None:  # an unchanged rerun: the tiles written last time are still there, byte for byte
        again, changed = load_judged(entry.root, out_dir, judged_key(stack))
        if again is not None:
            return outcome_from_record(stack, meta, pixels, again[0], again[1], cached=True, out_dir=out_dir,
                                       cache_key=key)
        if changed:  # a tile changed by hand since it was written is the user's now: never replaced
            raise InputError(changed_words(changed))
        # the tile was cut from the maps turned by the turn found (made above when the tile was made)
        pixels = as_made(pixels, normals, straightened, None)
    shown = pixels.values  # the report shows the source as the user has it, its light as it was
    pixels = as_made(pixels, normals, None, levelled, evened)  # the cut was made of the levelled or evened maps
    discriminator = tiles.pop("__discriminator__", None)
    captions = meta["scale"].get("level_pictures", [])
    levels = [(c, tiles.pop(f"__level{i}__")) for i, c in enumerate(captions) if f"__level{i}__" in tiles]

    t3 = time.perf_counter()
    if stopped is not None and stopped():
        raise RunStopped(f"{stack.material}: the run was stopped before its tiles were written")
    out_dir.mkdir(parents=True, exist_ok=True)
    emit("stage", "writing the maps")
    tile_hw = tuple(int(v) for v in next(iter(tiles.values())).shape[:2])
    uv_scale = tuple(float(v) for v in meta["uv_scale"])
    # the sources on the tile's texel grid: a GAN tile that was not refined is at the working resolution
    sources = on_tile_grid(list(pixels.values), [m.is_normal for m in stack.maps], tile_hw, uv_scale)
    outcomes: dict[tuple[str, str], MapOutcome] = {}
    written_values = []
    filenames = stack_tile_filenames(stack.maps, stack.id, [imaging.output_extension(info) for info in pixels.infos],
                                     job.settings.tile_key())
    for name, m, source, encoding, info, filename in zip(names, stack.maps, sources, pixels.encodings, pixels.infos,
                                                         filenames):
        values = tiles[name]
        target = confine(out_dir / filename, out_dir)
        record = tile_record(m, out_dir, uv_scale, (straightened, levelled, evened), filenames)  # read by check
        written = imaging.write_map(target, values, encoding, like=info, record=record, keep_from=m.resolved or None)
        back = imaging.decode_map(imaging.read_image(written, max_pixels=None)[0], encoding)  # what is on disk
        written_values.append(back)
        outcomes[map_identity(m)] = MapOutcome(
            output=Path(written),
            **_report_figures(back, source, m.is_normal),
        )
    timings = dict(meta.get("timings", {}))
    timings["write"] = time.perf_counter() - t3

    scale = dict(meta["scale"])
    t4 = time.perf_counter()
    # the written maps read against the sources once, for the verdict and the join figures alike
    assets = [m.asset for m in stack.maps]
    emit("stage", "judging the written maps")
    reading = Reading(written_values, normals, assets, Reference(sources, normals, assets, keep_index=False),
                      [e.network_code for e in pixels.encodings])
    verdict = judge_reading(reading)
    ratio = synthesis.written_lattice_ratio(scale.get("lattice") or {}, scale.get("layout"))
    if ratio is not None and ratio < synthesis.LATTICE_TARGET:  # the source repeats and the tile breaks it
        verdict.failing.append(f"all maps: lattice_ratio {ratio:.3g} (tolerance at least {synthesis.LATTICE_TARGET:.2f})")
        verdict.faithful = False
    timings["verdict"] = time.perf_counter() - t4
    t5 = time.perf_counter()
    joins = join_stats(written_values, sources, normals, assets, reading=reading)
    del reading  # let the working copies go before the structure figures
    inside = inside_figures(written_values, sources, normals, assets, joins=joins)
    timings["inside"] = time.perf_counter() - t5  # bad joins, coherence and structure of every map
    for m, figures in zip(stack.maps, inside):
        # the fidelity figures the status was decided on (full resolution), in place of the report's smaller reading
        fidelity = {k: v for k, v in verdict.figures.get(m.asset, {}).items() if v is not None}
        outcomes[map_identity(m)].metrics.update({**figures, **fidelity})
    turned = uv_turn_of(straightened)
    turn = None if turned is None else (authored, *turned, source_uv_scale(uv_scale, straightened))
    previews = stack_previews(stack.maps, shown, [tiles[n] for n in names], uv_scale, discriminator,
                              levels=levels, turn=turn)
    record = {"outputs": {json.dumps(list(k)): {"path": str(o.output), "metrics": o.metrics,
                                                "source_metrics": o.source_metrics} for k, o in outcomes.items()},
              "verdict": verdict.as_dict(), "timings": timings, "tile_size": list(tile_hw)}
    # kept, the pictures are read again only when the report draws them: a library run holds none in memory
    previews = save_judged(entry.root, out_dir, judged_key(stack), record, previews) or previews
    return outcome_from_record(stack, meta, pixels, record, previews, cached=cached is not None, out_dir=out_dir,
                               cache_key=key)


#: The shortest side (px) of the working grid a tile is made from: below it the cuts and the verdict's patch figures
#: have too few texels (a 24 px stack failed inside the cut; 32 px is the smallest that gets a tile and a verdict).
MIN_WORKING_SIDE = 32


def _check_size(pixels, max_size: int | None) -> None:
    """A clear error for a stack whose working grid is too small to make a tile from (naming ``--max-size`` when
    that is what made it so)."""
    from seamless_usd.synthesis.types import SCORE_SIDE, score_halving  # no torch: an unchanged rerun needs none

    w, h = pixels.working_size
    halve = score_halving(h, w)  # as the candidates are weighed
    if min(w, h) // halve >= MIN_WORKING_SIDE:
        return
    from seamless_usd.errors import SeamlessUsdError

    sizes = ", ".join(dict.fromkeys(f"{i.width} x {i.height}" for i in pixels.infos))
    reduced = max(i.width for i in pixels.infos) > w or max(i.height for i in pixels.infos) > h
    if min(w, h) >= MIN_WORKING_SIDE:
        cause = (f"its maps ({sizes} px) are so long and thin that the figures that weigh a tile, read at most "
                 f"{SCORE_SIDE} px across, keep {min(w, h) // halve} px of the short side (at least "
                 f"{MIN_WORKING_SIDE}); a strip this thin is not made tileable")
    elif reduced:
        cause = (f"--max-size {max_size} reduces its maps ({sizes} px) to {w} x {h} px; raise --max-size to keep "
                 f"at least {MIN_WORKING_SIDE} px on the short side")
    else:
        cause = f"its maps are {sizes} px; a tile is made from at least {MIN_WORKING_SIDE} px on each side"
    raise SeamlessUsdError(f"too small to make a tile from: {cause}")


def _drop_unusable_checkpoint(checkpoint_dir: Path, seeds: int) -> None:
    """Remove a checkpoint that is not a safetensors file of ours (torn, planted, foreign).

    Training resumes from a checkpoint it can load; one it refuses would fail the stack on every
    run, so it is removed (never unpickled) and training starts over.
    """
    from seamless_usd.synthesis.gan.checkpoint import CHECKPOINT_NAME, load_checkpoint
    from seamless_usd.synthesis.gan.seeds import seed_checkpoint_dir

    for i in range(seeds):  # one checkpoint per seed
        path = seed_checkpoint_dir(checkpoint_dir, i) / CHECKPOINT_NAME
        if not path.exists():
            continue
        try:
            load_checkpoint(path)
        except (ValueError, KeyError):
            path.unlink(missing_ok=True)


def _gan_facts(made) -> dict[str, Any]:
    """The SeamlessGAN's crop, candidates, model, device and precision; their empty values when no GAN was
    trained (the tile cut from the source passed first, or the stack is too small)."""
    gan = made.gan
    if gan is None:
        return {"crop_size": list(made.tile_size), "candidates": 0, "model_hash": "", "device": "none (not trained)",
                "precision": ""}
    return {"crop_size": list(gan.crop_size), "candidates": len(gan.candidates), "model_hash": gan.model_hash,
            "device": gan.device, "precision": gan.precision}


def _q_dict(tile) -> dict[str, Any]:
    q = tile.q
    if q is None:
        return {}
    return {
        "passed": bool(tile.q_passed),
        "tau": float(q.tau),
        "band_min": [float(q.band_min_vertical), float(q.band_min_horizontal)],
        "margin": float(q.margin),
    }


def _discriminator_preview(tile) -> np.ndarray | None:
    """The discriminator map as grey, with the seam bands tinted, as uint8 RGB."""
    d = getattr(tile.q, "d_map", None)
    if d is None:
        return None
    d = np.asarray(d, dtype=np.float32)
    d = d.reshape(d.shape[-2], d.shape[-1]) if d.ndim > 2 else d
    grey = np.clip(d, 0.0, 1.0)
    rgb = np.stack([grey, grey, grey], axis=-1)
    mask = np.asarray(tile.q.band_vertical, dtype=bool) | np.asarray(tile.q.band_horizontal, dtype=bool)
    rgb[mask] = 0.6 * rgb[mask] + 0.4 * np.array([1.0, 0.55, 0.1])
    scale = max(1, 256 // max(grey.shape))
    rgb = rgb.repeat(scale, axis=0).repeat(scale, axis=1)
    return (rgb * 255.0 + 0.5).astype(np.uint8)
