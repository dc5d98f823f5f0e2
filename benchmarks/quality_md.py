"""``quality.md``: the quality benchmark's figures as Markdown tables, with the targets checked."""
from __future__ import annotations

import numpy as np

from seamless_usd import metrics as M

__all__ = ["SEAMLESSGAN", "TARGETS", "fmt", "to_markdown"]

SEAMLESSGAN = "seamlessgan"

#: The targets every map is held to: (figure, comparison, threshold). Fidelity against the source
#: (feature scale, patch distance) and seams across the border and the centre lines, from
#: ``seamless_usd.metrics.TARGETS``; the product passes a stack on the fidelity ones.
TARGETS: tuple[tuple[str, str, float], ...] = tuple(
    (key, op, bound)
    for key, (low, high) in M.TARGETS.items()
    for op, bound in ((">=", low), ("<=", high))
    if bound is not None
)


def _figure(row: dict, key: str):
    if key == "detail_ratio_min":
        pair = (row.get("detail_ratio"), row.get("detail_ratio_centre"))
        return None if None in pair else min(pair)
    return row.get(key)


def _int(v):
    return None if v is None else int(v)


def _meets(v, op: str, threshold: float) -> bool:
    return v is not None and (v <= threshold if op == "<=" else v >= threshold)


def fmt(v, digits=2) -> str:
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    return f"{v:.{digits}f}" if isinstance(v, float) else str(v)


def to_markdown(result: dict) -> str:
    """The benchmark's figures as Markdown: one table per stack and a target summary per method."""
    s = result["settings"]
    lines = ["# Quality benchmark", ""]
    if not result.get("complete", True):
        lines += ["**Partial: the run is still going or was stopped; only the stacks below are done.**", ""]
    if s.get("command"):
        lines += [f"Command: `{s['command']}`", ""]
    lines += [
        f"Methods: {', '.join(s['methods'])}"
        + (f"; SeamlessGAN preset `{s['preset']}`" if s.get("preset") else "")
        + (
            " (k={k}, ngf={ngf}, res blocks={n_res_blocks}, {iterations} iterations, tiling {tiling})".format(
                **s["preset_config"]
            )
            if s.get("preset_config")
            else ""
        )
        + f"; seed {s['seed']}" + (f"; inputs downscaled to <= {s['max_size']} px" if s.get("max_size") else ""),
        "",
        "Columns: seam ratio per axis (first / second differences; about 1 when seamless), "
        "periodic-plus-smooth score (0 when periodic), detail ratio in the border seam bands and in "
        f"the centre bands (band half-width {s['band_fraction']:.0%} of the size, high-pass sigma "
        f"{s['highpass_sigma']} px; < 1 when blurred), SSIM of the tile repeated to the source's size, "
        "the relative Gram distance (0 = same statistics), and the feature-scale ratio and patch distance "
        "against the source. See `seamless_usd/metrics/`.",
        "",
    ]
    lines += [
        "Reading the figures: a seam ratio compares one row (or column) pair with the mean of all, so "
        "for coarse or strongly periodic patterns (bricks, weave) it ranges about 0.6-1.6 on seamless "
        "tiles (see the crossfade rows); the periodic-plus-smooth score of a seamless but fine-grained "
        "(noise-like) tile is not 0 but about 0.03-0.15, because Moisan's boundary term also counts "
        "ordinary neighbour differences. Compare methods on the same map.",
        "",
    ]
    for note in result.get("notes", []):
        lines += [f"- {note}"]
    lines += [""]
    header = (
        "| map | method | tile | seam x | seam y | seam² x | seam² y | ctr seam x | ctr seam y | p+s | detail "
        "| detail ctr | SSIM | Gram | scale | patch | s |"
    )
    sep = "|---|---|---|" + "---:|" * (len(M.METRIC_KEYS) + 1)
    rows = result["results"]
    for stack in s["stacks"]:
        lines += [f"## {stack}", "", s["stacks"][stack], "", header, sep]
        for r in (r for r in rows if r["stack"] == stack):
            tile = "x".join(str(n) for n in r["tile_size"])
            extra = ""
            if r.get("passed") is not None:  # the product's verdict on the row's tile
                extra = " (passed)" if r["passed"] else " (not passed)"
            if r.get("q_passed") is False:  # the SeamlessGAN rows: Q of the row's layout
                extra += " (Q failed)"
            if r["method"] == "seamless-usd" and r.get("layout") == "lattice":
                extra += " (lattice cut)"
            elif r["method"] == "seamless-usd" and r.get("iterations") == 0:  # the cut passed: nothing trained
                extra += f" ({r.get('layout')} cut, no GAN trained)"
            elif r.get("layout_used") is False and r["method"] != "lattice-cut":
                extra += " (GAN layout rejected: random start)"
            lines.append(
                f"| {r['map']}{' (normal)' if r['is_normal'] else ''} | {r['method']}{extra} | {tile} | "
                + " | ".join(
                    fmt(r.get(k), 3 if k in ("ps_score", "ssim", "gram_distance") else 2)
                    for k in M.METRIC_KEYS
                )
                + f" | {fmt(r['seconds'], 1)} |"
            )
        lines += [""]
        inner = [r for r in rows if r["stack"] == stack and r.get("structure") is not None]
        if inner:
            lines += ["Inside the tile: bad joins between copied blocks (count and total length in texels, "
                      "`seamless_usd.verdict.joins`; – when the tile is not made of source texels), the field's "
                      "coherence, and the structure figure (line ends and line lengths against the source, divided "
                      "by the source's own half-vs-half spread; target <= 1.5, `seamless_usd.metrics.structure`):",
                      "", "| map | method | bad joins | join length | coherence | structure |", "|---|---|---:|---:|---:|---:|"]
            lines += [f"| {r['map']} | {r['method']} | {fmt(_int(r.get('bad_joins')))} | {fmt(_int(r.get('join_length')))} | "
                      f"{fmt(r.get('coherence'), 3)} | {fmt(r.get('structure'))} |" for r in inner]
            crops = [r for r in inner if r.get("crop_1x")]
            if crops:
                lines += ["", "Texels as they are (the tile repeated across its wrap corner | the source), 1x and 3x: "
                          + ", ".join(f"[{r['map']} 1x]({r['crop_1x']}) / [3x]({r['crop_3x']})" for r in crops)]
            peak = max((r.get("peak_rss_gib") or 0 for r in inner), default=0)
            if peak:
                lines += ["", f"Peak memory of the process so far: {peak:.2f} GiB."]
            lines += [""]
        ratios = {r["method"]: r["lattice_ratio"] for r in rows
                  if r["stack"] == stack and r.get("lattice_ratio") is not None}
        if ratios:
            lines += ["Lattice ratio (the tile's autocorrelation at the source's lattice periods over the source's; "
                      "about 1 when the repeat is kept, target >= 0.9): "
                      + ", ".join(f"{m} {fmt(v, 2)}" for m, v in ratios.items()), ""]
    lines += ["## Medians per method", "", "| method | maps | " + " | ".join(M.METRIC_KEYS) + " |"]
    lines += ["|---|---:|" + "---:|" * len(M.METRIC_KEYS)]
    for method in s["methods"]:
        mine = [r for r in rows if r["method"] == method]
        cells = []
        for k in M.METRIC_KEYS:
            vals = [r[k] for r in mine if r.get(k) is not None]
            cells.append(fmt(float(np.median(vals)), 3) if vals else "–")
        lines.append(f"| {method} | {len(mine)} | " + " | ".join(cells) + " |")
    lines += [""]
    lines += [
        "## Targets",
        "",
        "Maps meeting each target (`seamless_usd.metrics.TARGETS`: feature scale and patch distance "
        "against the source, seams across the border and the centre lines):",
        "",
    ]
    lines += ["| method | " + " | ".join(f"{k} {op} {v}" for k, op, v in TARGETS) + " | all |"]
    lines += ["|---|" + "---:|" * (len(TARGETS) + 1)]
    for method in s["methods"]:
        mine = [r for r in rows if r["method"] == method]
        cells = [f"{sum(_meets(_figure(r, k), op, v) for r in mine)}/{len(mine)}" for k, op, v in TARGETS]
        every = sum(all(_meets(_figure(r, k), op, v) for k, op, v in TARGETS) for r in mine)
        lines.append(f"| {method} | " + " | ".join(cells) + f" | {every}/{len(mine)} |")
    lines += [""]
    return "\n".join(lines)
