"""Authoring inputs for stacks that are not trained: an already-tileable stack kept as it is, and what a
dry run would write (from the cache, when an earlier run with the same files and settings made the tiles)."""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from pathlib import Path

from seamless_usd.version import __version__
from seamless_usd.textures import TextureStack
from seamless_usd.naming import stack_tile_filenames
from seamless_usd.pipeline.options import Options

__all__ = ["CachedPlan", "cached_plan", "planned_result", "plan_line", "wrap_only_result"]


def wrap_only_result(stack: TextureStack):
    """Authoring input for an already-tileable stack: its own maps, wrap = repeat, no UV change."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult

    prov = Provenance(source_asset="", crop_size=(0, 0), uv_scale=(1.0, 1.0), q_passed=None, q_tau=0.0,
                      q_band_min=(0.0, 0.0), model_hash="", tool_version=__version__, passed=True,
                      verdict=f"already seamless, judged against itself ({stack.intent_reason})")
    maps = [MapResult(map=m, output_path=Path(m.resolved)) for m in stack.maps if m.resolved]
    return StackResult(stack=stack, maps=maps, uv_scale=(1.0, 1.0), provenance=prov, wrap_only=True)


@dataclass(frozen=True)
class CachedPlan:
    """What an earlier run made of a stack, as its cache entry holds it: the UV scale and crop of its tiles, and, when
    they were written into the same folder and are still there byte for byte (so the run keeps them and writes
    nothing), that run's result (``outcome``: its status, reasons and provenance, as the run would give them again);
    None: written from the cache and judged again."""

    uv_scale: tuple[float, float]
    crop: tuple[int, int]
    outcome: object | None = None  # a StackOutcome
    #: where ``outcome`` is None: the verdict the same tiles got when an earlier run wrote them into another folder
    #: (a copy of the library), which the run will give them again once written; None when none is kept
    verdict_elsewhere: dict | None = None
    #: the tiles written into this folder that a TD changed since (painted over): the run leaves them and fails the
    #: stack (:func:`.rerun.written_state`)
    changed: tuple[str, ...] = ()


def cached_plan(stack: TextureStack, out_dir: Path, settings, cache_dir) -> CachedPlan | None:
    """The :class:`CachedPlan` of ``stack`` when a run with the same files and job ``settings`` finished it into the
    cache at ``cache_dir`` and its entry is still whole (``pipeline.cache.JobIndex``); else None. Reads no pixels, so
    it is blind where the run finds the cache by the pixels alone: files written again with the same pixels, a
    setting that does not change the tile (``--device``), a cache whose index was written by an older version."""
    from seamless_usd.pipeline.cache import MANIFEST, JobIndex, job_fingerprint
    from seamless_usd.pipeline.madefrom import source_uv_scale
    from seamless_usd.pipeline.outcome import outcome_from_record
    from seamless_usd.pipeline.rerun import judged_key, read_record, verdict_elsewhere, written_state
    from seamless_usd.report.model import Previews
    from seamless_usd.version import __version__ as version

    try:
        folder = JobIndex(cache_dir).entry(job_fingerprint(stack, settings))
        if folder is None:
            return None
        manifest = json.loads((folder / MANIFEST).read_text(encoding="utf-8"))
        if not all((folder / name).is_file() for name in manifest["files"]):
            return None  # the run finds it broken and makes the tiles again
        meta = manifest["meta"]
        plan = CachedPlan(source_uv_scale(meta["uv_scale"], meta.get("straightened")),
                          (int(meta["crop_size"][0]), int(meta["crop_size"][1])))
    except Exception:  # noqa: BLE001 - an entry of any other shape: the run makes the tiles again, so planned as new
        return None
    def anew() -> CachedPlan:
        """The tiles written again and judged again, as the run will (a tile gone or changed, no record for this
        folder, a record of another shape), with the verdict they got where they were written before, if known
        (the other records are read only here)."""
        return dataclasses.replace(plan, verdict_elsewhere=verdict_elsewhere(folder))

    try:
        record = read_record(folder, out_dir, judged_key(stack))
        if record is None:
            return anew()
        same, changed = written_state(record)
        if record.get("version") != version or not same:
            return dataclasses.replace(anew(), changed=tuple(str(p) for p in changed))
        outcome = outcome_from_record(stack, meta, None, record, Previews(), True, out_dir, folder.name)
        return dataclasses.replace(plan, outcome=outcome)
    except Exception:  # noqa: BLE001 - a record of another shape: the run judges the tiles again
        return anew()


def planned_result(stack: TextureStack, out_dir: Path, options: Options, made_with: str, tiles_of: str | None = None,
                   cached: CachedPlan | None = None):
    """What a dry run shows authoring: the tile paths that would be written, and the UV scale: from the cache when an
    earlier run made the tiles (``cached``), else that of a source-sized tile (scale 1; the paper's tile of the whole
    texture, c = working size, halves it). A dry run reads no pixels, so it cannot tell a stack whose written tile
    will be smaller (a lattice cut: a larger scale).
    ``tiles_of``: the id of an identical stack planned earlier into the same folder, whose tiles this one reuses
    (as the run does); ``made_with``: the job settings' :meth:`.JobSettings.tile_key`, which the names carry."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult, uv_scale_for
    from seamless_usd.imaging import WorkingResolution, output_extension

    sizes = [(m.image.width, m.image.height) for m in stack.maps if m.image is not None]
    working = WorkingResolution(max_size=options.max_size).working_size(sizes) if sizes else (1, 1)
    if cached is not None:
        uv, crop = cached.uv_scale, cached.crop
    elif options.tile_size == "source" and options.refine != "off":
        uv, crop = (1.0, 1.0), (working[0] // 2, working[1] // 2)
    else:
        uv, crop = uv_scale_for(working, working), working
    read = [m for m in stack.maps if m.image is not None]
    names = stack_tile_filenames(read, tiles_of or stack.id, [output_extension(m.image) for m in read], made_with)
    maps = [MapResult(map=m, output_path=out_dir / name) for m, name in zip(read, names)]
    prov = Provenance(
        source_asset=", ".join(m.asset for m in stack.maps), crop_size=crop, uv_scale=uv, q_passed=None,
        q_tau=0.0, q_band_min=(0.0, 0.0), model_hash="", tool_version=__version__,
    )
    return StackResult(stack=stack, maps=maps, uv_scale=uv, provenance=prov, scale_known=cached is not None)


def elsewhere_words(verdict: dict | None) -> str:
    """What a dry run says of the verdict the same tiles got when written into another folder ("" when unknown)."""
    if verdict is None:
        return ""
    from seamless_usd.verdict import Verdict

    said = "passed" if verdict.get("passed") else f"not passed: {'; '.join(Verdict.from_dict(verdict).reasons())}"
    return f"; written into another folder before, they were {said}"


def plan_line(where: str, stack: TextureStack, out_dir: Path, uv: tuple[float, float], cached: CachedPlan | None) -> str:
    """The dry run's words for one stack: made from the cache, or made anew, and where its tiles go."""
    count = len(stack.maps)
    maps = f"{count} map{'s' if count != 1 else ''}: {', '.join(Path(m.asset).name for m in stack.maps)}"
    scale = f"UV scale {uv[0]:.4g} x {uv[1]:.4g}"
    if cached is None:
        return (f"make tiles of {where} ({maps}): cuts of the source first, SeamlessGAN trained only if none "
                f"passes; and write them to {out_dir} ({scale} for a tile of the size planned; a tile of another size, "
                "such as a cut of whole lattice periods, gives another scale)")
    outcome = cached.outcome
    if outcome is None:
        known = elsewhere_words(cached.verdict_elsewhere)
        return (f"write the tiles an earlier run made of {where} ({maps}), from the cache with nothing trained or "
                f"cut again, to {out_dir} ({scale}; judged again once written{known})")
    status = "passed" if outcome.passed else f"not passed: {'; '.join(outcome.reasons())}"
    return (f"keep the tiles an earlier run wrote of {where} ({maps}) in {out_dir}: they are there unchanged, so "
            f"nothing is trained, cut or written ({scale}; {status})")
