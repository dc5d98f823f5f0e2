#!/usr/bin/env python3
"""``seamless-usd check`` as users run it, timed from the command line (start-up included).

- a 2K 3-map stack: the end-to-end scene (``endtoend.py``: the MaterialX brick's base colour, normal and
  roughness at ``--size`` px, as PNGs), judged against itself (target 5 s);
- a 1K picture: a photo of ``benchmarks/photos`` at 1024 px (``--picture``; target 1 s);
- ``--pictures N``: a folder of N pictures (256 px windows of the photos, some rolled by half, some whole
  tileable textures brought to 256 px) checked with ``--json`` and an HTML contact sheet.

Each single check runs ``--repeat`` times; the median is printed with the load average before it.

    .venv/bin/python benchmarks/check_time.py --out /tmp/check_time
    .venv/bin/python benchmarks/check_time.py --out /tmp/check_time --pictures 1000
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from endtoend import build_scene  # noqa: E402
from photos import PHOTOS, tileable_photos  # noqa: E402

PICTURE = "stones_cliff_1.jpg"  # 1024 x 1024


def _exe() -> str:
    return str(Path(sys.executable).with_name("seamless-usd"))


def timed(args: list[str], repeat: int) -> tuple[float, dict]:
    """Median wall seconds of ``seamless-usd check ARGS --json`` and its last JSON."""
    times, payload = [], {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        done = subprocess.run([_exe(), "check", *args, "--json"], capture_output=True, text=True)
        times.append(time.perf_counter() - t0)
        if done.returncode not in (0, 1):
            raise SystemExit(f"error: check {' '.join(args)} exited {done.returncode}: {done.stderr[-2000:]}")
        payload = json.loads(done.stdout)
    return statistics.median(times), payload


def library(folder: Path, count: int, seed: int = 0) -> int:
    """``count`` 256 px pictures from the photos: windows (seamed), windows rolled by half (seamed) and whole
    textures made to tile (seamless), as 8-bit PNGs. Returns how many are seamless by construction."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    made = sorted(tileable_photos(PHOTOS))
    photos = sorted(p.name for p in PHOTOS.glob("*.jpg"))
    folder.mkdir(parents=True, exist_ok=True)
    seamless = 0
    cache: dict[str, Image.Image] = {}
    for k in range(count):
        whole = k % 3 == 0
        name = made[rng.integers(len(made))] if whole else photos[rng.integers(len(photos))]
        im = cache.setdefault(name, Image.open(PHOTOS / name).convert("RGB"))
        if whole:
            out = im.resize((256, 256), Image.Resampling.LANCZOS)
            a = np.roll(np.asarray(out), (int(rng.integers(256)), int(rng.integers(256))), (0, 1))
            seamless += 1
        else:
            w, h = im.size
            side = int(min(w, h) * rng.uniform(0.4, 0.8))
            x, y = int(rng.integers(w - side + 1)), int(rng.integers(h - side + 1))
            a = np.asarray(im.crop((x, y, x + side, y + side)).resize((256, 256), Image.Resampling.LANCZOS))
            if k % 3 == 2:
                a = np.roll(a, (128, 128), (0, 1))
        Image.fromarray(np.ascontiguousarray(a)).save(folder / f"p{k:04d}.png")
    return seamless


def main(argv: list[str] | None = None) -> int:
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, required=True)
    ap.add_argument("--size", type=int, default=2048)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--pictures", type=int, default=0, help="also check a folder of this many pictures")
    ap.add_argument("--picture", default=PICTURE, help="the photo of benchmarks/photos checked alone")
    ap.add_argument("--jobs", type=int, default=0, help="check's --jobs for the folder (0: its default)")
    a = ap.parse_args(argv)
    scene = build_scene(a.out / "stack", a.size)
    picture = a.out / "picture.png"
    with Image.open(PHOTOS / a.picture) as im:
        im.convert("RGB").save(picture)
        side = max(im.size)

    load = os.getloadavg()[0]
    seconds, payload = timed([str(scene)], a.repeat)
    [item] = payload["items"]
    print(f"check a {a.size} px 3-map stack: {seconds:.2f} s (median of {a.repeat}, start-up included), "
          f"passed {item['passed']}, {len(item['verdict']['seams'])} seams; load {load:.2f}")
    load = os.getloadavg()[0]
    seconds, payload = timed([str(picture)], a.repeat)
    [item] = payload["items"]
    print(f"check a {side} px picture: {seconds:.2f} s (median of {a.repeat}, start-up included), "
          f"passed {item['passed']}; load {load:.2f}")
    if a.pictures:
        folder = a.out / "library"
        seamless = library(folder, a.pictures)
        load = os.getloadavg()[0]
        t0 = time.perf_counter()
        jobs = ["--jobs", str(a.jobs)] if a.jobs else []
        done = subprocess.run([_exe(), "check", str(folder), "--json", "--report", str(a.out / "sheet.html"), *jobs],
                              capture_output=True, text=True)
        wall = time.perf_counter() - t0
        payload = json.loads(done.stdout)
        items = {Path(i["name"]).stem: i for i in payload["items"]}
        right = sum(items[f"p{k:04d}"]["passed"] == (k % 3 == 0) for k in range(a.pictures))
        print(f"check a folder of {a.pictures} pictures (256 px; {seamless} seamless by construction): {wall:.1f} s "
              f"({1000 * wall / a.pictures:.0f} ms a picture), exit {done.returncode}, {payload['passed']} passed, "
              f"{right} of {a.pictures} as labelled, sheet {(a.out / 'sheet.html').stat().st_size / 2 ** 20:.1f} MiB; "
              f"load {load:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
