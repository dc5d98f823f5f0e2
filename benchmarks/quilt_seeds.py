#!/usr/bin/env python3
"""Would a wider search hide a quilt's joins? The worst join's difference over more seeds, smaller blocks
or a smaller tile, on the quilt gate's items.

The product makes ``QUILT_TRIES`` quilts of a stack (seeds 0, 1, ...) and keeps the one whose worst join
costs least (``seamless_usd.synthesis.lattice.quilt.best_quilt``); a quilt is written as passed only where
that join's difference is at most ``QUILT_MAX_DIFFERENCE`` (``benchmarks/quilt_gate.py``). This script
makes ``--seeds`` quilts of every item of ``quilt_gate.py`` and prints the best worst-join difference of
the product's first ``QUILT_TRIES`` seeds against that of all of them, and every seed's: whether a wider
search would bring the structured stacks' joins under the threshold. ``--cells`` and ``--tile`` change
the blocks and the tile's size (the product's: 2 x 2 blocks on a source-sized tile).

    .venv/bin/python benchmarks/quilt_seeds.py                 # writes results/quilt_seeds.md
    .venv/bin/python benchmarks/quilt_seeds.py --seeds 6 --items cells_256_1,wood_37_512 --out /tmp/seeds
    .venv/bin/python benchmarks/quilt_seeds.py --seeds 3 --cells 3x3   # smaller blocks: results/quilt_seeds_3x3.md
    .venv/bin/python benchmarks/quilt_seeds.py --seeds 3 --tile 0.8    # a smaller tile: results/quilt_seeds_tile0.8.md
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

import quilt_gate  # noqa: E402


def run_item(name: str, seeds: int, cells: tuple[int, int] | None = None, tile: float = 1.0) -> dict | None:
    """The worst-join difference of each seed's quilt (``cells`` blocks, the product's by default, of a tile
    ``tile`` times the source's sides), the product's best of its tries, and the best of all."""
    from seamless_usd.synthesis.lattice.quilt import quilt_field, quilt_order
    from seamless_usd.synthesis.tile import QUILT_CELLS, QUILT_TRIES

    stack = quilt_gate.stack_for(name)
    maps = [stack[k][0] for k in stack]
    start = time.perf_counter()
    hw = tuple(round(n * tile) for n in maps[0].shape[:2])
    made = [quilt_field(maps, hw, cells or QUILT_CELLS, seed=s) for s in range(seeds)]
    if any(q is None for q in made):
        return None
    figures = [q[1] for q in made]

    def best(group: list[dict]) -> float:  # best_quilt's choice
        return min(group, key=quilt_order)["difference_worst"]

    return {"item": name, "tile": list(hw), "product": best(figures[:QUILT_TRIES]),
            "all": best(figures), "seeds": [f["difference_worst"] for f in figures],
            "seconds": round(time.perf_counter() - start, 1)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--items", default=",".join(quilt_gate.ITEMS))
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--cells", default=None, help="blocks, e.g. 3x3 (default: the product's)")
    ap.add_argument("--tile", type=float, default=1.0, help="the tile's sides over the source's (the product's: 1)")
    ap.add_argument("--out", type=Path, default=quilt_gate.RESULTS)
    args = ap.parse_args(argv)
    from seamless_usd.synthesis.tile import QUILT_CELLS, QUILT_MAX_DIFFERENCE, QUILT_TRIES

    cells = tuple(int(v) for v in args.cells.split("x")) if args.cells else QUILT_CELLS
    name = ("quilt_seeds" + ("" if cells == tuple(QUILT_CELLS) else f"_{cells[0]}x{cells[1]}")
            + ("" if args.tile == 1.0 else f"_tile{args.tile:g}"))

    load = os.getloadavg()[0]
    rows = [r for r in (run_item(item, args.seeds, cells, args.tile) for item in args.items.split(","))
            if r is not None]
    lines = [f"# Quilts of {cells[0]} x {cells[1]} blocks over more seeds", "",
             f"`benchmarks/quilt_seeds.py --seeds {args.seeds} --cells {cells[0]}x{cells[1]} --tile {args.tile:g}`: "
             "the worst join's difference (over that of unrelated texels) of the quilt the product keeps of "
             f"its {QUILT_TRIES} seeds, against the one "
             f"kept of {args.seeds}; joins hide at {QUILT_MAX_DIFFERENCE} or less. Labels by eye: "
             f"`quilt_gate.md`. Load average at the start: {load:.2f}. At the end: {os.getloadavg()[0]:.2f}.", "",
             f"| item | tile | best of {QUILT_TRIES} | best of {args.seeds} | every seed | s |",
             "|---|---|---:|---:|---|---:|"]
    for r in rows:
        lines.append(f"| {r['item']} | {r['tile'][0]}x{r['tile'][1]} | {r['product']:.3f} | {r['all']:.3f} | "
                     f"{' '.join(f'{d:.2f}' for d in r['seeds'])} | {r['seconds']} |")
    hide = lambda key: [r["item"] for r in rows if r[key] <= QUILT_MAX_DIFFERENCE]  # noqa: E731
    lines += ["", f"Joins hide, best of {QUILT_TRIES}: {', '.join(hide('product')) or 'none'}. "
              f"Best of {args.seeds}: {', '.join(hide('all')) or 'none'}."]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / f"{name}.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
