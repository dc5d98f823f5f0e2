#!/usr/bin/env python3
"""The peer: GIMP's Resynthesizer making a photo tileable, as artists do by hand.

Runs in its own environment, never the project's (Resynthesizer is GPL-3.0; PyPI ``resynthesizer``):

    python3 -m venv .peers && .peers/bin/pip install resynthesizer
    .peers/bin/python benchmarks/peers/resynthesizer_tile.py IN.png OUT.png --band 0.15

The photo is offset by half its size, so its own wrap is seamless and its edges meet in a cross in the
middle; a band over that cross (``--band``: its total width, a share of each side) is masked and
re-synthesised from the rest of the photo with the tileable option on (the synthesis treats the image as
a torus). Prints the seconds the synthesis took.
"""
from __future__ import annotations

import argparse
import time

from PIL import Image, ImageChops, ImageDraw


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("src")
    p.add_argument("dst")
    p.add_argument("--band", type=float, default=0.15, help="total width of the band over each seam, a share of the side")
    a = p.parse_args()
    from resynthesizer import getDefaultParams, resynthesize

    image = Image.open(a.src).convert("RGB")
    w, h = image.size
    rolled = ImageChops.offset(image, w // 2, h // 2)
    mask = Image.new("L", (w, h), 0)
    draw = ImageDraw.Draw(mask)
    bx, by = max(2, round(w * a.band / 2)), max(2, round(h * a.band / 2))
    draw.rectangle([w // 2 - bx, 0, w // 2 + bx - 1, h - 1], fill=255)
    draw.rectangle([0, h // 2 - by, w - 1, h // 2 + by - 1], fill=255)
    t0 = time.perf_counter()
    out = resynthesize(rolled, mask, getDefaultParams())
    print(f"{time.perf_counter() - t0:.3f}")
    out.save(a.dst)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
