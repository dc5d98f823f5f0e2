#!/usr/bin/env python3
"""What the SeamlessGAN's own layout holds of a structured stack, at the CPU preset and with longer training.

An experiment (``benchmarks/experiments/``): the GAN's layout is open work. A tile of source copies cannot
hide its joins where the texture neither repeats nor continues itself (``benchmarks/experiments/results/``:
``window_gate.md``, ``quilt_gate.md``, ``levers*.md``); only synthesis of new structure could, and here
that is the GAN. This script trains the ``default`` preset's networks (one seed) for N iterations on a
stack, makes its tile with ``make_tile``, and prints, for the GAN's tileable layout at the working
resolution: the structure figure of its first map against the source at that resolution
(``seamless_usd.metrics.structure``; target <= 1.5), the layout's feature scale per map, whether the layout
seeded the refinement, what was written, and the time. Picture (``--out``, default
``benchmarks/experiments/results/gan_layout/``): the layout repeated 2 x 2 beside the source (twice, one
above the other), 1x. The table of its runs (``results/gan_layout.md``) is written by hand from the
printed rows and the pictures.

    .venv/bin/python benchmarks/experiments/gan_layout.py --stack stripes_512 --iterations 2400
    .venv/bin/python benchmarks/experiments/gan_layout.py --stack stripes_512 --iterations 9600
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


def main(argv: list[str] | None = None) -> int:
    from stacks import load_stack

    from seamless_usd.metrics import preview_uint8
    from seamless_usd.metrics.structure import structure_figures
    from seamless_usd.synthesis import MapInput, RefineConfig, downsample_maps, get_preset, make_tile

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stack", default="stripes_512")
    ap.add_argument("--iterations", type=int, default=None, help="training iterations (default: the preset's)")
    ap.add_argument("--preset", default="default", help="the networks' preset")
    ap.add_argument("--seeds", type=int, default=1, help="seeds trained side by side (the best tile is kept)")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "gan_layout")
    a = ap.parse_args(argv)
    stack = load_stack(a.stack)
    keys = list(stack)
    maps = [MapInput(k, stack[k][0], stack[k][1]) for k in keys]
    base = get_preset(a.preset)
    a.iterations = a.iterations or base.iterations
    config = dataclasses.replace(base, iterations=a.iterations, seeds=a.seeds, checkpoint_every=max(200, a.iterations))
    load, t0 = os.getloadavg()[0], time.perf_counter()
    # no cut first: the GAN trains even where a tile cut from the source would pass (its layout is the subject)
    made = make_tile(maps, config, refine_config=RefineConfig(lattice=False), seed=0, keep_alternatives=True)
    layout = made.gan.maps[keys[0]]
    source = downsample_maps([maps[0]], layout.shape[:2])[0].pixels
    row = {"stack": a.stack, "iterations": a.iterations, "seeds": a.seeds, "seconds": round(time.perf_counter() - t0),
           "preset": a.preset, "working": list(layout.shape[:2]), "layout_structure": structure_figures(layout, source)["structure"],
           "layout_scale": made.layout_scale, "layout_used": made.layout_used, "written": made.layout_kind,
           "load": [round(load, 2), round(os.getloadavg()[0], 2)]}
    print(json.dumps(row), flush=True)
    normal = stack[keys[0]][1]
    pic = np.concatenate([preview_uint8(np.tile(layout, (2, 2, 1)), normal),
                          preview_uint8(np.tile(source, (2, 1, 1)), normal)], axis=1)
    import OpenImageIO as oiio

    a.out.mkdir(parents=True, exist_ok=True)
    buf = oiio.ImageBuf(np.ascontiguousarray(pic))
    buf.specmod().attribute("Compression", "jpeg:80")
    buf.write(str(a.out / f"gan_layout_{a.stack}_{a.iterations}{'' if a.seeds == 1 else f'_seeds{a.seeds}'}.jpg"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
