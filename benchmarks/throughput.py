#!/usr/bin/env python3
"""Passed stacks an hour: ``process`` on a library of real 512 px photo materials, one command, cold cache.

Each photo of ``--photos`` (default ``benchmarks/photos``; every ``--every``-th, from ``--start``) becomes
one material in a scene file of its own: a ground plane whose UsdPreviewSurface reads it as its sRGB colour
map, brought to at most ``--size`` px (a texture its publisher made to tile is read through a plain window
of it, as in ``photos.py``, so that it does not tile). The whole folder is then processed by one
``seamless-usd process FOLDER --json`` in this process, with ``--preset`` (default ``default``) and a fresh
cache, as a TD would run a library; ``--jobs N`` runs N stacks at once in worker processes (``process --jobs``),
each with the cores shared out among them. Printed and written to ``--out`` (``throughput.md`` / ``.json``): wall
time, stacks passed, how each was made (a cut, or trained), and passed stacks an hour (target: 60); with
``--jobs N`` (N > 1) the files are ``throughput-jobsN.md`` / ``.json``.

    .venv/bin/python benchmarks/throughput.py --every 3
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent), str(HERE.parent / "sample_assets")]


def build_library(photos: list[Path], folder: Path, size: int) -> list[Path]:
    """One scene per photo in ``folder`` (its colour map beside it); the scenes' paths."""
    import numpy as np
    from PIL import Image
    from photos import load_photo, tileable_photos
    from usdkit import bind, new_layer, plane, preview_material

    made = tileable_photos(photos[0].parent) if photos else set()
    scenes = []
    for path in photos:
        pixels = load_photo(path, size, window=path.name in made)
        sub = folder / path.stem
        sub.mkdir(parents=True)
        Image.fromarray(np.clip(np.rint((pixels + 1.0) * 127.5), 0, 255).astype(np.uint8)).save(sub / "color.png")
        stage = new_layer(sub / "scene.usda", "World")
        stage.DefinePrim("/World", "Xform")
        bind(plane(stage, "/World/Ground", 4.0, 1.0, cells=1).GetPrim(), "/World/Looks/M")
        preview_material(stage, "/World/Looks/M", {"diffuseColor": ("./color.png", "rgb", "sRGB")})
        stage.Save()
        scenes.append(sub / "scene.usda")
    return scenes


def run(folder: Path, preset: str, cache: Path, jobs: int = 1) -> tuple[int, dict, float]:
    from seamless_usd_cli.main import main as cli

    out = io.StringIO()
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(out):
        code = cli(["process", str(folder), "--preset", preset, "--cache-dir", str(cache), "--json",
                    *(["--jobs", str(jobs)] if jobs > 1 else [])])
    return code, json.loads(out.getvalue()), time.perf_counter() - t0


def summary(payload: dict, seconds: float) -> dict:
    rows = []
    for stack in payload["stacks"]:
        gan = (stack.get("resampled") or {}).get("gan") or {}
        rows.append({"source": Path(stack.get("source") or "").parent.name, "status": stack["status"],
                     "intent": stack.get("intent"),
                     "layout": gan.get("layout"), "trained": bool(stack.get("model_hash")),
                     "seconds": round(sum((stack.get("timings") or {}).values()), 1)})
    passed = sum(r["status"] == "passed" for r in rows)
    return {"stacks": len(rows), "passed": passed, "trained": sum(r["trained"] for r in rows),
            "seconds": round(seconds, 2), "passed_per_hour": round(passed * 3600.0 / seconds, 1), "rows": rows}


def markdown(s: dict, a: argparse.Namespace, load: tuple[float, float]) -> str:
    lines = ["# Passed stacks an hour", "",
             f"`benchmarks/throughput.py --every {a.every} --start {a.start} --size {a.size} --preset {a.preset}"
             f"{f' --jobs {a.jobs}' if a.jobs > 1 else ''}`: "
             f"{s['stacks']} real photos as one library, one `process` command, cold cache; load {load[0]:.2f} "
             f"before, {load[1]:.2f} after.", "",
             f"**{s['passed']} of {s['stacks']} passed in {s['seconds'] / 60:.1f} min: {s['passed_per_hour']:g} passed "
             f"stacks an hour** (target 60); {s['trained']} trained a GAN.", "",
             "| photo | tiling intent | status | made from | trained | s |", "|---|---|---|---|---|---:|"]
    lines += [f"| {r['source']} | {r['intent']} | {r['status']} | {r['layout']} | {'yes' if r['trained'] else 'no'} | "
              f"{r['seconds']:g} |"
              for r in s["rows"]]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--photos", type=Path, default=HERE / "photos")
    p.add_argument("--every", type=int, default=1, help="every n-th photo (sorted by name)")
    p.add_argument("--start", type=int, default=0)
    p.add_argument("--size", type=int, default=512)
    p.add_argument("--preset", default="default")
    p.add_argument("--jobs", type=int, default=1, help="stacks run at once (process --jobs)")
    p.add_argument("--out", type=Path, default=HERE / "results")
    a = p.parse_args(argv)
    stem = "throughput" if a.jobs <= 1 else f"throughput-jobs{a.jobs}"
    photos = sorted(a.photos.glob("*.jpg"))[a.start::a.every]
    with tempfile.TemporaryDirectory() as tmp:
        build_library(photos, Path(tmp) / "library", a.size)
        load0 = os.getloadavg()[0]
        code, payload, seconds = run(Path(tmp) / "library", a.preset, Path(tmp) / "cache", a.jobs)
        load = (load0, os.getloadavg()[0])
    s = {**summary(payload, seconds), "exit_code": code, "load": load, "preset": a.preset, "size": a.size,
         "jobs": a.jobs}
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / f"{stem}.json").write_text(json.dumps(s, indent=1))
    (a.out / f"{stem}.md").write_text(markdown(s, a, load))
    print(markdown(s, a, load))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
