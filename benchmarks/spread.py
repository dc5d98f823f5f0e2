#!/usr/bin/env python3
"""How far do the quality targets' figures move on tiles that are equally good?

The quality benchmark holds every map to fixed targets (``seamless_usd.metrics.TARGETS``). Some of
those figures read a single line or a single draw, and this script measures how much they move when
nothing about the tile's quality changes:

1. **Seam ratios over the tile's origin.** A tile made on a torus (the refinement, the lattice cut of
   whole periods) has no special line: rolling it gives the same tiled texture, only the lines that
   the border and centre seam ratios read change. For every origin (every roll along x, then along
   y), the worse of the border and centre seam ratio is taken; the table gives the figure at the
   tile's own origin, the least and the most over all origins, and the share of origins where both
   lines are inside the target. The tiles need no training: the lattice cut (for stacks that repeat)
   and the refinement from a random start.
2. **Feature scale of the source against itself.** The scale ratio of the source's halves against
   each other, and of each quadrant against the whole source.
3. **Q over the tile's origin** (``--q``, trains SeamlessGAN with the preset on each stack): the share
   of origins whose tile passes the discriminator's Q, for the same torus tiles and for the source
   used as a tile (the naive tile, which has real seams at its own origin), and Q's margin at the
   tile's own origin.

Writes ``<out>/spread.json`` and ``<out>/spread.md``. Run from anywhere::

    .venv/bin/python benchmarks/spread.py                  # sections 1 and 2, about 20 s
    .venv/bin/python benchmarks/spread.py --q --stacks cloth,brick   # and Q (minutes per stack)
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Sequence

import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

from methods import preset_config  # noqa: E402
from results_io import write_results  # noqa: E402
from stacks import SHARED_DIR, STACKS, load_stack  # noqa: E402

from seamless_usd import metrics as M  # noqa: E402
from seamless_usd.metrics.common import _prepare, _ratio  # noqa: E402
from seamless_usd.metrics.seams import _angle  # noqa: E402

SEAM_TARGET = M.TARGETS["seam_ratio_x"][1]
Q_ORIGINS = 6  # origins per axis for the Q section (36 in all)


def _worst_lines(tile: np.ndarray, is_normal: bool, axis: int) -> np.ndarray:
    """For every roll ``k`` of ``tile`` along ``axis`` (``np.roll(tile, k, axis)``), the worse of its
    border and centre seam ratio there: exactly :func:`seam_ratios` and :func:`centre_seam_ratios` of the
    rolled tile, read from one profile of the mean neighbour difference across each line (every line
    holds as many texels, so the interior mean is the mean over the other lines)."""
    u = _prepare(tile, is_normal)
    nxt = np.roll(u, -1, axis=axis)  # line j lies between index j and j + 1 (the last across the wrap)
    d = _angle(u, nxt) if is_normal else np.abs(nxt - u).mean(axis=-1)
    line = d.mean(axis=1 - axis)
    n = len(line)
    others = (line.sum() - line) / (n - 1)
    ratio = np.array([_ratio(a, b) for a, b in zip(line, others)])
    k = np.arange(n)
    border, centre = (n - 1 - k) % n, (n - 1 - k - n // 2) % n  # the line each one reads after the roll
    return np.maximum(ratio[border], ratio[centre])


def origin_spread(tile: np.ndarray, is_normal: bool) -> dict[str, dict[str, float]]:
    """Per axis: the worse of border and centre seam ratio at the tile's origin, least and most over all
    origins, median, and the share of origins inside the target."""
    out = {}
    for axis, label in ((1, "x"), (0, "y")):
        v = _worst_lines(tile, is_normal, axis)
        out[label] = {"at_origin": float(v[0]), "min": float(v.min()), "median": float(np.median(v)),
                      "max": float(v.max()), "inside": float(np.mean(v <= SEAM_TARGET))}
    return out


def scale_spread(source: np.ndarray, is_normal: bool) -> dict[str, float]:
    """Scale ratios of the source's halves against each other and of its quadrants against the whole."""
    h, w = source.shape[:2]
    quads = [source[:h // 2, :w // 2], source[:h // 2, w // 2:], source[h // 2:, :w // 2], source[h // 2:, w // 2:]]
    q = [M.scale_ratio(part, source, is_normal) for part in quads]
    return {"top_vs_bottom": M.scale_ratio(source[:h // 2], source[h // 2:], is_normal),
            "left_vs_right": M.scale_ratio(source[:, :w // 2], source[:, w // 2:], is_normal),
            "quadrant_min": float(min(q)), "quadrant_max": float(max(q))}


def torus_tiles(stack: dict[str, tuple[np.ndarray, bool]], seed: int) -> dict[str, dict[str, np.ndarray]]:
    """The tiles made on a torus without training: the lattice cut (when the stack repeats) and the
    refinement from a random start."""
    from seamless_usd import synthesis as syn
    from seamless_usd.synthesis.lattice.cut import find_lattice, lattice_cut, lattice_tile_size

    names = list(stack)
    maps = [stack[n][0] for n in names]
    h, w = maps[0].shape[:2]
    out = {}
    sizes = lattice_tile_size((h, w), find_lattice(maps))
    if sizes is not None:
        field, _ = lattice_cut(maps, *sizes)
        out["lattice-cut"] = {n: m[field[..., 0], field[..., 1]] for n, m in zip(names, maps)}
    res = syn.refine(maps, None, (h, w), seed=seed)
    out["refine-random"] = dict(zip(names, res.maps))
    return out


def q_over_origins(stack: dict[str, tuple[np.ndarray, bool]], tiles: dict[str, dict[str, np.ndarray]],
                   preset: str, seed: int) -> dict[str, dict[str, float]]:
    """Train SeamlessGAN on the stack (the preset's seeds; the first seed's discriminator judges), then
    judge each tile, and the source as a tile, at ``Q_ORIGINS`` x ``Q_ORIGINS`` origins."""
    from seamless_usd import synthesis as syn
    from seamless_usd.synthesis.gan.sample import judge
    from seamless_usd.synthesis.grid import on_grid
    from seamless_usd.synthesis.gan.train import TrainedModel

    maps = [syn.MapInput(n, np.ascontiguousarray(px, dtype=np.float32), isn) for n, (px, isn) in stack.items()]
    with tempfile.TemporaryDirectory() as ck:
        made = syn.make_tile(maps, preset_config(preset), seed=seed, checkpoint_dir=ck, refine_config=None)
        model = TrainedModel.load(os.path.join(ck, "checkpoint.safetensors"))
    H, W = maps[0].pixels.shape[:2]
    factor = (made.working_size[0] / H, made.working_size[1] / W)
    out = {}
    for kind, tile in {**tiles, "naive": {m.name: m.pixels for m in maps}}.items():
        grid = on_grid(tile, maps, factor)
        h, w = next(iter(grid.values())).shape[:2]
        passed = []
        for dy in np.linspace(0, h, Q_ORIGINS, endpoint=False).astype(int):
            for dx in np.linspace(0, w, Q_ORIGINS, endpoint=False).astype(int):
                q = judge(model, {n: np.roll(v, (dy, dx), axis=(0, 1)) for n, v in grid.items()})
                passed.append(q.passed)
        at_origin = judge(model, grid)
        out[kind] = {"passed_share": float(np.mean(passed)), "passed_at_origin": bool(at_origin.passed),
                     "margin_at_origin": float(at_origin.margin)}
    return out


def run(stacks: Sequence[str], seed: int, with_q: bool, preset: str, textures_dir: Path,
        max_size: int | None) -> dict:
    result = {"seed": seed, "preset": preset if with_q else None, "seam_target": SEAM_TARGET,
              "load_start": os.getloadavg()[0], "stacks": {}}
    for name in stacks:
        t0 = time.perf_counter()
        stack = load_stack(name, textures_dir, max_size)
        tiles = torus_tiles(stack, seed)
        entry = {"scale": {m: scale_spread(px, isn) for m, (px, isn) in stack.items()},
                 "origins": {kind: {m: origin_spread(t[m], stack[m][1]) for m in stack} for kind, t in tiles.items()}}
        if with_q:
            entry["q"] = q_over_origins(stack, tiles, preset, seed)
        entry["seconds"] = round(time.perf_counter() - t0, 1)
        entry["load"] = round(os.getloadavg()[0], 2)
        result["stacks"][name] = entry
        print(f"{name}: {entry['seconds']} s, load {entry['load']}", flush=True)
    return result


def to_markdown(result: dict) -> str:
    t = result["seam_target"]
    lines = ["# How far the target figures move on equally good tiles", "",
             "Written by `benchmarks/spread.py`. Load average at the start: "
             f"{result['load_start']:.2f}.", "",
             "## Seam ratios over the origin of a torus tile", "",
             f"The worse of the border and centre seam ratio along each axis, at the tile's own origin and "
             f"over every other origin of the same tile (the tiled texture is the same at every origin); "
             f"'inside' is the share of origins where both lines are within {t}.", "",
             "| stack | tile | map | x at origin | x least-most | x inside | y at origin | y least-most | y inside |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for name, e in result["stacks"].items():
        for kind, per_map in e["origins"].items():
            for m, s in per_map.items():
                cells = []
                for a in ("x", "y"):
                    v = s[a]
                    cells += [f"{v['at_origin']:.2f}", f"{v['min']:.2f}-{v['max']:.2f}", f"{v['inside']:.0%}"]
                lines.append(f"| {name} | {kind} | {m} | " + " | ".join(cells) + " |")
    lines += ["", "## Feature scale of the source against itself", "",
              "Scale ratio of the top half against the bottom one, of the left against the right, and of each "
              "quadrant against the whole source (the target for a tile is 0.9-1.1).", "",
              "| stack | map | top vs bottom | left vs right | quadrants vs whole |", "|---|---|---:|---:|---:|"]
    for name, e in result["stacks"].items():
        for m, s in e["scale"].items():
            lines.append(f"| {name} | {m} | {s['top_vs_bottom']:.2f} | {s['left_vs_right']:.2f} | "
                         f"{s['quadrant_min']:.2f}-{s['quadrant_max']:.2f} |")
    if any("q" in e for e in result["stacks"].values()):
        lines += ["", f"## Q over the tile's origin (preset `{result['preset']}`)", "",
                  f"Share of {Q_ORIGINS * Q_ORIGINS} origins at which the tile passes Q, and Q at the tile's own "
                  "origin. `naive` is the source used as a tile: its own origin has real seams.", "",
                  "| stack | tile | passes at its origin | margin there | origins passing |", "|---|---|---|---:|---:|"]
        for name, e in result["stacks"].items():
            for kind, q in e.get("q", {}).items():
                lines.append(f"| {name} | {kind} | {q['passed_at_origin']} | {q['margin_at_origin']:+.4f} | "
                             f"{q['passed_share']:.0%} |")
    lines += ["", "Seconds and load per stack: " + ", ".join(
        f"{n} {e['seconds']} s (load {e['load']})" for n, e in result["stacks"].items()), ""]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--stacks", default=None, help=f"comma-separated, from: {', '.join(STACKS)} (default: all available)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--q", action="store_true", help="also train SeamlessGAN on each stack and judge the tiles' Q")
    p.add_argument("--preset", default="default", help="preset for --q (default: %(default)s)")
    p.add_argument("--textures-dir", type=Path, default=SHARED_DIR)
    p.add_argument("--max-size", type=int, default=None, help="downscale inputs to at most this many px (quick runs)")
    p.add_argument("--out", type=Path, default=HERE / "results")
    args = p.parse_args(argv)
    names = [s.strip() for s in args.stacks.split(",")] if args.stacks else [
        n for n, s in STACKS.items() if s.folder == "samples" or args.textures_dir.is_dir()]
    unknown = [n for n in names if n not in STACKS]
    if unknown:
        p.error(f"unknown stacks {unknown}; choose from {', '.join(STACKS)}")
    result = run(names, args.seed, args.q, args.preset, args.textures_dir, args.max_size)
    page, _ = write_results(args.out, "spread", to_markdown(result), result)
    print(f"wrote {page}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
