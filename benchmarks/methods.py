"""The methods the quality benchmark compares, beyond the simple baselines of ``baselines.py``.

``seamlessgan``
    SeamlessGAN alone (``--refine off``): trained at the stack's working resolution, sampled with
    the crop search and Q. Its tile lives on the working grid, so its figures are taken against the
    source brought to that grid (same texel scale).
``refine-random``
    The toroidal exemplar refinement alone, from a block-random start, at the source's resolution.
``seamlessgan+refine``
    The GAN's tile seeds the refinement (``--refine gan``; the same trained model as ``seamlessgan``,
    so the two rows differ only by the refinement).
``lattice-cut``
    Only for stacks that repeat on a lattice: a tile of whole periods cut from the source, joined
    across its wraps along minimum-error boundary cuts (``seamless_usd.synthesis.lattice.cut``).
``seamless-usd``
    The product's default (``--refine on``): of the two rows above, the one that passes Q,
    then the lower fidelity score; the same as ``seamlessgan+refine`` where there is no lattice.
``img2texture``
    The ``img2texture`` package from PyPI (overlap-and-blend of opposite borders through PIL, 8-bit),
    the tool many users reach for today. Normal maps are renormalised afterwards.
``resynthesizer``
    GIMP's Resynthesizer (PyPI ``resynthesizer``, GPL-3.0), run in its own environment, never the
    project's (``RESYNTH_PYTHON`` or ``--resynth-python``: ``benchmarks/peers/resynthesizer_tile.py``):
    the map offset by half, a band over the seam cross re-synthesised from the rest of it, as artists
    do by hand. 8-bit RGB: each map on its own (grey maps as RGB), normal maps renormalised afterwards.
"""
from __future__ import annotations

import os
import subprocess
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from seamless_usd.verdict import judge

__all__ = ["MethodResult", "SYNTHESIS_METHODS", "run_synthesis", "img2texture_tile", "resynthesizer_tile",
           "to_source_grid"]

PEER = Path(__file__).resolve().parent / "peers" / "resynthesizer_tile.py"

SYNTHESIS_METHODS = ("seamlessgan", "refine-random", "seamlessgan+refine", "lattice-cut", "seamless-usd")
_REFINED = ("seamlessgan+refine", "lattice-cut", "seamless-usd")


@dataclass
class MethodResult:
    """The tiles of one method on one stack, what it reported, and the grid its texels belong to."""

    tiles: dict[str, np.ndarray]
    seconds: float
    info: dict = field(default_factory=dict)
    references: dict[str, np.ndarray] | None = None  # the source on the tile's grid, when it is not the source's


def img2texture_tile(pixels: np.ndarray, is_normal: bool = False, overlap: float = 0.25) -> np.ndarray:
    """Run img2texture's ``image_to_seamless`` on a network-domain map (through 8-bit, as the tool does)."""
    from img2texture import image_to_seamless
    from PIL import Image

    c = pixels.shape[2]
    v = np.clip(np.rint((pixels + 1.0) * 127.5), 0, 255).astype(np.uint8)
    img = Image.fromarray(v[..., 0] if c == 1 else v[..., :3], "L" if c == 1 else "RGB")
    out = np.asarray(image_to_seamless(img, overlap=overlap), dtype=np.float32) / 127.5 - 1.0
    out = out[..., None] if out.ndim == 2 else out
    out = out[..., :1] if c == 1 else out[..., :3]
    if c == 4:  # img2texture drops alpha: blend it the same way as grey
        alpha = img2texture_tile(pixels[..., 3:], False, overlap)
        out = np.concatenate([out, alpha], axis=2)
    if is_normal and out.shape[2] >= 3:
        out[..., :3] /= np.maximum(np.linalg.norm(out[..., :3], axis=-1, keepdims=True), 1e-12)
    return np.ascontiguousarray(out, dtype=np.float32)


def resynthesizer_tile(pixels: np.ndarray, is_normal: bool = False, python: str | None = None,
                       band: float = 0.15) -> tuple[np.ndarray, float]:
    """GIMP's Resynthesizer making a network-domain map tileable (through 8-bit RGB), in the environment of
    ``python`` (default: ``RESYNTH_PYTHON``); returns the tile and the seconds its synthesis took."""
    from PIL import Image

    python = python or os.environ.get("RESYNTH_PYTHON")
    if not python:
        raise RuntimeError("resynthesizer needs its own environment: pass --resynth-python or set RESYNTH_PYTHON "
                           "(see benchmarks/peers/resynthesizer_tile.py)")
    c = pixels.shape[2]
    v = np.clip(np.rint((pixels + 1.0) * 127.5), 0, 255).astype(np.uint8)
    rgb = np.repeat(v[..., :1], 3, axis=2) if c < 3 else v[..., :3]
    with tempfile.TemporaryDirectory() as tmp:
        src, dst = Path(tmp) / "in.png", Path(tmp) / "out.png"
        Image.fromarray(rgb).save(src)
        done = subprocess.run([python, str(PEER), str(src), str(dst), "--band", str(band)], capture_output=True,
                              text=True)
        if done.returncode != 0:
            raise RuntimeError(f"resynthesizer failed: {done.stderr.strip()[-300:]}")
        with Image.open(dst) as im:
            out = np.asarray(im.convert("RGB"), dtype=np.float32) / 127.5 - 1.0
    if c < 3:
        out = out[..., :c] if c == 1 else np.concatenate([out[..., :1], out[..., :1]], axis=2)
    elif c == 4:
        alpha, _ = resynthesizer_tile(pixels[..., 3:], False, python, band)
        out = np.concatenate([out, alpha], axis=2)
    if is_normal and out.shape[2] >= 3:
        out[..., :3] /= np.maximum(np.linalg.norm(out[..., :3], axis=-1, keepdims=True), 1e-12)
    return np.ascontiguousarray(out, dtype=np.float32), float(done.stdout.strip().splitlines()[-1])


def preset_config(preset: str, overrides: dict | None = None):
    """The preset, with the benchmark's overrides of its fields (``{"iterations": 1200}``; None: the preset's)."""
    from seamless_usd.synthesis import get_preset

    config = get_preset(preset)
    changes = {k: v for k, v in (overrides or {}).items() if v is not None}
    return config.replace(**changes) if changes else config


def run_synthesis(stack: dict[str, tuple[np.ndarray, bool]], methods: list[str], preset: str, seed: int,
                  log: Callable[[str], None], overrides: dict | None = None) -> dict[str, MethodResult]:
    """The synthesis methods asked for, training SeamlessGAN once for all GAN rows (``lattice-cut`` is
    missing from the result for a stack without a lattice)."""
    from seamless_usd import synthesis as syn

    config = preset_config(preset, overrides)
    maps = [syn.MapInput(k, np.ascontiguousarray(px, dtype=np.float32), n) for k, (px, n) in stack.items()]
    out: dict[str, MethodResult] = {}
    if "refine-random" in methods:
        t0 = time.perf_counter()
        res = syn.refine([m.pixels for m in maps], None, maps[0].pixels.shape[:2], seed=seed)
        out["refine-random"] = MethodResult({m.name: t for m, t in zip(maps, res.maps)}, time.perf_counter() - t0,
                                            {"levels": len(res.levels)})
    if not {"seamlessgan", *_REFINED} & set(methods):
        return out
    step = max(1, config.iterations // 10)

    def progress(kind: str, p) -> None:
        if kind == "train" and (p.iteration % step == 0 or p.iteration == p.total):
            log(f"    train {p.iteration}/{p.total}  {p.it_per_s:.1f} it/s  eta {p.eta_s / 60:.1f} min")

    t0 = time.perf_counter()
    made = syn.make_tile(maps, config, seed=seed, progress=progress, keep_alternatives=True)
    total = time.perf_counter() - t0
    gan = made.gan  # None: a tile cut from the source passed before any training
    info = {
        "preset": preset, "iterations": config.iterations if gan is not None else 0,
        "crop_size": list(gan.crop_size) if gan is not None else None,
        "q_passed": bool(gan.q_passed) if gan is not None else None,
        "working_size": list(made.working_size), "structure_px": round(made.structure_px, 1),
        "train_seconds": round(made.timings.get("train", 0.0), 2),
        "sample_seconds": round(made.timings.get("sample", 0.0), 2),
    }
    if made.seeds:
        info["seeds"] = made.seeds
    lattice_s = made.timings.get("lattice", 0.0)
    gan_seconds = total - made.timings.get("refine", 0.0) - lattice_s
    if "seamlessgan" in methods and gan is not None:
        working = {w.name: w.pixels for w in syn.downsample_maps(maps, made.working_size)}
        out["seamlessgan"] = MethodResult(dict(gan.maps), gan_seconds, dict(info), references=working)
    refined = {"seamless-usd": made.maps, made.layout_kind: made.maps, **made.alternatives}
    refined["seamlessgan+refine"] = refined.get("gan", refined.get("random"))
    refined["lattice-cut"] = refined.get("lattice")
    seconds = {"seamless-usd": total, "seamlessgan+refine": total - lattice_s,
               "lattice-cut": gan_seconds + lattice_s}
    details = {**info, "layout_used": made.layout_used, "refine_seconds": round(made.timings.get("refine", 0.0), 2),
               "layout": made.layout_kind, "lattice": made.lattice}
    q_passed = {"seamless-usd": made.q_passed, "seamlessgan+refine": gan is not None and bool(gan.q_passed),
                "lattice-cut": bool(made.lattice.get("q_passed"))}  # Q of each row's own tile
    for method in _REFINED:
        if method in methods and refined[method] is not None:
            tiles = dict(refined[method])
            verdict = judge([tiles[m.name] for m in maps], [m.pixels for m in maps], [m.is_normal for m in maps],
                            [m.name for m in maps])  # the product's verdict on this row's tile
            out[method] = MethodResult(tiles, seconds[method], {**details, "q_passed": q_passed[method],
                                                                "passed": verdict.passed,
                                                                "verdict": verdict.reasons()})
    return out


def to_source_grid(tile: np.ndarray, reference: np.ndarray, source: np.ndarray) -> np.ndarray:
    """A tile made on ``reference``'s grid, resized so its texels have the ``source``'s size."""
    if reference.shape[:2] == source.shape[:2]:
        return tile
    from seamless_usd.synthesis import MapInput, downsample_maps

    fy, fx = source.shape[0] / reference.shape[0], source.shape[1] / reference.shape[1]
    size = (max(1, round(tile.shape[0] * fy)), max(1, round(tile.shape[1] * fx)))
    [resized] = downsample_maps([MapInput("tile", np.ascontiguousarray(tile, dtype=np.float32))], size)
    return resized.pixels
