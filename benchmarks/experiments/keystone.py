#!/usr/bin/env python3
"""Structure that converges with perspective: find the vanishing point, rectify, cut, judge.

A wall or pavement shot at a slant has lines that meet at a vanishing point: a brick pavement's long joints lean
one way on the left of the photo and the other way on the right, and its courses come closer towards the far
side. No cut of whole periods fits such a photo, and straightening by one angle (``--straighten``) cannot help.
This experiment measures the first step of the issue's "a lattice that drifts with perspective":

1. **The vanishing point** of the lines that run within 30 degrees of the picture's vertical. The grey picture,
   light broader than 6 px taken away, is read in an 8 x 8 grid of cells; each cell's structure tensor (of the
   gradients within 30 degrees of the horizontal: a grid's other lines left out) gives its lines' lean and its
   coherence. A line through the vanishing point ``(vx, vy)`` passes each cell centre ``(x, y)`` with
   ``tan(a) = (vx - x) / (y - vy)``, fitted by coherence-weighted least squares in ``u = 1 / (y0 - vy)`` and
   ``u vx`` (``y0`` the centre row), so that lines that barely converge (``u`` near 0) are as well posed as lines
   that meet close by (:func:`vanishing_point`). Only leans that spread by at least ``MIN_SPREAD`` degrees across
   the picture are rectified.
2. **The one-point homography** that sends it to infinity: with ``X = x - vx`` and ``Y = y - vy``,
   ``x' = X Yr / Y`` and ``y' = Yr - Yr^2 / Y``. Lines through the vanishing point become vertical, and rows
   evenly spaced on the plane (a camera pitched about the horizontal axis) come out evenly spaced. ``Yr`` is
   the far row, so no texel is magnified: the near rows are shrunk, each through a Gaussian prefilter as wide as
   its shrink (:func:`rectify`). The rectified picture is cut to the largest rectangle of source texels.
3. The product's cuts (:func:`seamless_usd.synthesis.candidates.best_cut`) on the rectified picture, judged by
   the verdict against it, beside the cuts of the photo as it is.

Not in the product: the results are in ``docs/decisions.md`` ("Rectifying perspective"). Pictures (not kept in
the repository): the rectified source, and each tile repeated 3 x 3 beside its source with its wrap corner at 3x.

    .venv/bin/python benchmarks/experiments/keystone.py                       # the angled brick photo
    .venv/bin/python benchmarks/experiments/keystone.py --photos brick_angle_1,tiles_floor_white_1 --out /tmp/ks
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent  # benchmarks/experiments
sys.path[:0] = [str(HERE), str(HERE.parent), str(HERE.parents[1])]  # its siblings, the benchmarks' plumbing, the library

import numpy as np  # noqa: E402

CELLS = 8
LEAN_MAX = np.radians(30.0)  # lines leaning further from the vertical are not read
LIGHT = 6.0  # px: broader changes are light, taken away first
#: Leans spread by fewer degrees (10th to 90th percentile) are parallel lines: the 512 px photos of a tiled floor,
#: a corrugated panel and a concrete-tile facade read 0.8-1.5, the brick pavement shot at a slant 17.
MIN_SPREAD = 3.0


def _grey(values: np.ndarray) -> np.ndarray:
    from scipy import ndimage

    g = np.asarray(values, dtype=np.float64).reshape(values.shape[0], values.shape[1], -1).mean(axis=2)
    return g - ndimage.gaussian_filter(g, LIGHT)


def cell_leans(values: np.ndarray, cells: int = CELLS) -> list[tuple[float, float, float, float]]:
    """(x, y, tan(lean), coherence) of each cell whose dominant lines lean at most LEAN_MAX from the vertical:
    the structure tensor's gradient direction is the lines' normal, so for near-vertical lines it is their lean.
    Only gradients within LEAN_MAX of the horizontal are read, so a grid's other lines do not pull the tensor."""
    g = _grey(values)
    gy, gx = np.gradient(g)
    steep = np.abs(gy) > np.tan(LEAN_MAX) * np.abs(gx)  # gradients of lines leaning further (a grid's other lines)
    gx, gy = np.where(steep, 0.0, gx), np.where(steep, 0.0, gy)
    h, w = g.shape
    out = []
    for i in range(cells):
        for j in range(cells):
            x0, x1, y0, y1 = i * w // cells, (i + 1) * w // cells, j * h // cells, (j + 1) * h // cells
            sx, sy = gx[y0:y1, x0:x1], gy[y0:y1, x0:x1]
            jxx, jyy, jxy = float((sx * sx).sum()), float((sy * sy).sum()), float((sx * sy).sum())
            if jxx + jyy <= 0:
                continue
            phi = 0.5 * np.arctan2(2 * jxy, jxx - jyy)
            if abs(phi) > LEAN_MAX:
                continue
            out.append(((x0 + x1) / 2, (y0 + y1) / 2, float(np.tan(phi)), float(np.hypot(jxx - jyy, 2 * jxy) / (jxx + jyy))))
    return out


def vanishing_point(values: np.ndarray, cells: int = CELLS) -> dict:
    """The vanishing point of the near-vertical lines (see the module notes), with the leans' spread: ``vx``,
    ``vy`` (px, picture coordinates, y down) and ``lean_spread`` (degrees between the cells' least and most lean,
    the coherence-weighted 10th and 90th percentiles: about 0 for lines that run parallel)."""
    leans = cell_leans(values, cells)
    if len(leans) < 4:
        return {"vx": None, "vy": None, "lean_spread": 0.0, "cells": len(leans)}
    x, y, t, c = (np.array(v) for v in zip(*leans))
    from scipy.optimize import least_squares

    # t = (vx - x) / (y - vy), written with u = 1 / (y0 - vy) (0: parallel lines) and p = u vx about the centre row
    # y0, so that lines that barely converge are as well posed as lines that meet close by
    y0 = float(np.average(y, weights=c))
    slope, icept = np.polyfit(x, t, 1, w=c)  # near y0: t = p - u x
    fit = least_squares(lambda q: c * (t - (q[1] - q[0] * x) / (1.0 + q[0] * (y - y0))), [-slope, icept])
    u, p = fit.x
    order = np.argsort(t)
    cum = np.cumsum(c[order]) / c.sum()
    lo, hi = t[order][np.searchsorted(cum, 0.1)], t[order][min(len(t) - 1, np.searchsorted(cum, 0.9))]
    vx, vy = (float(p / u), float(y0 - 1.0 / u)) if abs(u) > 1e-9 else (None, None)
    return {"vx": vx, "vy": vy, "lean_spread": float(np.degrees(np.arctan(hi) - np.arctan(lo))),
            "cells": len(leans)}


def rectify(values: np.ndarray, vx: float, vy: float) -> tuple[np.ndarray, dict]:
    """``values`` (H, W, C) resampled by the one-point homography of the module notes (the vanishing point above
    the picture: ``vy < 0``), cut to the largest rectangle of source texels, and what it did."""
    from scipy import ndimage

    h, w = values.shape[:2]
    if vy >= 0:
        raise ValueError("the lines do not meet above the picture")
    y_top, y_bottom = -vy, h - 1 - vy
    yr = y_top  # the far row keeps its texel size; nearer rows shrink, none is magnified
    out_h = int(yr - yr * yr / y_bottom)
    left = max(-vx * yr / y_top, -vx * yr / y_bottom)
    right = min((w - 1 - vx) * yr / y_top, (w - 1 - vx) * yr / y_bottom)
    out_w = int(right - left)
    if out_w < 16 or out_h < 16:
        raise ValueError(f"the rectified picture keeps only {out_w} x {out_h} texels")
    yp, xp = np.mgrid[0:out_h, 0:out_w].astype(np.float64)
    big_y = yr * yr / (yr - yp)
    sy, sx = big_y + vy, (xp + left) * big_y / yr + vx
    shrink = float(y_bottom / yr)  # the nearest row's linear shrink along x (its square along y)
    flat = np.asarray(values, dtype=np.float64).reshape(h, w, -1)
    lo, hi = flat.min(axis=(0, 1)), flat.max(axis=(0, 1))
    sigma = 0.5 * max(0.0, shrink - 1.0)  # one prefilter for the whole picture: the mean shrink's
    chans = [ndimage.map_coordinates(ndimage.gaussian_filter(flat[..., k], sigma) if sigma else flat[..., k],
                                     [sy, sx], order=3, mode="nearest") for k in range(flat.shape[2])]
    out = np.clip(np.stack(chans, axis=-1), lo, hi).astype(np.float32)
    return out, {"size": [out_w, out_h], "source_size": [w, h], "near_shrink_x": round(shrink, 3),
                 "near_shrink_y": round(shrink * shrink, 3)}


def _cut(pixels: np.ndarray, seed: int = 0) -> tuple[np.ndarray, dict]:
    from seamless_usd.synthesis import MapInput
    from seamless_usd.synthesis.candidates import best_cut

    cut, made = best_cut([MapInput("color", pixels)], True, seed)
    if cut.kind is None:
        raise ValueError("no tile can be cut")
    return cut.tiles["color"], {"kind": cut.kind, "passed": cut.passes, "score": round(cut.score, 3), **made}


def run_photo(path: Path, size: int, folder: Path | None) -> dict:
    from photos import load_photo, pictures, to_uint8

    photo = load_photo(path, size)
    t0 = time.perf_counter()
    vp = vanishing_point(photo)
    row = {"photo": path.name, "size": list(photo.shape[1::-1]), "vanishing_point": vp}
    tile, row["as_is"] = _cut(photo)
    if folder is not None:
        pictures(path.stem, "as-is", tile, photo, folder)
    if vp["vy"] is None or vp["vy"] >= 0 or vp["lean_spread"] < MIN_SPREAD:
        row["rectified"] = None
        return row
    rect, row["rectify"] = rectify(photo, vp["vx"], vp["vy"])
    row["rectify"]["seconds"] = round(time.perf_counter() - t0, 2)
    row["rectify"]["after"] = vanishing_point(rect)
    tile, row["rectified"] = _cut(rect)
    if folder is not None:
        from PIL import Image

        pictures(path.stem, "rectified", tile, rect, folder)
        Image.fromarray(to_uint8(rect)).save(folder / f"{path.stem}__rectified_source.png")
    return row


def _text(cut: dict | None) -> str:
    if not cut:
        return "-"
    return f"{cut['kind']} {'passed' if cut['passed'] else 'not passed'} {cut['score']:.2f}"


def markdown(rows: list[dict], header: str = "") -> str:
    lines = ["# Rectifying perspective (experiment)", "", *([header, ""] if header else []),
             "| photo | size | vanishing point (x, y) | lean spread | rectified to | spread after | cut as is | cut rectified |",
             "|---|---|---|---:|---|---:|---|---|"]
    for r in rows:
        vp, rect = r["vanishing_point"], r.get("rectify") or {}
        at = "-" if vp["vx"] is None else f"{vp['vx']:.0f}, {vp['vy']:.0f}"
        after = rect.get("after", {}).get("lean_spread")
        lines.append(f"| {r['photo']} | {r['size'][0]}x{r['size'][1]} | {at} | {vp['lean_spread']:.1f} | "
                     f"{'x'.join(map(str, rect['size'])) if rect else '-'} | {'-' if after is None else f'{after:.1f}'} | "
                     f"{_text(r['as_is'])} | {_text(r.get('rectified'))} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--photos", default="brick_angle_1,tiles_floor_white_1,metal_corrugated_wall_1,"
                    "facade_concrete_tiles_1,concrete_wall_1",
                    help="names in benchmarks/photos (without .jpg)")
    ap.add_argument("--size", type=int, default=512, help="longest side (px)")
    ap.add_argument("--folder", type=Path, default=HERE.parent / "photos")
    ap.add_argument("--out", type=Path, default=HERE / "results")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    rows = [run_photo(a.folder / f"{name}.jpg", a.size, a.out / "keystone") for name in a.photos.split(",")]
    header = (f"`benchmarks/experiments/keystone.py --photos {a.photos} --size {a.size}`: "
              f"{time.perf_counter() - t0:.0f} s, load average {load:.2f} before, {os.getloadavg()[0]:.2f} after. "
              "Cuts: the product's (lattice, window, mend, quilt; levelled or evened where none passes), judged by the "
              "verdict against the picture they were cut from; lean spread in degrees.")
    (a.out / "keystone.json").write_text(json.dumps(rows, indent=1))
    (a.out / "keystone.md").write_text(markdown(rows, header))
    print(markdown(rows, header))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
