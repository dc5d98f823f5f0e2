#!/usr/bin/env python3
"""When a quilt may be written as passed: quilts of textures that do not repeat, judged and looked at.

A quilt (``seamless_usd.synthesis.lattice.quilt``) is 2 x 2 large source blocks on a torus joined along
minimum-error cuts. Its joins meander like a window cut's, and the verdict misses the same breaks along
them: a stone whose two halves come from two stones, a tone patch with a stepped edge, a stripe that ends
at a cut. This script makes the product's quilt of every item (three seeds, the cheapest worst join; cuts
by the blocks' difference) and, where the texture has long lines, the quilt of the lever not kept whose
cuts run along them (``item/lines``), and prints for each the worst difference along a cut
(``difference_worst``: the two blocks' mean squared difference along it over that of two unrelated
texels), whether the joins *hide* (at most ``QUILT_MAX_DIFFERENCE``, the window cut's threshold, fixed
before these quilts were made), what the verdict says, and the label given by eye where one was (every
quilt the verdict passes, and the low-difference ones). Pictures of those
(``benchmarks/experiments/results/quilt_gate/``): the first map's tile repeated 2 x 2, 2x below 700 px.

``make_tile`` never writes a quilt whose joins do not hide as a tile that passes: such a quilt is written
only where the verdict at full resolution does not pass it (``synthesis/tile.py``). An experiment
(``benchmarks/experiments/``): the gate is open work.

    .venv/bin/python benchmarks/experiments/quilt_gate.py   # writes experiments/results/quilt_gate.md and .json
    .venv/bin/python benchmarks/experiments/quilt_gate.py --items cells_256_2,wood_37_512 --out /tmp/gate
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent  # benchmarks/experiments
sys.path[:0] = [str(HERE), str(HERE.parent), str(HERE.parents[1])]  # its siblings, the benchmarks' plumbing, the library

import numpy as np  # noqa: E402

#: Items: ``cells_S_SEED`` / ``stripes_S_SEED`` (``synthetic.py`` at S px, the tests' feature size scaled
#: with S), and the names of ``window_gate.stack_for`` (turned wood and brick, weave windows, the lit brick).
ITEMS = ("cells_160_6,cells_256_1,cells_256_2,cells_320_3,stripes_160_7,stripes_256_1,stripes_256_2,stripes_320_3,"
         "wood,rot23_wood_512,rot61_wood_512,wood_11_512,wood_37_512,wood_49_512,wood_74_512,rot23_brick_512,"
         "rot61_brick_512,brick_11_512,brick_37_512,brick_49_512,brick_74_512,weave_40_300_300_256,"
         "weave_100_100_500_256,ramp_0.05,ramp_0.1,drift_0.01,drift_0.02,"
         # added after the gate was in place (and labelled then): more stones and stripes, other angles,
         # weave windows and lit-brick ramps
         "cells_192_4,cells_224_5,cells_288_7,cells_160_8,stripes_192_4,stripes_224_5,stripes_288_8,stripes_160_9,"
         "wood_29_512,wood_61_384,brick_29_512,brick_61_384,weave_60_200_400_256,weave_10_10_300_200,ramp_0.02,"
         "drift_0.005").split(",")

#: "item/cut" -> (seamless by eye, what was seen in the 2 x 2 repeat); cut: "difference" or "lines".
LABELS: dict[str, tuple[bool, str]] = {
    "stripes_160_7/difference": (True, "lines run unbroken and unkinked across the joins and wraps (3x)"),
    "weave_100_100_500_256/difference": (True, "threads continue across every join"),
    "cells_256_2/difference": (False, "two-tone stones: halves of two stones meet inside one outline"),
    "stripes_256_2/difference": (False, "stripes end at a cut; darker ground patches with stepped edges"),
    "rot61_wood_512/difference": (False, "tone patches with straight and stepped edges"),
    "weave_40_300_300_256/difference": (False, "notches cut into threads at a join"),
    "ramp_0.05/difference": (False, "a head joint steps and a brick is cut short at a join"),
    "ramp_0.1/difference": (False, "darker brick patches end on a join"),
    "cells_256_2/lines": (False, "stones whole, but joints thicken, fork and leave thin slivers at the joins"),
    "stripes_224_5/difference": (False, "stripes end, cross and fork at the joins"),
    "stripes_288_8/difference": (False, "an orphan stub of a stripe, and stripes that kink at a join"),
    "cells_160_8/difference": (False, "stones of two and three tones inside one outline, joints that end"),
    "stripes_160_7/lines": (False, "forks and stubs where the cut follows one block's line then another's"),
}


def stack_for(name: str) -> dict:
    kind, *rest = name.split("_")
    if kind in ("cells", "stripes") and len(rest) == 2:
        import synthetic

        side, seed = (int(v) for v in rest)
        return getattr(synthetic, kind)(side, (40 if kind == "cells" else 30) * side / 160, seed=seed)
    import window_gate

    return window_gate.stack_for(name)


def run_item(name: str, out: Path) -> list[dict]:
    from seamless_usd.metrics import preview_uint8
    from seamless_usd.synthesis.lattice.quilt import best_quilt
    from seamless_usd.synthesis.tile import QUILT_CELLS, QUILT_MAX_DIFFERENCE, QUILT_TRIES
    from seamless_usd.verdict import judge

    stack = stack_for(name)
    keys = list(stack)
    maps, normals = [stack[k][0] for k in keys], [stack[k][1] for k in keys]
    rows = []
    for lines in (True, False):
        made = best_quilt(maps, maps[0].shape[:2], QUILT_CELLS, QUILT_TRIES, lines=lines)
        if made is None or (lines and not made[1]["lines"]):
            continue  # no lines: the same quilt as by difference
        field, figures = made
        tiles = [np.ascontiguousarray(m[field[..., 0], field[..., 1]]) for m in maps]
        verdict = judge(tiles, maps, normals, keys)
        item = f"{name}/{'lines' if lines else 'difference'}"
        seamless, seen = LABELS.get(item, (None, ""))
        rows.append({"item": item, "tile": list(field.shape[:2]), "difference_worst": figures["difference_worst"],
                     "hides": figures["difference_worst"] <= QUILT_MAX_DIFFERENCE, "verdict_passed": verdict.passed,
                     "seams": len(verdict.seams), "seamless_by_eye": seamless, "seen": seen})
        if item not in LABELS and not verdict.passed:
            continue  # pictures of what was looked at: every quilt the verdict passes, and the labelled ones
        pic = np.tile(preview_uint8(tiles[0], normals[0]), (2, 2, 1))
        if pic.shape[0] <= 700:
            pic = pic.repeat(2, axis=0).repeat(2, axis=1)
        import OpenImageIO as oiio

        (out / "quilt_gate").mkdir(parents=True, exist_ok=True)
        buf = oiio.ImageBuf(pic)
        buf.specmod().attribute("Compression", "jpeg:80")  # pictures to look at, kept small
        buf.write(str(out / "quilt_gate" / f"{item.replace('/', '__')}.jpg"))
    return rows


def summary(rows: list[dict]) -> list[str]:
    """The table's closing lines: what the verdict passes, with and without the gate, against the eye."""
    passed = [r for r in rows if r["verdict_passed"]]
    seen = [r for r in passed if r["seamless_by_eye"] is not None]
    written = [r for r in passed if r["hides"]]
    return ["", f"The verdict passes {len(passed)} of {len(rows)} quilts; all {len(seen)} of those were looked at. "
            f"Seamless by eye: {sum(r['seamless_by_eye'] for r in seen)}. Passed with seams: "
            f"{sum(not r['seamless_by_eye'] for r in seen)} without the gate, "
            f"{sum(not r['seamless_by_eye'] for r in seen if r['hides'])} with it (written as passed: "
            f"{len(written)}, the joins hiding)."]


def main(argv: list[str] | None = None) -> int:
    from window_gate import finish_gate, gate_command

    args, out = gate_command(argv, __doc__, ",".join(ITEMS))
    from seamless_usd.synthesis.tile import QUILT_MAX_DIFFERENCE

    load = os.getloadavg()[0]
    rows = []
    for name in args.items.split(","):
        for row in run_item(name, out):
            rows.append(row)
            print(json.dumps(row), flush=True)
    lines = ["# When a quilt may pass", "",
             "Quilts of textures that do not repeat (`benchmarks/experiments/quilt_gate.py`): the worst difference along a cut, "
             f"whether the joins hide (at most {QUILT_MAX_DIFFERENCE}, the window cut's threshold), the verdict, and "
             "the label by eye from the 2 x 2 repeat (`results/quilt_gate/`). A quilt whose joins do not hide is "
             "never written as passed. "
             f"Load average at the start: {load:.2f}. At the end: {os.getloadavg()[0]:.2f}.", "",
             "| quilt | tile | worst difference | joins hide | verdict | by eye |", "|---|---|---:|---|---|---|"]
    for r in sorted(rows, key=lambda r: r["difference_worst"]):
        eye = "" if r["seamless_by_eye"] is None else ("seamless: " if r["seamless_by_eye"] else "seamed: ") + r["seen"]
        lines.append(f"| {r['item']} | {r['tile'][0]}x{r['tile'][1]} | {r['difference_worst']:.4f} | "
                     f"{'yes' if r['hides'] else 'no'} | {'passed' if r['verdict_passed'] else str(r['seams']) + ' seams'}"
                     f" | {eye} |")
    lines += summary(rows)
    return finish_gate(args, out, "quilt_gate", ",".join(ITEMS), lines, rows)


if __name__ == "__main__":
    sys.exit(main())
