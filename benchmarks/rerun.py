#!/usr/bin/env python3
"""An unchanged library processed again: how long each stack costs once everything is in the cache.

Builds a library of N one-material scenes, each reading a plain window (``--size`` px) of a different real
photo of ``benchmarks/photos`` (CC0; see its SOURCES.md), processes it once into a fresh cache (``--preset``,
``tiny`` by default so that the stacks no cut passes train quickly: the rerun does not depend on how they were
made), then runs the same ``seamless-usd process`` command ``--repeats`` times, as a user would, and times
each whole command against ``seamless-usd --version`` (the start-up alone). Also says whether the rerun
imported torch. Target (issue "Tiles that keep what the photo shows"): under 0.2 s a stack after start-up.

    .venv/bin/python benchmarks/rerun.py --scenes 6 --size 512

Writes ``benchmarks/results/rerun.md`` and ``.json``.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "benchmarks"))
sys.path.insert(0, str(ROOT / "sample_assets"))

from results_io import write_results  # noqa: E402

PHOTOS = ROOT / "benchmarks" / "photos"
RUN = ("import json, sys, time\nt = time.perf_counter()\nfrom seamless_usd_cli.main import main\n"
       "rc = main(sys.argv[1:])\n"
       "print(json.dumps({'rc': rc, 'torch': 'torch' in sys.modules}), file=sys.stderr)\n")


def build(folder: Path, scenes: int, size: int) -> list[Path]:
    import OpenImageIO as oiio
    from usdkit import bind, new_layer, plane, preview_material

    made = []
    for i, photo in enumerate(sorted(PHOTOS.glob("*.jpg"))[:scenes]):
        px = oiio.ImageBuf(str(photo)).get_pixels(oiio.UINT8)
        side = min(size, *px.shape[:2])
        window = np.ascontiguousarray(px[:side, :side, :3])
        out = oiio.ImageBuf(oiio.ImageSpec(side, side, 3, oiio.UINT8))
        out.set_pixels(oiio.ROI(0, side, 0, side, 0, 1, 0, 3), window)
        assert out.write(str(folder / f"{photo.stem}.png")), out.geterror()
        stage = new_layer(folder / f"{photo.stem}.usda", "World")
        stage.DefinePrim("/World", "Xform")
        bind(plane(stage, "/World/Ground", 4.0, 1.0, cells=1).GetPrim(), "/World/Looks/Ground")
        preview_material(stage, "/World/Looks/Ground", {"diffuseColor": (f"./{photo.stem}.png", "rgb", "sRGB")})
        stage.Save()
        made.append(folder / f"{photo.stem}.usda")
    return made


def timed(args: list[str]) -> tuple[float, dict, dict]:
    """Wall seconds of one ``seamless-usd`` command in a fresh interpreter, its JSON and its facts."""
    t = time.perf_counter()
    run = subprocess.run([sys.executable, "-c", RUN, *args], capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - t
    facts = json.loads(run.stderr.strip().splitlines()[-1])
    return seconds, (json.loads(run.stdout) if "--json" in args else {}), facts


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenes", type=int, default=6)
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--preset", default="tiny")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "library"
        folder.mkdir()
        build(folder, args.scenes, args.size)
        command = ["process", str(folder), "--cache-dir", str(Path(tmp) / "cache"), "--preset", args.preset, "--json"]
        load = os.getloadavg()[0]
        cold, payload, _ = timed(command)
        statuses = [s["status"] for s in payload["stacks"]]
        processed = sum(s != "left-alone" for s in statuses)
        warm = [timed(command) for _ in range(args.repeats)]
        start = min(timed(["--version"])[0] for _ in range(args.repeats))
        load_after = os.getloadavg()[0]
    best = min(w[0] for w in warm)
    per_stack = (best - start) / max(processed, 1)
    figures = {"scenes": args.scenes, "size": args.size, "preset": args.preset, "statuses": statuses,
               "cold_s": round(cold, 2), "warm_s": [round(w[0], 3) for w in warm], "start_up_s": round(start, 3),
               "per_stack_after_start_up_s": round(per_stack, 3), "warm_torch": [w[2]["torch"] for w in warm],
               "warm_origins": [s["origin"] for s in warm[0][1]["stacks"]], "load": [round(load, 2), round(load_after, 2)]}
    page = (f"# An unchanged library processed again\n\n`benchmarks/rerun.py --scenes {args.scenes} --size {args.size}`: "
            f"{args.scenes} scenes, each a {args.size} px window of a real photo ({processed} stacks processed, the "
            f"others left alone); load {load:.2f} before, {load_after:.2f} after.\n\n"
            "| run | wall (s) |\n|---|---:|\n"
            f"| first (preset {args.preset}) | {cold:.1f} |\n"
            + "".join(f"| again, {i + 1} | {w[0]:.2f} |\n" for i, w in enumerate(warm))
            + f"| `seamless-usd --version` (start-up) | {start:.2f} |\n\n"
            f"Again, after start-up: **{per_stack:.3f} s a stack** (target under 0.2 s); torch imported by the "
            f"reruns: {', '.join(str(w[2]['torch']).lower() for w in warm)}.\n")
    write_results(args.out, "rerun", page, figures)
    print(page)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
