#!/usr/bin/env python3
"""Refinement levers, before and after: each setting of ``RefineConfig`` against the product's default,
the window cut (``seamless_usd.synthesis.lattice.window``: one window of the source, cut across its
wraps), and the quilt (``seamless_usd.synthesis.lattice.quilt``: ny x nx large source blocks on a torus,
joined along cuts that follow the texture's lines), the candidates that ``make_tile`` weighs against the
refined tile for a stack with no lattice (the window where the texture continues itself, else the 2x2 quilt).
An experiment (``benchmarks/experiments/``): what it measures is open work, not a figure of the product.

The refinement alone (a random start, no GAN training: what the levers change is the same either way)
runs on structured 512 px stacks whose structure breaks visibly when copied blocks meet badly: stone cells
and curved stripes (``benchmarks/synthetic.py``), and the MaterialX wood and brick turned 23 degrees;
``--stacks`` takes the full-resolution ones too (``stacks.FULLRES_STACKS``: 2048 and 4096 px).
For every lever and stack it measures, against the source: the bad joins inside the tile (count, per
map and for the maps together; ``seamless_usd.verdict.joins``), the field's coherence, the verdict
(``passed``, seams named), the structure figure (``seamless_usd.metrics.structure``; target <= 1.5), feature
scale and patch distance, and the time. Pictures: the first map's tile at 3x (its top-left corner, and
the corner where its wraps meet, the tile repeated), ``benchmarks/experiments/results/levers/``. The
``guide`` levers match a guidance channel with the maps (the distance to the texture's lines; Kaspar et
al. 2015), not written. Conclusions of the levers not kept: ``docs/decisions.md``.

    .venv/bin/python benchmarks/experiments/levers.py            # every lever: experiments/results/levers.md, .json
    .venv/bin/python benchmarks/experiments/levers.py --levers "default,coarse patch 17" --stacks cells_512
    .venv/bin/python benchmarks/experiments/levers.py --levers "default,guide dark lines 1,guide edges 2" --name levers_guide
    .venv/bin/python benchmarks/experiments/levers.py --levers "quilt 2x2,quilt 2x2 by difference,quilt 3x3" --name levers_quilt
    .venv/bin/python benchmarks/experiments/levers.py --name levers_quilt_blend \
        --levers "quilt 2x2 by difference,quilt 2x2 by difference + blend 3,quilt 2x2 by difference + blend 8"
    .venv/bin/python benchmarks/experiments/levers.py --name levers_quilt_deform --levers "quilt 2x2 by difference,\
quilt 2x2 by difference + deform 0.125,quilt 2x2 by difference + deform 0.25"
    .venv/bin/python benchmarks/experiments/levers.py --levers "quilt 2x2,quilt 2x2 by difference" --name levers_quilt_fullres \
        --stacks rot23_wood_2048,rot61_wood_2048,rot23_brick_2048,rot61_brick_2048,cells_2048,stripes_2048
    .venv/bin/python benchmarks/experiments/levers.py --levers "default,window cut" --name levers_fullres \
        --stacks rot23_wood_2048,rot61_wood_2048,rot23_brick_2048,rot61_brick_2048,cells_2048,stripes_2048,rot23_wood_4096,rot23_brick_4096
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent  # benchmarks/experiments
sys.path[:0] = [str(HERE), str(HERE.parent), str(HERE.parents[1])]  # its siblings, the benchmarks' plumbing, the library

import numpy as np  # noqa: E402

#: Each lever: the RefineConfig fields it changes (the product's default first).
LEVERS: dict[str, dict] = {
    "default": {},
    "coherence 3": {"coherence": 3.0},
    "patch 17": {"patch": 17},
    "coarse patch 17": {"coarse_patch": 17},
    "coarse patch 21": {"coarse_patch": 21},
    "occurrence 0.02": {"occurrence": 0.02},
    "carry above 256": {"carry_above": 256},
    "heal 8": {"heal": 8},
    "blend 3": {"blend": 3},
    "blend 6": {"blend": 6},
    "heal 8 + blend 3": {"heal": 8, "blend": 3},
    "robust vote 3": {"robust_vote": 3},
    "window cut": {"window": True},  # not a refinement: one window of the source cut across its wraps
    # not a refinement: image quilting on a torus from ny x nx large source blocks (lattice/quilt.py)
    # cut along the texture's lines where it has long ones, or ("by difference", the product's) where the
    # blocks agree
    "quilt 2x2": {"quilt": (2, 2), "lines": True},
    "quilt 2x2 by difference": {"quilt": (2, 2)},
    # the product's quilt with a band of 3 or 8 texels around every join blended in the gradient domain
    "quilt 2x2 by difference + blend 3": {"quilt": (2, 2), "blend": 3},
    "quilt 2x2 by difference + blend 8": {"quilt": (2, 2), "blend": 8},
    "quilt 3x3": {"quilt": (3, 3), "lines": True},
    # the product's quilt with each new block's texels near its joins shifted to line up with the laid ones
    # (lattice/deform.py; Wu and Yu 2004), by at most this share of the overlap band
    "quilt 2x2 by difference + deform 0.125": {"quilt": (2, 2), "deform": 0.125},
    "quilt 2x2 by difference + deform 0.25": {"quilt": (2, 2), "deform": 0.25},
    # a guidance channel matched with the maps and not written (Kaspar et al. 2015, self-tuning texture
    # optimisation): the distance to the texture's lines, clipped at 16 px, as ``weight`` extra maps
    "guide dark lines 1": {"guide": ("dark", 1)},
    "guide edges 2": {"guide": ("edge", 2)},
}
STACK_NAMES = ("cells_512", "stripes_512", "rot23_wood_512", "rot23_brick_512")


def line_guide(pixels: np.ndarray, kind: str, clip: float = 16.0) -> np.ndarray:
    """(H, W, 1) distance (px, clipped at ``clip``, mapped to [-1, 1]) to the map's lines: its darkest fifth
    after a 4 px high-pass (``"dark"``: joints, gaps, grain), or its strongest edges (``"edge"``: the top 15 %
    of the gradient magnitude at 2 px)."""
    from scipy import ndimage

    from seamless_usd.metrics.structure import _channel

    u, _ = _channel(pixels, None)
    if kind == "edge":
        g = ndimage.gaussian_gradient_magnitude(u, 2.0)
        lines = g > np.quantile(g, 0.85)
    else:
        hp = u - ndimage.gaussian_filter(u, 4.0, mode="reflect")
        lines = ndimage.binary_opening(hp < np.quantile(hp, 0.2))
    d = ndimage.distance_transform_edt(~lines)
    return (np.minimum(d, clip) / clip * 2 - 1).astype(np.float32)[..., None]


def run_one(stack: dict, lever: dict, seed: int) -> tuple[dict, np.ndarray]:
    import torch

    from seamless_usd.metrics import patch_distance, scale_ratio
    from seamless_usd.metrics.structure import structure_figures
    from seamless_usd.synthesis import RefineConfig, refine
    from seamless_usd.verdict import judge
    from seamless_usd.verdict.joins import join_stats

    torch.set_num_threads(1)
    keys = list(stack)
    maps = [stack[k][0] for k in keys]
    normals = [stack[k][1] for k in keys]
    t0 = time.perf_counter()
    notes = {}
    if lever.get("window"):
        from seamless_usd.synthesis.lattice.cut import lattice_cut
        from seamless_usd.synthesis.lattice.window import continues_itself, window_tile_size

        tile_hw, band, lags = window_tile_size(maps)
        offered = continues_itself(lags)  # whether make_tile offers this cut (see window_gate.py)
        field, _ = lattice_cut(maps, tile_hw, band)
        tiles = [np.ascontiguousarray(m[field[..., 0], field[..., 1]]) for m in maps]
    elif lever.get("quilt"):
        from seamless_usd.synthesis.lattice.quilt import best_quilt
        from seamless_usd.synthesis.tile import QUILT_TRIES

        field, quilted = best_quilt(maps, maps[0].shape[:2], lever["quilt"], QUILT_TRIES, seed=seed,
                                    lines=lever.get("lines", False), deform=lever.get("deform", 0.0))
        if lever.get("blend"):
            from seamless_usd.synthesis.refinement.blend import blend_band

            tiles = blend_band(maps, field, lever["blend"], normals)[0]
        else:
            tiles = [np.ascontiguousarray(m[field[..., 0], field[..., 1]]) for m in maps]
        offered = True
        notes = {"join_mean": quilted["join_mean"], "join_worst": quilted["join_worst"], "lines": quilted["lines"]}
    else:
        guide_kind, weight = lever.get("guide", (None, 0))
        extra = [line_guide(maps[0], guide_kind)] * weight  # matched, then dropped
        config = dataclasses.replace(RefineConfig(lattice=False), **{k: v for k, v in lever.items() if k != "guide"})
        result = refine(maps + extra, None, maps[0].shape[:2], config, seed=seed, normals=normals + [False] * weight)
        tiles, field = result.maps[:len(maps)], result.field
        offered = True
    seconds = time.perf_counter() - t0
    joins = join_stats(tiles, maps, normals, keys, origin=field)  # the field: blended texels keep their place
    verdict = judge(tiles, maps, normals, keys)
    fy, fx = field[..., 0], field[..., 1]
    changed = np.zeros(fy.shape, dtype=bool)  # texels that are not the copy the field names (blended or voted)
    for tile, source in zip(tiles, maps):
        changed |= np.abs(tile - source[fy, fx]).max(axis=-1) > 1e-6
    blended = round(float(changed.mean()), 3)
    row = {"seconds": round(seconds, 1), "tile": list(tiles[0].shape[:2]), "coherence": joins["coherence"],
           "blended": blended,
           "bad_joins": {k: v["count"] for k, v in (joins["maps"] or {}).items()},
           "passed": verdict.passed, "seams": len(verdict.seams), "offered": offered,
           "structure": {k: structure_figures(t, m)["structure"] for k, t, m in zip(keys, tiles, maps)},
           "scale": {k: round(scale_ratio(t, m, n), 3) for k, t, m, n in zip(keys, tiles, maps, normals)},
           "patch": {k: round(patch_distance(t, m, n), 3) for k, t, m, n in zip(keys, tiles, maps, normals)}, **notes}
    return row, tiles[0]


def _md(rows: list[dict], load: str) -> str:
    from seamless_usd.metrics.structure import STRUCTURE_TARGET

    out = ["# Refinement levers", "",
           "The refinement alone (random start, seed 0, one thread) on structured stacks, and the window cut "
           "(one window of the source cut across its wraps; its tile is smaller, its UV transform keeps the texel "
           "density; *not offered*: the texture does not continue itself at the window's lags, so `make_tile` does "
           "not weigh this cut, `benchmarks/experiments/results/window_gate.md`), and the quilt (large source blocks on a torus; "
           "*along lines*: the stack has long lines and the cuts followed them); `benchmarks/experiments/levers.py`. Verdict: passed, or the seams it names (at most 6 per direction "
           "and map). Bad joins: stretches of >= 8 texels where two copied blocks meet with a "
           "continuation error above the verdict's threshold, for the maps together (per-map counts in "
           "levers.json), read through the refinement's own field (so blended texels are judged where they "
           "stand). Blended: share of texels that are not the copy the field names (blended or voted; the rest are exact "
           "copies). "
           f"Structure: the worst map, target <= {STRUCTURE_TARGET}. Scale and patch: the worst map's distance "
           f"from 1 / its value. {load}", "",
           "| stack | lever | tile | bad joins | coherence | blended | verdict | structure (worst) | scale (worst) "
           "| patch (worst) | s |", "|---|---|---|---:|---:|---:|---|---:|---:|---:|---:|"]
    for r in rows:
        scale = max(r["scale"].values(), key=lambda v: abs(v - 1))
        size = ("x".join(str(v) for v in r.get("tile", [])) + ("" if r.get("offered", True) else ", not offered")
                + (", along lines" if r.get("lines") else ""))
        verdict = "passed" if r["passed"] else f"{r['seams']} seams" if r["seams"] else "not faithful"
        out.append(f"| {r['stack']} | {r['lever']} | {size} | {r['bad_joins'].get('stack', '–')} | {r['coherence']} | "
                   f"{r['blended']:.0%} | {verdict} | {max(r['structure'].values()):.2f} | {scale:.2f} | "
                   f"{max(r['patch'].values()):.2f} | {r['seconds']} |")
    return "\n".join(out) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--levers", default=",".join(LEVERS), help="comma-separated lever names (default: all)")
    p.add_argument("--stacks", default=",".join(STACK_NAMES), help="comma-separated stacks of benchmarks/stacks.py")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=HERE / "results")
    p.add_argument("--name", default="levers", help="base name of the .md / .json written and of the pictures' folder")
    a = p.parse_args(argv)
    from quality import write_picture
    from results_io import write_results
    from stacks import load_stack

    from seamless_usd.metrics import preview_uint8

    names = [n if n in LEVERS else sys.exit(f"error: unknown lever {n!r}; choose from {', '.join(LEVERS)}")
             for n in a.levers.split(",")]
    stacks = a.stacks.split(",")
    load = f"Load average at the start: {os.getloadavg()[0]:.2f}."
    rows = []
    pictures = a.out / a.name
    pictures.mkdir(parents=True, exist_ok=True)
    for stack_name in stacks:
        stack = load_stack(stack_name)
        for name in names:
            row, first = run_one(stack, LEVERS[name], a.seed)
            row = {"stack": stack_name, "lever": name, **row}
            rows.append(row)
            print(json.dumps(row), flush=True)
            label = f"{stack_name}__{name.replace(' ', '_').replace('+', 'and')}"
            h, w = first.shape[:2]
            wrap = np.tile(first, (2, 2, 1))[h - 100: h + 100, w - 100: w + 100]  # the wraps' corner, repeated
            for part, img in (("3x", first[:200, :200]), ("wrap_3x", wrap)):
                crop = preview_uint8(img, stack[next(iter(stack))][1])
                write_picture(pictures / f"{label}__{part}.jpg", np.repeat(np.repeat(crop, 3, 0), 3, 1))
    load += f" At the end: {os.getloadavg()[0]:.2f}."
    page, _ = write_results(a.out, a.name, _md(rows, load), {"load": load, "rows": rows})
    print(f"wrote @{page}@")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
