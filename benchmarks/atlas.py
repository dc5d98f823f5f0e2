#!/usr/bin/env python3
"""Atlas evidence measured on UV atlases against photos that do not tile and textures that do.

``seamless_usd.discover.atlas`` flags a map that no geometry binds as a UV atlas when a flat
background covers at least ``BACKGROUND_MIN`` of it and cuts the rest into at least
``ISLANDS_MIN`` islands. This script gives the figures those limits come from:

- **atlases**: the bundled baked atlases (``sample_assets/textures/*_atlas*.png``,
  ``teapot_porcelain_arm.png``) and atlases baked the same way with other layouts (3x3 to 8x8
  islands), backgrounds (black, grey, white, a colour) and padding (0 to 6 texels);
- **photos**: windows (256 to 2048 px, several origins) of the MaterialX example images given as
  the source folder (``../shared/textures`` beside the repository), which do not tile;
- **tiling**: the whole source images (periodic) and the bundled ``wood_tileable*.jpg``.

Writes a table of each group's least and most background share and island count. Run::

    .venv/bin/python benchmarks/atlas.py [/path/to/shared/textures]
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "sample_assets"))

from make_variants import bake_atlas  # noqa: E402

from seamless_usd.discover.atlas import BACKGROUND_MIN, ISLANDS_MIN, atlas_figures  # noqa: E402
from seamless_usd.imaging.io import read_image  # noqa: E402


def _atlases(textures: Path) -> dict[str, np.ndarray]:
    out = {p.name: read_image(p)[0] for p in sorted(textures.glob("*_atlas*.png"))}
    out["teapot_porcelain_arm.png"] = read_image(textures / "teapot_porcelain_arm.png")[0]
    sources = {n: read_image(textures / n)[0] for n in ("brick_albedo.png", "wood_color.png", "cloth.png")}
    backgrounds = {"black": (0, 0, 0), "grey": (0.5, 0.5, 0.5), "white": (1, 1, 1), "blue": (0.1, 0.2, 0.6)}
    seed = 10
    for grid in (3, 5, 8):
        for pad in (0, 2, 6):
            for k, (bname, bg) in enumerate(backgrounds.items()):
                sname, src = list(sources.items())[k % len(sources)]
                seed += 1
                layout = (0.02, 0.98, grid, 0)
                out[f"baked {grid}x{grid} pad {pad} {bname} {sname}"] = bake_atlas(layout, src, bg, 256, pad, seed)
    return out


def _photos(source: Path) -> dict[str, np.ndarray]:
    out = {}
    rng = np.random.default_rng(0)
    for p in sorted(source.glob("*.jpg")):
        img = read_image(p)[0]
        h, w = img.shape[:2]
        for size in (256, 512, 1024, 2048):
            if size > min(h, w):
                continue
            for _ in range(3 if size < min(h, w) else 1):
                y, x = rng.integers(0, h - size + 1), rng.integers(0, w - size + 1)
                out[f"{p.name} window {size} at ({x},{y})"] = img[y:y + size, x:x + size]
    return out


def _tiling(source: Path, textures: Path) -> dict[str, np.ndarray]:
    out = {f"{p.name} (whole, periodic)": read_image(p)[0] for p in sorted(source.glob("*.jpg"))}
    for name in ("wood_tileable.jpg", "wood_tileable_roughness.jpg"):
        out[name] = read_image(textures / name)[0]
    return out


def main(argv: list[str]) -> int:
    source = Path(argv[0]) if argv else ROOT.parent / "shared" / "textures"
    textures = ROOT / "sample_assets" / "textures"
    groups = {"atlases": _atlases(textures), "photos": _photos(source), "tiling": _tiling(source, textures)}
    print(f"limits: background >= {BACKGROUND_MIN}, islands >= {ISLANDS_MIN}\n")
    print("| group | images | background min-max | islands min-max | flagged |")
    print("|---|---|---|---|---|")
    worst = {}
    for group, images in groups.items():
        figures = {name: atlas_figures(np.clip(img, 0, 1)) for name, img in images.items()}
        bg = [f.background for f in figures.values()]
        isl = [f.islands for f in figures.values()]
        flagged = sum(f.is_atlas for f in figures.values())
        print(f"| {group} | {len(images)} | {min(bg):.3f}-{max(bg):.3f} | {min(isl)}-{max(isl)} | {flagged} |")
        key = (lambda kv: kv[1].background) if group != "atlases" else (lambda kv: -kv[1].background)
        worst[group] = sorted(figures.items(), key=key)[-3:]
    print()
    for group, items in worst.items():
        for name, f in items:
            print(f"{group:8s} {name}: background {f.background:.3f}, {f.islands} islands")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
