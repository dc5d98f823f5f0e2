#!/usr/bin/env python3
"""Cuts of walls lit unevenly, with and without the copies' tone levelled (a lever measured, not kept).

The product cuts a stack that repeats to whole lattice periods (``seamless_usd.synthesis.lattice.cut``),
and one that continues itself to one window (``.window``). Both join the crop's texels with their copies
one tile on. Where the wall is lit unevenly, the copies differ in tone, and a brick the cut crosses is
split in two tones (seen at 3x on the lattice cut at a ramp of 0.05, which the verdict passed:
``results/verdict.md``, kind ``lattice-lit``). :func:`tone_matched` removes the light's change over one
tile as a linear ramp over the texels' source places. Measured and not kept (README, verdict section): the
ramp-0.1 bricks stay two-tone at 3x, and every texel moves by more than the one 8-bit code within which the
verdict finds a copy, so the verdict judges the levelled tile by its classifier alone and passes drifting
bricks whose mortar jogs. A first form offset only a band beside each cut (each side cross-faded to the
other's low-passed tone); the verdict then named the band's straight edge as a seam at 5 places on the ramp
of 0.05 that it passed plain.

For each item this makes the product's cut (the lattice where one is found and fits, else the window
where it is offered), plain and tone-matched, and prints: the verdict on each; the fidelity figures
against the source (feature scale, patch distance); the share of texels that are not exact source copies;
and the tone step at the cuts, the mean absolute difference, along each cut, of the low-passed tile on its
two sides against the low-passed source's own step there. Pictures (``results/lattice_tone/``): the two
join bands of each (as ``window_gate.join_bands``), 3x, plain left of matched; the labels were given from
them.

Items: the MaterialX brick (it repeats) over 1.3 periods, lit by a tone ramp of 0-0.2 network units across
it (``verdict_corpus.lit_brick``) or with a scale drifting by 0.5-4 % across it; the bundled brick sample
and the MaterialX brick and weave windows of the quality benchmark.

    .venv/bin/python benchmarks/lattice_tone.py            # writes results/lattice_tone.md and .json
    .venv/bin/python benchmarks/lattice_tone.py --items ramp_0.05 --out /tmp/tone
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import numpy as np  # noqa: E402

RESULTS = HERE / "results"
ITEMS = ("ramp_0", "ramp_0.02", "ramp_0.05", "ramp_0.1", "ramp_0.2", "drift_0.005", "drift_0.01", "drift_0.02",
         "drift_0.04", "brick", "mx_brick", "cloth", "mx_cloth")


def _stack(name: str) -> dict:
    kind, *numbers = name.split("_")
    if kind in ("ramp", "drift"):
        import verdict_corpus

        return {"base_gray": (verdict_corpus.lit_brick(kind, float(numbers[0])), False)}
    import stacks

    return stacks.load_stack(name)


def product_cut(maps: list[np.ndarray]):
    """(kind, field, offset, tile, band) of the product's cut of ``maps``, or None."""
    from seamless_usd.synthesis.lattice.cut import find_lattice, lattice_cut, lattice_tile_size
    from seamless_usd.synthesis.lattice.window import continues_itself, window_tile_size

    lattice = find_lattice(maps)
    sizes = lattice_tile_size(maps[0].shape[:2], lattice) if lattice.found else None
    kind = "lattice"
    if sizes is None:
        window = window_tile_size(maps)
        if window is None or not continues_itself(window[2]):
            return None
        sizes, kind = window[:2], "window"
    field, offset = lattice_cut(maps, *sizes)
    return kind, field, offset, sizes[0], sizes[1]


def tone_matched(maps: list[np.ndarray], normals: list[bool], field: np.ndarray, offset: tuple[int, int],
                 tile: tuple[int, int], band: tuple[int, int]) -> list[np.ndarray]:
    """The tiles (float32, one per map) of a lattice or window cut (``lattice_cut``'s ``field`` and
    ``offset``, for ``tile`` and ``band``) with the light's change over one tile removed: the median difference
    between the crop's texels and their copies one tile on over each cut's band (one figure per channel and
    axis), removed as a linear ramp over the texels' source places (a texel ``k`` texels along an axis from the
    crop's first gets ``D * k / tile``), so the copies one tile on carry the crop's own tone. Normal maps are
    left as they are (lighting is not in them).
    """
    (th, tw), (bh, bw) = tile, band
    y0, x0 = offset
    fy, fx = field[..., 0], field[..., 1]
    out = []
    for m, is_normal in zip(maps, normals):
        src = np.asarray(m, dtype=np.float32)
        src = src[..., None] if src.ndim == 2 else src
        t = np.ascontiguousarray(src[fy, fx])
        if is_normal or bw < 1 or bh < 1:
            out.append(t)
            continue
        # own - one tile on over each band, its median: the light's change over one tile, not the texels' own
        # differences where the copies sit a texel off the lattice or the pattern drifts
        d = np.median((src[y0: y0 + th + bh, x0: x0 + bw] - src[y0: y0 + th + bh, x0 + tw: x0 + tw + bw]
                       ).reshape(-1, src.shape[-1]), axis=0)
        e = np.median((src[y0: y0 + bh, x0: x0 + tw] - src[y0 + th: y0 + th + bh, x0: x0 + tw]
                       ).reshape(-1, src.shape[-1]), axis=0)
        ramp = d * ((fx - x0) / tw)[..., None] + e * ((fy - y0) / th)[..., None]
        t += ramp - ramp.mean(axis=(0, 1))
        out.append(t)
    return out


def tone_step(tile: np.ndarray, field: np.ndarray, source: np.ndarray, sigma: float) -> float:
    """Mean absolute low-frequency step between neighbours that are not source neighbours (the cuts'
    texel pairs), less the source's own low-frequency step there: what the cuts add, in map units."""
    from scipy import ndimage

    low_t = ndimage.gaussian_filter(tile, (sigma, sigma, 0), mode="wrap")
    low_s = ndimage.gaussian_filter(source, (sigma, sigma, 0), mode="nearest")
    steps = []
    for axis, step in ((0, np.array([1, 0])), (1, np.array([0, 1]))):
        nxt = np.roll(field, -1, axis=axis)
        joined = np.any(nxt != field + step, axis=-1)
        if not joined.any():
            continue
        a = low_t[joined]
        b = np.roll(low_t, -1, axis=axis)[joined]
        fy, fx = field[..., 0][joined], field[..., 1][joined]
        ny = np.minimum(fy + step[0], source.shape[0] - 1)
        nx = np.minimum(fx + step[1], source.shape[1] - 1)
        own = np.abs(low_s[ny, nx] - low_s[fy, fx])
        steps.append(np.maximum(np.abs(b - a) - own, 0).mean())
    return float(np.mean(steps)) if steps else 0.0


def run_item(name: str, out: Path) -> dict:
    import OpenImageIO as oiio
    from window_gate import join_bands

    from seamless_usd.metrics import patch_distance, scale_ratio
    from seamless_usd.verdict import judge
    from seamless_usd.verdict.copies import copy_origins

    stack = _stack(name)
    keys = list(stack)
    maps, normals = [stack[k][0] for k in keys], [stack[k][1] for k in keys]
    cut = product_cut(maps)
    if cut is None:
        return {"item": name, "cut": None}
    kind, field, offset, tile_hw, band = cut
    plain = [np.ascontiguousarray(m[field[..., 0], field[..., 1]]).astype(np.float32) for m in maps]
    matched = tone_matched(maps, normals, field, offset, tile_hw, band)
    row = {"item": name, "cut": kind, "tile": list(tile_hw), "band": list(band)}
    sigma = max(2.0, min(band) / 3.0)
    for label, tiles in (("plain", plain), ("matched", matched)):
        v = judge(tiles, maps, normals, keys)
        changed = np.zeros(tile_hw, dtype=bool)
        for t, m in zip(tiles, maps):
            changed |= np.abs(t - np.asarray(m, np.float32)[field[..., 0], field[..., 1]]).reshape(*tile_hw, -1).max(-1) > 0
        _, placed = copy_origins(np.concatenate([t.reshape(*tile_hw, -1) for t in tiles], -1).astype(np.float64),
                                 np.concatenate([np.asarray(m).reshape(*m.shape[:2], -1) for m in maps], -1
                                                ).astype(np.float64))
        row[label] = {"passed": v.passed, "placed": round(float(placed), 3), "seams": len(v.seams), "strongest": round(float(v.strongest / v.margin), 3),
                      "scale": round(max(abs(scale_ratio(t, m, n) - 1) for t, m, n in zip(tiles, maps, normals)) + 1, 3),
                      "patch": round(max(patch_distance(t, m, n) for t, m, n in zip(tiles, maps, normals)), 3),
                      "changed": round(float(changed.mean()), 4),
                      "tone_step": round(max(tone_step(t.reshape(*tile_hw, -1), field, np.asarray(m, np.float32).reshape(
                          *m.shape[:2], -1), sigma) for t, m, n in zip(tiles, maps, normals) if not n), 4)}
    (out / "lattice_tone").mkdir(parents=True, exist_ok=True)
    a, b = (join_bands(t.reshape(*tile_hw, -1), band) for t in (plain[0], matched[0]))
    pic = np.concatenate([a, np.full((a.shape[0], 12, 3), 255, np.uint8), b], axis=1).repeat(3, 0).repeat(3, 1)
    oiio.ImageBuf(np.ascontiguousarray(pic)).write(str(out / "lattice_tone" / f"{name}.jpg"))
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--items", default=",".join(ITEMS))
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    load = os.getloadavg()[0]
    rows = []
    for name in args.items.split(","):
        row = run_item(name, args.out)
        rows.append(row)
        print(json.dumps(row), flush=True)
    end = os.getloadavg()[0]
    lines = ["# Cuts of walls lit unevenly: the copies' tone levelled", "",
             "`benchmarks/lattice_tone.py`: the product's cut of each item (lattice, else window), plain and with "
             "the light's change over one tile removed as a linear ramp (`tone_matched` there). "
             "Verdict: passed, or its seams and strongest run over its threshold. Tone step: the low-passed tile's "
             "step across the cuts beyond the source's own (map units). Scale, patch: the worst map against the "
             "source. Changed: share of texels that are not exact source copies. Placed: share of texels the verdict "
             "places in the source (found within one 8-bit code, or inferred beside found ones; under 0.9 it cannot "
             "read the tile as copies and judges it by its classifier alone). Pictures: "
             f"`results/lattice_tone/<item>.jpg`, join bands at 3x, plain left of matched. Load average at the "
             f"start: {load:.2f}. At the end: {end:.2f}.", "",
             "| item | cut | tile | verdict plain / matched | tone step | scale | patch | changed | placed |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if r["cut"] is None:
            lines.append(f"| {r['item']} | none | | | | | | | |")
            continue
        p, m = r["plain"], r["matched"]
        say = lambda x: "passed" if x["passed"] else f"{x['seams']} seams ({x['strongest']:.2f})"  # noqa: E731
        lines.append(f"| {r['item']} | {r['cut']} | {r['tile'][0]}x{r['tile'][1]} | {say(p)} / {say(m)} | "
                     f"{p['tone_step']:.4f} / {m['tone_step']:.4f} | {p['scale']:.2f} / {m['scale']:.2f} | "
                     f"{p['patch']:.2f} / {m['patch']:.2f} | {p['changed']:.1%} / {m['changed']:.1%} | "
                     f"{p['placed']:.2f} / {m['placed']:.2f} |")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "lattice_tone.md").write_text("\n".join(lines) + "\n")
    (args.out / "lattice_tone.json").write_text(json.dumps({"load": [load, end], "rows": rows}, indent=1))
    print(f"wrote @{args.out / 'lattice_tone.md'}@")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
