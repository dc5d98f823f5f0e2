#!/usr/bin/env python3
"""Full-resolution benchmark: time and peak memory of one stack end to end at several sizes.

For each size (one child process per size, so peak memory is per run), a three-map stack (base
colour, normal, roughness) is cut from the MaterialX brick images in ``../shared/textures`` (2048
px; 4096 is that image upsampled 2x, which keeps the memory and time right but adds no detail),
decoded to the network domain, and run through ``seamless_usd.synthesis.make_tile``: working
resolution, SeamlessGAN training and sampling, refinement to the full size. ``--iterations``
shortens training for quick runs: training time does not depend on the stack's size (it works on
crops at the working resolution), so the figures also give the time at the preset's own count,
scaled from the measured rate.

    .venv/bin/python benchmarks/fullres.py --sizes 512,1024,2048,4096 --preset default
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # results_io sits beside this script
    sys.path.insert(0, str(HERE))

from results_io import write_results  # noqa: E402

TEXTURES = HERE.parent.parent / "shared" / "textures"
NOTES = "## Notes"  # fullres.md keeps everything from this heading on when the table is rewritten
MAPS = (("brick_base_gray.jpg", False), ("brick_normal.jpg", True), ("brick_roughness.jpg", False))


def _load(size: int, textures: Path):
    import numpy as np
    import OpenImageIO as oiio

    out = []
    for name, is_normal in MAPS:
        buf = oiio.ImageBuf(str(textures / name))
        if size > buf.spec().width:
            buf = oiio.ImageBufAlgo.resize(buf, "lanczos3", roi=oiio.ROI(0, size, 0, size, 0, 1, 0, buf.nchannels))
        px = np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)[:size, :size]
        px = px[..., None] if px.ndim == 2 else px
        px = px * 2.0 - 1.0
        if is_normal:
            px = px / np.maximum(np.linalg.norm(px, axis=-1, keepdims=True), 1e-6)
        out.append((name, np.ascontiguousarray(px), is_normal))
    return out


def child(size: int, preset: str, iterations: int | None, textures: Path) -> dict:
    from seamless_usd.synthesis import MapInput, get_preset, make_tile

    config = get_preset(preset)
    full_iterations = config.iterations
    if iterations is not None:
        config = config.replace(iterations=iterations)
    t0 = time.perf_counter()
    maps = [MapInput(n, px, is_normal) for n, px, is_normal in _load(size, textures)]
    load = time.perf_counter() - t0
    made = make_tile(maps, config, seed=0)
    total = time.perf_counter() - t0
    train = made.timings.get("train", 0.0)
    scaled = total - train + train * full_iterations / config.iterations
    return {
        "size": size, "preset": preset, "iterations": config.iterations, "preset_iterations": full_iterations,
        "load_s": round(load, 2), **{f"{k}_s": round(v, 2) for k, v in made.timings.items()},
        "total_s": round(total, 1), "total_at_preset_iterations_s": round(scaled, 1),
        "peak_rss_gib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 ** 2, 2),
        "working_size": list(made.working_size), "structure_px": round(made.structure_px, 1),
        "tile_size": list(made.tile_size), "layout_used": made.layout_used, "layout": made.layout_kind,
        "lattice": made.lattice,
        "levels": [(lv["tile"][0], lv["seconds"]) for lv in made.refine_levels],
        "threads": int(os.environ.get("OMP_NUM_THREADS", "0")) or None,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default="512,1024,2048,4096")
    p.add_argument("--preset", default="default")
    p.add_argument("--iterations", type=int, default=None, help="shorter training (time is scaled back)")
    p.add_argument("--textures-dir", type=Path, default=TEXTURES)
    p.add_argument("--out", type=Path, default=HERE / "results")
    p.add_argument("--child", type=int, default=None, help=argparse.SUPPRESS)
    a = p.parse_args(argv)
    if a.child is not None:
        print(json.dumps(child(a.child, a.preset, a.iterations, a.textures_dir)))
        return 0
    if not a.textures_dir.is_dir():
        print(f"error: @{a.textures_dir}@ not found (the MaterialX brick images)", file=sys.stderr)
        return 2
    rows = []
    for size in (int(s) for s in a.sizes.split(",")):
        load_before = os.getloadavg()[0]
        cmd = [sys.executable, __file__, "--child", str(size), "--preset", a.preset, "--textures-dir", str(a.textures_dir)]
        if a.iterations:
            cmd += ["--iterations", str(a.iterations)]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            print(f"error at {size} px:\n{done.stderr[-2000:]}", file=sys.stderr)
            return 1
        row = json.loads(done.stdout.strip().splitlines()[-1])
        row["load_average_at_start"] = round(load_before, 2)
        rows.append(row)
        print(f"{size:>5} px: total {row['total_s']:.0f} s (at {row['preset_iterations']} iterations: "
              f"{row['total_at_preset_iterations_s']:.0f} s), refine {row.get('refine_s', 0):.0f} s, "
              f"peak {row['peak_rss_gib']:.2f} GiB, working {row['working_size']}, load {load_before:.2f}", flush=True)
    lines = ["# Full-resolution benchmark", "", f"Command: `benchmarks/fullres.py {' '.join(argv or sys.argv[1:])}`", "",
             "| size | working | train s | sample s | refine s | lattice s | total s | total at preset iterations s "
             "| peak RSS GiB | tile | layout | load |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|---|---|---:|"]
    for r in rows:
        lines.append(f"| {r['size']} | {'x'.join(map(str, r['working_size']))} | {r.get('train_s', 0):.0f} | "
                     f"{r.get('sample_s', 0):.1f} | {r.get('refine_s', 0):.1f} | {r.get('lattice_s', 0):.1f} | "
                     f"{r['total_s']:.0f} | {r['total_at_preset_iterations_s']:.0f} | {r['peak_rss_gib']:.2f} | "
                     f"{'x'.join(map(str, r['tile_size']))} | {r.get('layout', '')} | {r['load_average_at_start']:.2f} |")
    page = a.out / "fullres.md"
    notes = page.read_text().partition(NOTES)[2] if page.exists() else ""  # kept: written by hand
    text = "\n".join(lines) + "\n" + (f"\n{NOTES}{notes}" if notes else "")
    write_results(a.out, "fullres", text, rows, end="\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
