#!/usr/bin/env python3
"""The verdict alone at full resolution: time, peak memory and seams of ``judge`` on one 3-map stack.

The maps are the end-to-end scene's (``endtoend.py``: the MaterialX brick's base colour, normal and
roughness, resized with Lanczos to ``--size`` px, in the network domain); the tile stands in for a cut
of about 0.86 of the source: a crop of it, rolled, so its joins are the crop's wraps and the verdict has
seams to find. One process per run keeps the peak the verdict's own.

    .venv/bin/python benchmarks/verdict_time.py --size 4096
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from endtoend import MAPS as SCENE_MAPS, TEXTURES  # noqa: E402

#: The end-to-end scene's maps: (name, channels read, whether a normal map).
MAPS = tuple((name, 1 if role == "roughness" else 3, role == "normal") for name, role, _ in SCENE_MAPS)


def _peak_gib() -> float:
    with open("/proc/self/status") as f:
        return next(int(line.split()[1]) for line in f if line.startswith("VmHWM")) / 2 ** 20


def stand_in(size: int, textures: Path = TEXTURES) -> tuple[list[np.ndarray], list[np.ndarray], list[bool]]:
    """(tiles, sources, normals): the maps at ``size`` px and a rolled crop of 0.86 of each."""
    import OpenImageIO as oiio

    sources = []
    for name, channels, _ in MAPS:
        buf = oiio.ImageBuf(str(textures / f"{name}.jpg"))
        buf = oiio.ImageBufAlgo.resize(buf, "lanczos3", roi=oiio.ROI(0, size, 0, size, 0, 1, 0, buf.nchannels))
        sources.append(np.ascontiguousarray(buf.get_pixels(oiio.FLOAT)[..., :channels] * 2 - 1, dtype=np.float32))
    side, y, x = round(size * 0.857), size // 40, size // 20
    tiles = [np.ascontiguousarray(np.roll(s[y: y + side, x: x + side], (side // 5, side // 4), (0, 1))) for s in sources]
    return tiles, sources, [normal for *_, normal in MAPS]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=4096)
    args = ap.parse_args(argv)
    tiles, sources, normals = stand_in(args.size)
    from seamless_usd.verdict import judge

    load, before = os.getloadavg()[0], _peak_gib()
    start = time.perf_counter()
    verdict = judge(tiles, sources, normals, [name for name, *_ in MAPS])
    seconds = time.perf_counter() - start
    print(f"verdict at {args.size} px (tile {tiles[0].shape[1]} x {tiles[0].shape[0]}): {seconds:.1f} s, peak "
          f"{_peak_gib():.2f} GiB (maps loaded: {before:.2f}), {len(verdict.seams)} seams, passed {verdict.passed}; "
          f"load {load:.2f} -> {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
