#!/usr/bin/env python3
"""Compare runs of ``quality.py``: medians and counts inside the targets, per method, one row per run.

Each ``--run LABEL=PATH`` names a ``quality.json``. For every synthesis method the runs share, the
table gives the training seconds summed over the stacks, then per target figure the median over the
maps and how many maps are inside, then how many maps meet both fidelity targets and all targets.
Runs with several seeds also list, per stack, the seed kept and each seed's score::

    .venv/bin/python benchmarks/compare.py --run "1 seed=benchmarks/results/quality.json" \\
        --run "2 seeds=runs/seeds/quality.json" --title "Seeds side by side" --out /tmp/seeds.md
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from seamless_usd.metrics import FIDELITY_KEYS, TARGETS, outside_target  # noqa: E402

__all__ = ["summarise", "to_markdown", "main"]


def _inside(key: str, value) -> bool:
    return value is not None and not outside_target(key, value)


def summarise(rows: list[dict], method: str) -> dict:
    """Medians, counts inside each target, train seconds and seeds of one method's rows."""
    mine = [r for r in rows if r["method"] == method]
    out: dict = {"maps": len(mine), "figures": {}}
    for key in TARGETS:
        values = [r.get(key) for r in mine if r.get(key) is not None]
        out["figures"][key] = (float(np.median(values)) if values else None,
                               sum(_inside(key, r.get(key)) for r in mine))
    out["fidelity_inside"] = sum(all(_inside(k, r.get(k)) for k in FIDELITY_KEYS) for r in mine)
    out["all_inside"] = sum(all(_inside(k, r.get(k)) for k in TARGETS) for r in mine)
    per_stack = {r["stack"]: r for r in mine}
    out["train_seconds"] = sum(float(r.get("train_seconds") or 0.0) for r in per_stack.values())
    out["seeds"] = {s: r["seeds"] for s, r in per_stack.items() if r.get("seeds")}
    return out


def to_markdown(runs: list[tuple[str, dict]], title: str, note: str = "") -> str:
    methods = [m for m in dict.fromkeys(r["method"] for _, d in runs for r in d["results"])
               if all(any(r["method"] == m for r in d["results"]) for _, d in runs)]
    methods = [m for m in methods if m.startswith("seamlessgan")] or methods
    lines = [f"# {title}", "", "Written by `benchmarks/compare.py` from these runs of `benchmarks/quality.py`:", ""]
    for label, d in runs:
        lines.append(f"- **{label}**: `{d['settings'].get('command')}`")
    if note:
        lines += ["", note]
    keys = list(TARGETS)
    for method in methods:
        lines += ["", f"## {method}", "",
                  "| run | train s (all stacks) | " + " | ".join(keys) + " | scale and patch inside | all inside |",
                  "|---|---:|" + "---:|" * (len(keys) + 2)]
        for label, d in runs:
            s = summarise(d["results"], method)
            cells = [f"{med:.2f} ({n}/{s['maps']})" if med is not None else "—" for med, n in
                     (s["figures"][k] for k in keys)]
            lines.append(f"| {label} | {s['train_seconds']:.0f} | " + " | ".join(cells)
                         + f" | {s['fidelity_inside']}/{s['maps']} | {s['all_inside']}/{s['maps']} |")
    for label, d in runs:
        seeds = summarise(d["results"], methods[0])["seeds"]
        if not seeds:
            continue
        lines += ["", f"## Seeds of run \"{label}\": score = worst figure / its target on the working-resolution "
                      "GAN tile (<= 1: every map inside)", "", "| stack | " + " | ".join(
                          f"seed {s['seed']}" for s in next(iter(seeds.values()))) + " | kept |",
                  "|---|" + "---:|" * (len(next(iter(seeds.values()))) + 1)]
        for stack, entries in seeds.items():
            kept = next(s["seed"] for s in entries if s["chosen"])
            lines.append(f"| {stack} | " + " | ".join(
                f"{s['score']:.2f}" + ("" if s["q_passed"] else " (Q failed)") for s in entries) + f" | {kept} |")
    return "\n".join(lines) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--run", action="append", required=True, metavar="LABEL=PATH", help="a quality.json (repeatable)")
    p.add_argument("--title", default="Quality runs compared")
    p.add_argument("--note", default="", help="a paragraph under the list of runs")
    p.add_argument("--out", type=Path, default=None, help="Markdown file to write (default: print)")
    a = p.parse_args(argv)
    runs = []
    for item in a.run:
        label, sep, path = item.partition("=")
        if not sep:
            p.error(f"--run takes LABEL=PATH, got {item!r}")
        runs.append((label, json.loads(Path(path).read_text())))
    text = to_markdown(runs, a.title, a.note)
    if a.out is None:
        print(text, end="")
    else:
        a.out.write_text(text)
        print(f"wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
