#!/usr/bin/env python3
"""When a window cut may be offered: window cuts of textures that do not repeat, looked at and labelled.

A window cut (``seamless_usd.synthesis.lattice.window``) is one window of the source joined across its
wraps along minimum-error cuts. Where the texture continues itself at the window's lags (a weave whose
windows repeat) the cut finds an invisible join; where it does not, the join shows: tone patches with
stair-stepped edges, mortar lines ending at the cut, threads cut in half. This script makes the window cut
of every item, and for each prints the chosen lags' difference (``window_tile_size``'s figures: 0, the
texture continues itself exactly; about 1, the wrap joins unrelated places), whether the product offers
the cut (``continues_itself``: both figures at most ``WINDOW_MAX_DIFFERENCE``), what the verdict says of
it, and the label given by eye. Pictures (``benchmarks/experiments/results/window_gate/``): the first
map's two join bands, the tile's columns and rows across each wrap (its texels 16 before the wrap to 16
past the cut's band), side by side, enlarged 2x (1x at 2K), which is how the labels were given.

The *tuning* items were looked at before the gate's threshold was chosen; the *held-back* ones (other
angles, other windows of the weave, the 2048 px stacks, and the repeating brick made to repeat less
exactly, by a tone ramp or a drifting scale, whose figures fall on both sides of the threshold) after it
was fixed. An experiment (``benchmarks/experiments/``): the gate is open work; its threshold lives in
``seamless_usd/synthesis/lattice/window.py``.

    .venv/bin/python benchmarks/experiments/window_gate.py   # writes experiments/results/window_gate.md and .json
    .venv/bin/python benchmarks/experiments/window_gate.py --items cloth,wood_37_512 --out /tmp/gate
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

import stacks  # noqa: E402
from results_io import write_results  # noqa: E402

RESULTS = HERE / "results"
WOOD = stacks.STACKS["rot23_wood_512"].maps
BRICK = stacks.STACKS["rot23_brick_512"].maps
WEAVE = stacks.STACKS["mx_cloth"].maps

#: name -> (split, seamless by eye, what was seen along the two wraps). Names ``wood_A_S`` / ``brick_A_S``: the
#: MaterialX maps repeated and turned A degrees, an S px window (as ``stacks.rot23_wood_512``); ``weave_X_Y_S_O``:
#: an S px window at (X, Y) of the MaterialX weave resized to O px (as ``stacks.mx_cloth``).
LABELS: dict[str, tuple[str, bool, str]] = {
    "cloth": ("tuning", True, "threads continue across both wraps"),
    "mx_cloth": ("tuning", True, "threads continue across both wraps"),
    "cells_512": ("tuning", False, "stones cut along the wrap, half-stones glued"),
    "stripes_512": ("tuning", False, "stripes jump at the wrap"),
    "wood": ("tuning", False, "grain ends on a stepped edge across the x wrap (faint, seen at 4x)"),
    "rot23_wood_512": ("tuning", False, "tone patches with stair-stepped edges"),
    "rot61_wood_512": ("tuning", False, "tone patches with stair-stepped edges"),
    "wood_11_512": ("tuning", False, "tone patches with stair-stepped edges"),
    "wood_37_512": ("tuning", False, "faint tone patch edges"),
    "wood_49_512": ("tuning", False, "tone patches with stair-stepped edges"),
    "wood_74_512": ("tuning", False, "tone patches with stair-stepped edges across the y wrap"),
    "rot23_brick_512": ("tuning", False, "a mortar line ends mid-brick; a brick-tone patch with a jagged edge"),
    "rot61_brick_512": ("tuning", False, "mortar lines end at the cut"),
    "brick_11_512": ("tuning", False, "mortar lines end at the cut"),
    "brick_37_512": ("tuning", False, "mortar lines end at the cut"),
    "brick_49_512": ("tuning", False, "a mortar line jogs sideways"),
    "brick_74_512": ("tuning", False, "mortar lines end at the cut"),
    "wood_17_512": ("held-back", False, "tone patches with stair-stepped edges"),
    "wood_29_512": ("held-back", False, "tone patches with stair-stepped edges"),
    "wood_43_512": ("held-back", False, "tone patches with stair-stepped edges"),
    "wood_67_512": ("held-back", False, "tone patches with stair-stepped edges"),
    "wood_83_512": ("held-back", False, "tone patches with stair-stepped edges across the y wrap"),
    "brick_17_512": ("held-back", False, "mortar lines end at the cut"),
    "brick_29_512": ("held-back", False, "mortar lines end at the cut"),
    "brick_43_512": ("held-back", False, "a mortar line kinks and narrows (slight, seen at 4x)"),
    "brick_67_512": ("held-back", False, "mortar lines end at the cut"),
    "brick_83_512": ("held-back", False, "mortar lines end at the cut"),
    "weave_40_300_300_256": ("held-back", False, "a thread doubled, another cut across"),
    "weave_100_100_500_256": ("held-back", False, "a bright thread cut across by a dark line"),
    "weave_250_20_380_320": ("held-back", True, "threads continue across both wraps"),
    "rot61_wood_2048": ("held-back", False, "a dark tone patch with a stepped edge"),
    "rot61_brick_2048": ("held-back", False, "a brick-tone patch with a straight edge; a corner joint broken"),
    # the MaterialX brick (it repeats) over 1.3 periods, made to repeat less and less exactly: an added tone ramp
    # (network units across the window) or a scale that drifts across it (perspective-like, share of the scale)
    "ramp_0.02": ("held-back", True, "mortar and bricks continue, no tone step seen"),
    "ramp_0.05": ("held-back", False, "a faint tone step inside a brick (seen at 3x)"),
    "ramp_0.1": ("held-back", False, "a darker patch with a jagged edge"),
    "ramp_0.2": ("held-back", False, "tone patches with jagged edges"),
    "drift_0.005": ("held-back", True, "mortar lines continue across both wraps"),
    "drift_0.01": ("held-back", False, "mortar lines jog a few texels at the cut"),
    "drift_0.02": ("held-back", False, "mortar lines jog at the cut"),
    "drift_0.04": ("held-back", False, "mortar lines jog and end at the cut"),
}


def stack_for(name: str) -> dict:
    """The maps of item ``name`` in the network domain (see :data:`LABELS` for the names it builds)."""
    kind, *numbers = name.split("_")
    if kind in ("ramp", "drift"):
        import verdict_corpus

        return {"base_gray": (verdict_corpus.lit_brick(kind, float(numbers[0])), False)}
    if name not in stacks.STACKS:
        if kind == "weave":
            x, y, size, out = (int(v) for v in numbers)
            stacks.STACKS[name] = stacks.StackSpec("shared", WEAVE, window=(x, y, size, out))
        else:
            angle, side = numbers
            stacks.STACKS[name] = stacks.StackSpec("shared", WOOD if kind == "wood" else BRICK,
                                                   rotated=(float(angle), int(side)))
    return stacks.load_stack(name)


def join_bands(tile: np.ndarray, band: tuple[int, int], margin: int = 16) -> np.ndarray:
    """The tile's columns and rows across each wrap (``margin`` texels before it to ``margin`` past the band
    the cut runs in), rows laid side by side with the columns: an 8-bit picture."""
    th, tw = tile.shape[:2]
    bh, bw = band
    cols = np.roll(tile, margin, axis=1)[:, : bw + 2 * margin]
    rows = np.roll(tile, margin, axis=0)[: bh + 2 * margin].transpose(1, 0, 2)
    n = max(th, tw)
    pad = lambda a: np.pad(a, ((0, n - a.shape[0]), (0, 0), (0, 0)), constant_values=1.0)
    gap = np.ones((n, 8, tile.shape[2]), tile.dtype)
    pic = np.concatenate([pad(cols), gap, pad(rows)], axis=1)
    pic = pic[..., :3] if pic.shape[2] >= 3 else np.repeat(pic[..., :1], 3, axis=2)
    return np.clip((pic + 1.0) * 127.5, 0, 255).astype(np.uint8)


def run_item(name: str, out: Path) -> dict:
    from seamless_usd.synthesis.lattice.cut import lattice_cut
    from seamless_usd.synthesis.lattice.window import continues_itself, window_tile_size
    from seamless_usd.verdict import judge

    stack = stack_for(name)
    keys = list(stack)
    maps, normals = [stack[k][0] for k in keys], [stack[k][1] for k in keys]
    split, seamless, seen = LABELS[name]
    sizes = window_tile_size(maps)
    if sizes is None:
        return {"item": name, "split": split, "seamless_by_eye": seamless, "seen": seen, "window": None}
    tile_hw, band, figures = sizes
    field, _ = lattice_cut(maps, tile_hw, band)
    tiles = [np.ascontiguousarray(m[field[..., 0], field[..., 1]]) for m in maps]
    t0 = time.perf_counter()
    verdict = judge(tiles, maps, normals, keys, fidelity=False)
    seconds = time.perf_counter() - t0
    pic = join_bands(tiles[0], band)
    if max(tile_hw) <= 600:
        pic = pic.repeat(2, axis=0).repeat(2, axis=1)
    import OpenImageIO as oiio

    (out / "window_gate").mkdir(parents=True, exist_ok=True)
    oiio.ImageBuf(pic).write(str(out / "window_gate" / f"{name}.jpg"))
    return {"item": name, "split": split, "seamless_by_eye": seamless, "seen": seen, "window": list(tile_hw),
            "lag_difference": figures, "offered": continues_itself(figures), "verdict_seams": len(verdict.seams),
            "verdict_passed": verdict.seamless, "verdict_seconds": round(seconds, 1)}


def _share(rows: list[dict], key: str) -> str:
    right = sum(r[key] == r["seamless_by_eye"] for r in rows)
    return f"{right}/{len(rows)}"


def gate_command(argv: list[str] | None, doc: str, items: str) -> tuple[argparse.Namespace, Path]:
    """A gate's command line (this one's and ``quilt_gate.py``'s): ``--items`` (comma-separated, ``items``
    by default) and ``--out``; returns the arguments and the folder the results go to."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--items", default=items)
    ap.add_argument("--out", type=Path, default=None, help="folder for the table, figures and pictures "
                    "(default: experiments/results/, written for every item only)")
    args = ap.parse_args(argv)
    return args, args.out or RESULTS


def finish_gate(args: argparse.Namespace, out: Path, name: str, items: str, lines: list[str],
                rows: list[dict]) -> int:
    """Write a gate's table and figures as ``out/{name}.md`` and ``.json`` (for a run of every item,
    ``items``, or with ``--out``), print the table, and return the exit code."""
    if args.out is not None or args.items == items:
        write_results(out, name, "\n".join(lines) + "\n", rows, end="\n")
    print("\n".join(lines))
    return 0


def main(argv: list[str] | None = None) -> int:
    args, out = gate_command(argv, __doc__, ",".join(LABELS))
    from seamless_usd.synthesis.lattice.window import WINDOW_MAX_DIFFERENCE

    load = os.getloadavg()[0]
    rows = []
    for name in args.items.split(","):
        row = run_item(name, out)
        rows.append(row)
        print(json.dumps(row), flush=True)
    done = [r for r in rows if r["window"] is not None]
    lines = ["# When a window cut is offered", "",
             "Window cuts of textures that do not repeat on a lattice (`benchmarks/experiments/window_gate.py`), each labelled by "
             "eye from its two join bands (`results/window_gate/<item>.jpg`, 2x; 1x at 2048 px). *Offered*: the "
             f"chosen lags' difference is at most {WINDOW_MAX_DIFFERENCE} on both axes, so `make_tile` weighs the cut "
             "against the refined tile. *Verdict*: what the product's verdict says of the cut on its own. "
             f"Load average at the start: {load:.2f}. At the end: {os.getloadavg()[0]:.2f}.", "",
             "| item | split | window | lag difference y / x | offered | verdict | by eye |",
             "|---|---|---|---|---|---|---|"]
    for r in done:
        fig = r["lag_difference"]
        lines.append(f"| {r['item']} | {r['split']} | {r['window'][0]}x{r['window'][1]} | {fig['y']:.4f} / {fig['x']:.4f} "
                     f"| {'yes' if r['offered'] else 'no'} | "
                     f"{'passed' if r['verdict_passed'] else str(r['verdict_seams']) + ' seams'} | "
                     f"{'seamless' if r['seamless_by_eye'] else 'seamed'}: {r['seen']} |")
    lines += ["", "| split | items | offered = seamless by eye | verdict passed = seamless by eye | "
              "seamed cuts the verdict passed | seamed cuts offered |", "|---|---:|---|---|---:|---:|"]
    for split in ("tuning", "held-back"):
        part = [r for r in done if r["split"] == split]
        if part:
            seamed = [r for r in part if not r["seamless_by_eye"]]
            lines.append(f"| {split} | {len(part)} | {_share(part, 'offered')} | {_share(part, 'verdict_passed')} | "
                         f"{sum(r['verdict_passed'] for r in seamed)} | {sum(r['offered'] for r in seamed)} |")
    return finish_gate(args, out, "window_gate", ",".join(LABELS), lines, rows)


if __name__ == "__main__":
    sys.exit(main())
