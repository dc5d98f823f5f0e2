#!/usr/bin/env python3
"""Straightening turned structure (``process --straighten``): the angle read, and the tile cut before and after.

Two parts, one heavy job:

- **Turned stacks** (``benchmarks/stacks.py``: the MaterialX wood and brick maps repeated and turned 23 or
  61 degrees clockwise, at ``--sides``): the orientation found against the true turn, the time to find it
  and to straighten every map, and the tile cut from the source (``check_cut``, no GAN: lattice, window,
  mend, quilt) as the stack is and after straightening, each judged by the verdict against the maps it was
  cut from.
- **Photos** (``benchmarks/photos``, at most 512 px): the orientation of each, to show which would be
  turned. None of them is shot turned, so a turn there is a false one (a stochastic texture read as lines).

Writes ``straighten.md`` / ``straighten.json`` to ``--out`` (default ``benchmarks/results``) and, per
turned stack, ``straighten/NAME.jpg``: the tile as cut repeated 2 x 2 beside the straightened tile
repeated 2 x 2, the same texel scale, to look at.

    .venv/bin/python benchmarks/straighten.py --sides 512,2048
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path[:0] = [str(HERE), str(HERE.parent)]

import numpy as np  # noqa: E402

TURNS = {"rot23": -23.0, "rot61": 29.0}  # clockwise 23 and 61: counter-clockwise -23 and -61 (29 mod 90)


def _cut(values: list[np.ndarray], normals: list[bool], seed: int) -> dict:
    from seamless_usd.synthesis import MapInput
    from seamless_usd.synthesis.candidates import check_cut
    from seamless_usd.verdict import judge

    maps = [MapInput(f"m{i}", v, n) for i, (v, n) in enumerate(zip(values, normals))]
    t0 = time.perf_counter()
    cut = check_cut(maps, True, seed)
    seconds = time.perf_counter() - t0
    if cut.kind is None:
        return {"kind": None, "passed": False, "seconds": round(seconds, 2)}
    tiles = [cut.tiles[m.name] for m in maps]
    verdict = judge(tiles, values, normals, [m.name for m in maps])
    return {"kind": cut.kind, "passed": verdict.passed, "strongest": round(verdict.strongest, 3),
            "margin": verdict.margin, "reasons": verdict.reasons(2), "tile": list(tiles[0].shape[:2]),
            "seconds": round(seconds, 2), "_tile": tiles[0]}


def _picture(path: Path, before: np.ndarray, after: np.ndarray, normal: bool) -> None:
    from PIL import Image

    from seamless_usd.metrics import preview_uint8

    a, b = preview_uint8(np.tile(before, (2, 2, 1)), normal), preview_uint8(np.tile(after, (2, 2, 1)), normal)
    h = max(a.shape[0], b.shape[0])
    sheet = np.full((h, a.shape[1] + 16 + b.shape[1], 3), 255, np.uint8)
    sheet[:a.shape[0], :a.shape[1]] = a
    sheet[:b.shape[0], a.shape[1] + 16:] = b
    path.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(sheet).save(path, quality=88)


def turned_stack(name: str, seed: int, out: Path) -> dict:
    from stacks import load_stack

    from seamless_usd.imaging.orientation import dominant_orientation
    from seamless_usd.imaging.straighten import straighten_maps

    stack = load_stack(name)
    values, normals = [v for v, _ in stack.values()], [n for _, n in stack.values()]
    truth = TURNS[name.split("_")[0]]
    t0 = time.perf_counter()
    found = dominant_orientation(values)
    straight = straighten_maps(values, normals, found.degrees) if found.straightens else values
    seconds = time.perf_counter() - t0
    row = {"stack": name, "size": list(values[0].shape[:2]), "truth": truth, **found.as_dict(),
           "error": round(found.degrees - truth, 2), "straightens": found.straightens,
           "straightened_size": list(straight[0].shape[:2]), "straighten_s": round(seconds, 2)}
    before, after = _cut(values, normals, seed), _cut(straight, normals, seed)
    if before.get("_tile") is not None and after.get("_tile") is not None:
        _picture(out / "straighten" / f"{name}.jpg", before["_tile"], after["_tile"], normals[0])
    row["as_is"] = {k: v for k, v in before.items() if not k.startswith("_")}
    row["straightened"] = {k: v for k, v in after.items() if not k.startswith("_")}
    return row


def photo_row(path: Path) -> dict:
    from photos import load_photo

    from seamless_usd.imaging.orientation import dominant_orientation

    pixels = load_photo(path, 512)
    t0 = time.perf_counter()
    found = dominant_orientation([pixels])
    return {"photo": path.name, **found.as_dict(), "straightens": found.straightens,
            "seconds": round(time.perf_counter() - t0, 2)}


def _verdict_text(cut: dict) -> str:
    if cut.get("kind") is None:
        return "no cut"
    status = "passed" if cut["passed"] else "not passed"
    return f"{cut['kind']} {status} {cut['strongest']:.2f}, {cut['seconds']:.1f} s"


def markdown(stacks: list[dict], photos: list[dict], load: tuple[float, float]) -> str:
    lines = ["# Straightening turned structure", "",
             f"`benchmarks/straighten.py`; load {load[0]:.2f} before, {load[1]:.2f} after. Angles are counter-clockwise "
             "as the picture is seen; a tile is the one cut from the source (no GAN), judged against the maps it "
             "was cut from.", "",
             "| stack | size | turn | found | strength | straighten s | size after | cut as is | cut straightened |",
             "|---|---|---:|---:|---:|---:|---|---|---|"]
    for r in stacks:
        lines.append(f"| {r['stack']} | {r['size'][1]}x{r['size'][0]} | {r['truth']:g} | {r['degrees']:g} | "
                     f"{r['strength']:g} | {r['straighten_s']:.2f} | {r['straightened_size'][1]}x{r['straightened_size'][0]} | "
                     f"{_verdict_text(r['as_is'])} | {_verdict_text(r['straightened'])} |")
    turned = [p for p in photos if p["straightens"]]
    lines += ["", f"Photos (not shot turned): {len(turned)} of {len(photos)} would be turned"
              + (": " + ", ".join(f"{p['photo']} ({p['degrees']:g} degrees, strength {p['strength']:g})"
                                  for p in turned) if turned else "") + ".", "",
              "| photo | found | strength | s |", "|---|---:|---:|---:|"]
    lines += [f"| {p['photo']} | {p['degrees']:g} | {p['strength']:g} | {p['seconds']:.2f} |" for p in photos]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--sides", default="512,2048", help="sides (px) of the turned stacks")
    p.add_argument("--kinds", default="wood,brick")
    p.add_argument("--photos", type=Path, default=HERE / "photos", help="folder of photos ('' for none)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", type=Path, default=HERE / "results")
    a = p.parse_args(argv)
    load0 = os.getloadavg()[0]
    stacks = []
    for side in [int(s) for s in a.sides.split(",") if s]:
        for kind in a.kinds.split(","):
            for turn in TURNS:
                row = turned_stack(f"{turn}_{kind}_{side}", a.seed, a.out)
                print(json.dumps(row), flush=True)
                stacks.append(row)
    photos = []
    if str(a.photos) and a.photos.is_dir():
        for path in sorted(a.photos.glob("*.jpg")):
            photos.append(photo_row(path))
            print(json.dumps(photos[-1]), flush=True)
    load = (load0, os.getloadavg()[0])
    a.out.mkdir(parents=True, exist_ok=True)
    (a.out / "straighten.json").write_text(json.dumps({"stacks": stacks, "photos": photos, "load": load}, indent=1))
    (a.out / "straighten.md").write_text(markdown(stacks, photos, load))
    print(markdown(stacks, photos, load))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
