#!/usr/bin/env python3
"""How well each decision rule tells seamless tiles from seamed ones, on a labelled corpus.

    python3 benchmarks/verdict.py                # the corpus at 256 and 512 px, every rule but Q
    python3 benchmarks/verdict.py --q            # also Q, with a draft discriminator trained per source
    python3 benchmarks/verdict.py --sides 256    # a quicker run

The corpus (``benchmarks/verdict_corpus.py``) is built from the bundled MaterialX maps and synthetic
noise; every item is seamless or seamed by construction. The *held-back* part (other textures, other
noise) was never looked at while the verdict's settings were chosen; it is reported on its own.

Rules: ``verdict`` (the product's, against the item's source), ``verdict-self`` (the same, judged
against the tile itself, as ``seamless-usd check`` does on a lone texture), ``seam-ratios`` (the worst
border or centre seam ratio above 1.15), ``periodic-plus-smooth`` (score above 0.075, the scan's old
already-tileable rule) and ``Q`` (the discriminator's quality function). For each: seamless called
seamless, seamed called seamed, and the ROC area of its continuous figure. Writes
``results/verdict.md`` and ``results/verdict.json``.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import verdict_corpus as corpus  # noqa: E402
from results_io import write_results  # noqa: E402
from seamless_usd.metrics import centre_seam_ratios, ps_score, seam_ratios  # noqa: E402
from seamless_usd.verdict import judge  # noqa: E402

RESULTS = HERE / "results"
PS_MAX = 0.075
SEAM_MAX = 1.15


def _seam_ratio(item) -> float:
    worst = 0.0
    for t, n in zip(item.tile, item.normals):
        r = {**seam_ratios(t, n), **centre_seam_ratios(t, n)}
        worst = max(worst, *(r[k] for k in ("seam_ratio_x", "seam_ratio_y", "centre_seam_x", "centre_seam_y")))
    return worst


def _figures(item, with_q: bool, models: dict) -> dict:
    out: dict = {}
    t0 = time.perf_counter()
    names = [f"m{i}" for i in range(len(item.tile))]
    v = judge(item.tile, item.source, item.normals, names, fidelity=False)
    out["verdict"] = (not v.seamless, v.strongest - v.margin)
    out["verdict_seconds"] = time.perf_counter() - t0
    s = judge(item.tile, None, item.normals, names, fidelity=False)
    out["verdict-self"] = (not s.seamless, s.strongest - s.margin)
    sr = _seam_ratio(item)
    out["seam-ratios"] = (sr > SEAM_MAX, sr)
    ps = max(ps_score(t, n) for t, n in zip(item.tile, item.normals))
    out["periodic-plus-smooth"] = (ps > PS_MAX, ps)
    if with_q:
        q = _q(item, models)
        out["Q"] = (not q.passed, -q.margin)
    return out


def _q(item, models: dict):
    """Q of the tile under a draft discriminator trained on the item's source (one model per source)."""
    from seamless_usd.synthesis import MapInput, get_preset, train
    from seamless_usd.synthesis.gan.sample import judge as q_judge

    key = (item.family, item.source[0].shape)
    if key not in models:
        maps = [MapInput(f"m{i}", np.ascontiguousarray(s, np.float32), n)
                for i, (s, n) in enumerate(zip(item.source, item.normals))]
        models[key] = train(maps, get_preset("draft"), seed=0)
    return q_judge(models[key], {f"m{i}": t for i, t in enumerate(item.tile)})


def roc_area(seamed: list[float], seamless: list[float]) -> float:
    """Probability that a seamed item's figure is above a seamless one's (ties count half)."""
    if not seamed or not seamless:
        return float("nan")
    a, b = np.asarray(seamed)[:, None], np.asarray(seamless)[None, :]
    return float(np.mean((a > b) + 0.5 * (a == b)))


#: Items whose joins were blended (a gradient-domain band, a crossfade): the class of tiles whose texels moved, where
#: the verdict cannot find copies, reported on its own as well.
BLENDS = ("blended", "lattice-blended", "blocky-blended", "crossfade")


def _part(rows: list[dict], split: str) -> list[dict]:
    if split == "held-back blends":
        return [r for r in rows if r["split"] == "held-back" and r["kind"] in BLENDS]
    return [r for r in rows if split == "all" or r["split"] == split]


def summarise(rows: list[dict], rules: list[str]) -> dict:
    out: dict = {}
    for split in ("tuning", "held-back", "held-back blends", "all"):
        part = _part(rows, split)
        out[split] = {}
        for rule in rules:
            seamless = [r for r in part if r["seamless"]]
            seamed = [r for r in part if not r["seamless"]]
            out[split][rule] = {
                "seamless_called_seamless": sum(not r[rule][0] for r in seamless) / max(1, len(seamless)),
                "seamed_called_seamed": sum(r[rule][0] for r in seamed) / max(1, len(seamed)),
                "roc_area": roc_area([r[rule][1] for r in seamed], [r[rule][1] for r in seamless]),
                "n_seamless": len(seamless), "n_seamed": len(seamed)}
    return out


def verdict_md(summary: dict, rows: list[dict], rules: list[str], note: str) -> str:
    lines = ["# Verdict benchmark", "", note, "",
             "| part | rule | seamless called seamless | seamed called seamed | ROC area |", "|---|---|---:|---:|---:|"]
    for split, rs in summary.items():
        for rule in rules:
            s = rs[rule]
            lines.append(f"| {split} ({s['n_seamless']} + {s['n_seamed']}) | {rule} | "
                         f"{100 * s['seamless_called_seamless']:.0f} % | {100 * s['seamed_called_seamed']:.0f} % | "
                         f"{s['roc_area']:.2f} |")
    lines += ["", "## Items", "", "| item | part | label | " + " | ".join(rules) + " |",
              "|---|---|---|" + "---|" * len(rules)]
    for r in rows:
        cells = [("**seamed**" if r[k][0] else "seamless") + f" {r[k][1]:.2f}" for k in rules]
        lines.append(f"| {r['name']} | {r['split']} | {'seamless' if r['seamless'] else 'seamed'} | "
                     + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sides", default="256,512", help="texel scales of the corpus (px per period)")
    ap.add_argument("--q", action="store_true", help="also Q (trains a draft discriminator per source)")
    ap.add_argument("--no-products", action="store_true", help="leave out the product's lattice cuts and refinements")
    ap.add_argument("--out", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    import torch
    torch.set_num_threads(1)
    sides = tuple(int(s) for s in args.sides.split(","))
    rules = ["verdict", "verdict-self", "seam-ratios", "periodic-plus-smooth"] + (["Q"] if args.q else [])
    rows, models = [], {}
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    for item in corpus.items(sides=sides, products=not args.no_products):
        figures = _figures(item, args.q, models)
        row = {"name": item.name, "kind": item.kind, "family": item.family, "split": item.split,
               "seamless": item.seamless, "size": list(item.tile[0].shape[:2]), **figures}
        rows.append(row)
        print(f"{item.name:34s} {'seamless' if item.seamless else 'seamed  '} "
              + " ".join(f"{k}={'S' if row[k][0] else '-'}{row[k][1]:.2f}" for k in rules), flush=True)
    summary = summarise(rows, rules)
    seconds = [r["verdict_seconds"] for r in rows]
    note = (f"{len(rows)} items at sides {sides}; {time.perf_counter() - t0:.0f} s in all, load average "
            f"{load:.2f} at the start; the verdict took {np.median(seconds):.2f} s per item (median, "
            f"{max(seconds):.2f} s at most).")
    write_results(args.out, "verdict", verdict_md(summary, rows, rules, note), {"summary": summary, "items": rows})
    print(note)
    for split, rs in summary.items():
        for rule, s in rs.items():
            print(f"{split:10s} {rule:22s} seamless {100 * s['seamless_called_seamless']:5.1f} %  "
                  f"seamed {100 * s['seamed_called_seamed']:5.1f} %  ROC {s['roc_area']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
