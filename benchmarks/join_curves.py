#!/usr/bin/env python3
"""Whether the verdict could follow a meandering cut: its copy runs read along the join, measured.

The verdict judges a tile of copies by runs of ``COPY_RUN`` texels along straight lines
(``seamless_usd.verdict.copies.copy_seams``): the mean continuation error over the run, texels copied
together reading 0. A minimum-error cut that meanders (window cuts, quilts, a lattice cut's band) crosses
any straight line for a few texels only, so a break along it is averaged with texels that are not joins
and the verdict passes it (``results/window_gate.md``, ``quilt_gate.md``, the lit brick of ``verdict.md``).

This script reads the same continuation errors along the cut instead: on each line, every texel takes the
largest error within ``w`` texels across it (a cut that moves at most ``w`` texels sideways per ``run``
stays inside), and the runs' mean is taken as before. For every labelled tile of copies it prints that
figure for ``w`` in 0 (the verdict's own), 2 and 4, and the table: per split, how well it tells the labels
apart (ROC area), the largest figure of a seamless tile, and the seamed tiles at or under it.

Items: the window cuts of ``window_gate.LABELS`` (tuning / held back as labelled there), the labelled quilts
of ``quilt_gate.LABELS`` (held back: labelled after the quilt gate), and the verdict corpus's tiles of copies
(``verdict_corpus.items``: lattice cuts, blended or not, the lit brick, refinements and block mosaics, with
the corpus's split).

    .venv/bin/python benchmarks/join_curves.py            # writes results/join_curves.md and .json
    .venv/bin/python benchmarks/join_curves.py --sets window --out /tmp/curves
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
WIDTHS = (0, 2, 4)
#: The corpus's kinds that are not tiles of copies (judged by the classifier, not by these runs).
NOT_COPIES = ("rolled", "noise", "naive", "half-roll", "crossfade", "splice")


def curve_figures(tiles: list[np.ndarray], sources: list[np.ndarray], normals: list[bool], run: int
                  ) -> dict[int, float] | None:
    """The strongest run for each width of :data:`WIDTHS` (the maps together), or None when the verdict
    would not judge the tile as copies."""
    from scipy.ndimage import maximum_filter1d

    from seamless_usd.verdict.copies import COPY_SHARE, EXACT_SHARE, INFER, continuation, copy_origins, step_unit
    from seamless_usd.verdict.features import moving_mean
    from seamless_usd.verdict.prepare import joined, prepare_maps

    tj, _ = joined(prepare_maps(tiles, normals))
    sj, _ = joined(prepare_maps(sources, normals))
    origin, share = copy_origins(tj, sj, INFER)
    if share < EXACT_SHARE or (origin[..., 0] >= 0).mean() < COPY_SHARE:
        return None
    out = {w: 0.0 for w in WIDTHS}
    for axis in (1, 0):
        err = continuation(tj, sj, origin, axis, step_unit(sj, axis))
        along = err if axis == 1 else err.T  # rows run along the line
        for w in WIDTHS:
            near = along if w == 0 else maximum_filter1d(along, 2 * w + 1, axis=1, mode="wrap")
            out[w] = max(out[w], float(moving_mean(near, min(run, near.shape[0]), periodic=True).max()))
    return out


def _items(sets: list[str]):
    """(name, split, seamless, tiles, sources, normals) of every labelled tile of copies."""
    if "window" in sets:
        import window_gate

        from seamless_usd.synthesis.lattice.cut import lattice_cut
        from seamless_usd.synthesis.lattice.window import window_tile_size

        for name, (split, seamless, _) in window_gate.LABELS.items():
            stack = window_gate.stack_for(name)
            maps, normals = [v[0] for v in stack.values()], [v[1] for v in stack.values()]
            sizes = window_tile_size(maps)
            if sizes is not None:
                field, _ = lattice_cut(maps, sizes[0], sizes[1])
                yield f"window {name}", split, seamless, [m[field[..., 0], field[..., 1]] for m in maps], maps, normals
    if "quilt" in sets:
        import quilt_gate

        from seamless_usd.synthesis.lattice.quilt import best_quilt
        from seamless_usd.synthesis.tile import QUILT_CELLS, QUILT_TRIES

        for item, (seamless, _) in quilt_gate.LABELS.items():
            name, cut = item.split("/")
            stack = quilt_gate.stack_for(name)
            maps, normals = [v[0] for v in stack.values()], [v[1] for v in stack.values()]
            field, _ = best_quilt(maps, maps[0].shape[:2], QUILT_CELLS, QUILT_TRIES, lines=cut == "lines")
            yield f"quilt {item}", "held-back", seamless, [m[field[..., 0], field[..., 1]] for m in maps], maps, normals
    if "corpus" in sets:
        import verdict_corpus

        for it in verdict_corpus.items():
            if it.kind not in NOT_COPIES:
                yield f"{it.kind} {it.name}", it.split, it.seamless, it.tile, it.source, it.normals


def roc_area(seamed: list[float], seamless: list[float]) -> float:
    a, b = np.asarray(seamed)[:, None], np.asarray(seamless)[None, :]
    return float((a > b).mean() + 0.5 * (a == b).mean())


def main(argv: list[str] | None = None) -> int:
    from seamless_usd.verdict import judge
    from seamless_usd.verdict.copies import COPY_THRESHOLD
    from seamless_usd.verdict.judge import COPY_RUN

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sets", default="window,quilt,corpus")
    ap.add_argument("--out", type=Path, default=RESULTS)
    ap.add_argument("--again", action="store_true", help="write the tables again from the .json of an earlier run")
    args = ap.parse_args(argv)
    load = os.getloadavg()[0]
    rows = []
    if args.again:
        earlier = json.loads((args.out / "join_curves.json").read_text())
        rows, (load, _) = earlier["rows"], earlier["load"]
    for name, split, seamless, tiles, sources, normals in ([] if args.again else _items(args.sets.split(","))):
        figures = curve_figures(tiles, sources, normals, COPY_RUN)
        if figures is None:
            continue
        passed = judge(tiles, sources, normals, [f"map{k}" for k in range(len(tiles))], fidelity=False).seamless
        row = {"item": name, "split": split, "seamless": seamless, "verdict_passed": passed,
               **{f"w{w}": round(v, 3) for w, v in figures.items()}}
        rows.append(row)
        print(json.dumps(row), flush=True)
    end = earlier["load"][1] if args.again else os.getloadavg()[0]
    lines = ["# Copy runs read along the cut", "",
             "`benchmarks/join_curves.py`: the verdict's copy runs (mean continuation error over "
             f"{COPY_RUN} texels; a seam above {COPY_THRESHOLD}) with each texel taking the largest error within "
             "w texels across its line, so a run follows a cut that meanders. w = 0 is the verdict's own figure. "
             "Per split: ROC area (seamed against seamless), the largest figure of a seamless tile, and how many "
             "seamed tiles read at or under it (of all seamed; of those the verdict passes). "
             f"Load average at the start: {load:.2f}. At the end: {end:.2f}.", "",
             "| split | w | tiles (seamless + seamed) | ROC area | largest seamless | seamed at or under it | "
             "of the verdict's false passes |", "|---|---:|---|---:|---:|---|---|"]
    for split in ("tuning", "held-back"):
        part = [r for r in rows if r["split"] == split]
        good, bad = [r for r in part if r["seamless"]], [r for r in part if not r["seamless"]]
        if not good or not bad:
            continue
        for w in WIDTHS:
            top = max(r[f"w{w}"] for r in good)
            missed = [r for r in bad if r[f"w{w}"] <= top]
            false_passes = [r for r in bad if r["verdict_passed"]]
            lines.append(f"| {split} | {w} | {len(good)} + {len(bad)} | "
                         f"{roc_area([r[f'w{w}'] for r in bad], [r[f'w{w}'] for r in good]):.3f} | {top:.2f} | "
                         f"{len(missed)}/{len(bad)} | {sum(r['verdict_passed'] for r in missed)}/{len(false_passes)} |")
    # as a rule for cut tiles (lattice, window, quilt: where a cut meanders), its threshold fixed on the tuning
    # split's cuts (midway between their largest seamless and smallest seamed figure), held-back cuts judged by it
    cuts = [r for r in rows if r["item"].split()[0] in ("window", "quilt", "lattice", "lattice-blended", "lattice-lit")]
    lines += ["", "Cut tiles only, with a rule: a seam where the figure exceeds a threshold fixed on the tuning split's "
              "cuts (midway between their largest seamless and smallest seamed figure).", "",
              "| w | threshold (tuning) | held-back cuts (seamless + seamed) | seamless flagged (new false seams) | "
              "seamed flagged | of the verdict's false passes |", "|---:|---:|---|---|---|---|"]
    for w in WIDTHS[1:]:
        tune = [r for r in cuts if r["split"] == "tuning"]
        held = [r for r in cuts if r["split"] == "held-back"]
        if not tune or not held:
            continue
        top = max([r[f"w{w}"] for r in tune if r["seamless"]] or [0.0])
        low = min([r[f"w{w}"] for r in tune if not r["seamless"]] or [top])
        t = (top + low) / 2
        good, bad = [r for r in held if r["seamless"]], [r for r in held if not r["seamless"]]
        new_seams = [r for r in good if r[f"w{w}"] > t and r["verdict_passed"]]
        caught = [r for r in bad if r[f"w{w}"] > t]
        lines.append(f"| {w} | {t:.2f} | {len(good)} + {len(bad)} | {len(new_seams)} "
                     f"({', '.join(r['item'] for r in new_seams) or 'none'}) | {len(caught)}/{len(bad)} | "
                     f"{sum(r['verdict_passed'] for r in caught)}/{sum(r['verdict_passed'] for r in bad)} |")
    lines += ["", "| item | split | by eye | verdict | " + " | ".join(f"w = {w}" for w in WIDTHS) + " |",
              "|---|---|---|---|" + "---:|" * len(WIDTHS)]
    for r in sorted(rows, key=lambda r: (r["seamless"], r[f"w{WIDTHS[-1]}"])):
        lines.append(f"| {r['item']} | {r['split']} | {'seamless' if r['seamless'] else 'seamed'} | "
                     f"{'passed' if r['verdict_passed'] else 'seams'} | " + " | ".join(f"{r[f'w{w}']:.2f}" for w in WIDTHS) + " |")
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "join_curves.md").write_text("\n".join(lines) + "\n")
    (args.out / "join_curves.json").write_text(json.dumps({"load": [load, end], "rows": rows}, indent=1))
    print(f"wrote @{args.out / 'join_curves.md'}@")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
