"""How well each rule tells seamless textures from seamed ones when a texture is judged on its own.

This is what ``seamless-usd check`` does with a picture, and what the scan's triage does before deciding a
stack is ``already-tileable``. The corpus is ``benchmarks/texture_corpus.py`` (real textures, rolled, halved
and turned when they tile; windows, half-rolls, splices, crossfades and lit versions when they do not); its
held-back part was never looked at while a rule's settings were chosen.

    .venv/bin/python benchmarks/texture_verdict.py                  # 128, 256 and 512 px, every rule
    .venv/bin/python benchmarks/texture_verdict.py --sizes 256      # one size

Rules:
    ``verdict``             the product's verdict on a texture judged against itself (what ``check`` and the scan's
                            triage both say of a picture): the classifier fitted on the texture's own lines, a seam
                            1.0 above its 4th-strongest line, and the line breaks' seams (``seamless_usd/verdict/
                            breaks.py``: every line's straddling differences at every lag against all parallel
                            lines);
    ``line-breaks``         the line breaks alone;
    ``continuation-ratio``  the continuation ratio alone (``seamless_usd/verdict/across.py``: the line across
                            which the rows predict each other least, against the next such line);
    ``periodic-plus-smooth``, ``seam-ratios``  the wrap gates the scan's triage used before it judged with the
                            verdict (above 0.075, above 2).

The classifier alone (the verdict before the line breaks joined it) and the old triage are in the history of
``results/texture_verdict.md``.

Writes ``results/texture_verdict.md`` and ``.json``: per part and class the share right, and every item's
figures.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from results_io import write_results  # noqa: E402
from texture_corpus import build  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"


def rules(item) -> dict[str, tuple]:
    """Each rule's call (True: seamed) and its figure on one item."""
    from seamless_usd.metrics import ps_score, seam_ratios
    from seamless_usd.verdict import judge
    from seamless_usd.verdict.across import unrelated_lines
    from seamless_usd.verdict.breaks import line_breaks, working
    from seamless_usd.verdict.prepare import prepare_maps

    pic, normal = item.picture, [item.is_normal]
    out = {}
    t0 = time.perf_counter()
    v = judge([pic], None, normal, [item.name], fidelity=False)
    out["verdict"] = (not v.seamless, round(v.strongest - v.margin, 3), round(time.perf_counter() - t0, 3))
    prepared = prepare_maps([pic], normal)
    work = working(prepared)
    found, strongest = line_breaks(prepared, [item.name], work=work)
    out["line-breaks"] = (bool(found), round(strongest - 1.0, 3))
    found, strongest = unrelated_lines(prepared, work=work)
    out["continuation-ratio"] = (bool(found), round(strongest - 1.0, 3))
    ps = float(ps_score(pic.astype(np.float64)))
    ratios = seam_ratios(pic.astype(np.float64))
    seam = float(max(ratios["seam_ratio_x"], ratios["seam_ratio_y"]))
    out["periodic-plus-smooth"] = (ps > 0.075, round(ps, 4))
    out["seam-ratios"] = (seam > 2.0, round(seam, 3))
    return out


def table(rows: list[dict]) -> list[dict]:
    """Share right per part, class and rule."""
    out = []
    names = [k for k in rows[0]["rules"]]
    for part in ("tuning", "held-back", "all"):
        mine = [r for r in rows if part == "all" or r["split"] == part]
        for rule in names:
            good = [r for r in mine if r["seamless"]]
            bad = [r for r in mine if not r["seamless"]]
            out.append({"part": part, "rule": rule,
                        "seamless_right": sum(not r["rules"][rule][0] for r in good) / max(1, len(good)),
                        "seamed_right": sum(r["rules"][rule][0] for r in bad) / max(1, len(bad)),
                        "seamless": len(good), "seamed": len(bad)})
    return out


def share_table(shares: list[dict], rules: bool = True) -> list[str]:
    """The shares of :func:`table` as Markdown lines, with or without the rule column."""
    rule = "rule | " if rules else ""
    lines = [f"| part | {rule}seamless called seamless | seamed called seamed |",
             f"|---|{'---|' if rules else ''}---:|---:|"]
    for s in shares:
        named = f"{s['rule']} | " if rules else ""
        lines.append(f"| {s['part']} ({s['seamless']} + {s['seamed']}) | {named}{100 * s['seamless_right']:.0f} % "
                     f"| {100 * s['seamed_right']:.0f} % |")
    return lines


def heading(title: str, run: str, count: int, seconds: float, load: float) -> list[str]:
    """A results page's title and what was run, how long it took and the load it started at."""
    return [f"# {title}", "", f"{run}: {count} pictures; {seconds:.0f} s in all, load average {load:.2f} at the start.",
            ""]


def markdown(rows: list[dict], shares: list[dict], seconds: float, load: float) -> str:
    lines = [*heading("Textures judged on their own", "`benchmarks/texture_verdict.py` on `benchmarks/texture_corpus.py`",
                      len(rows), seconds, load), *share_table(shares)]
    lines += ["", "Misses of the verdict, held back:", ""]
    for r in rows:
        call = r["rules"]["verdict"][0]
        if r["split"] == "held-back" and call == r["seamless"]:
            lines.append(f"- {r['name']} ({'seamless' if r['seamless'] else 'seamed'}): verdict {r['rules']['verdict'][1]}")
    times = sorted(r["rules"]["verdict"][2] for r in rows)
    lines += ["", f"The verdict took {np.median(times):.2f} s per picture (median), {times[-1]:.2f} s at most."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="128,256,512")
    ap.add_argument("--out", type=Path, default=RESULTS)
    a = ap.parse_args(argv)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    rows = []
    for item in build(tuple(int(s) for s in a.sizes.split(","))):
        r = rules(item)
        rows.append({"name": item.name, "family": item.family, "kind": item.kind, "split": item.split,
                     "seamless": item.seamless, "size": list(item.picture.shape[:2]), "rules": r})
        print(f"{item.name:32s} {'seamless' if item.seamless else 'seamed  '} "
              + " ".join(f"{k}={'S' if v[0] else '-'}{v[1]}" for k, v in r.items()), flush=True)
    shares = table(rows)
    seconds = time.perf_counter() - t0
    md, _ = write_results(a.out, "texture_verdict", markdown(rows, shares, seconds, load),
                          {"items": rows, "shares": shares, "seconds": round(seconds, 1), "load": load})
    for s in shares:
        print(f"{s['part']:10s} {s['rule']:22s} seamless {100 * s['seamless_right']:5.1f} %  "
              f"seamed {100 * s['seamed_right']:5.1f} %")
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
