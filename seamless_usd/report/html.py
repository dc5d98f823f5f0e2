"""Self-contained HTML report: one page per run, pictures embedded as data URIs.

Per stack, the page shows what a lookdev TD needs to accept or reject a tile: its status and
tiling intent, the figures outside their targets, the material lit from a grazing angle (source
vs result), and per map the source and the tile repeated over the same UV area (same texel
scale), with the figures and their verdicts in words. A page-wide switch lays the repeat borders
and the tile's centre lines over every picture. Library runs get an index page
(:mod:`seamless_usd.report.index`).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from seamless_usd.fileio import atomic_write_text
from seamless_usd.report.facts import stack_facts
from seamless_usd.report.htmlparts import esc, figure, fmt, overlay_svg, page, seams_svg
from seamless_usd.report.target import clear_stale_pages
from seamless_usd.report.model import MapReport, Report, StackReport, StackStatus
from seamless_usd.report.repeat import ViewGeometry
from seamless_usd.report.stored import loaded
from seamless_usd.synthesis.advice import structure_advice
from seamless_usd.verdict.lines import Seam, figure_text
from seamless_usd.report.verdicts import LABELS, SEAM_KEYS, TORUS_NOTE, target_text, targets, verdict

__all__ = ["render_html", "write_html", "write_json",
           "stack_html", "map_verdicts", "failing_figures", "source_report"]


_LIT_HINT = (" Seams in the normal and roughness maps show here, where pictures of the maps hide them: "
             "compare the repeats at their borders and, for the tile, its centre lines.")


def _metric_order() -> tuple[str, ...]:
    try:
        from seamless_usd.metrics import METRIC_KEYS
    except ImportError:  # pragma: no cover - the metrics package is part of the project
        METRIC_KEYS = ()
    first = ("scale_ratio", "patch_distance", "seam_ratio_x", "seam_ratio_y", "centre_seam_x", "centre_seam_y")
    return first + tuple(k for k in METRIC_KEYS if k not in first)


def _map_name(m: MapReport) -> str:
    return ", ".join(m.roles) or Path(m.asset).name


def made_on_a_torus(stack: StackReport) -> bool:
    """Whether the stack's tile was refined or cut from the source (every line of it is a line of the
    texture), rather than sampled from SeamlessGAN alone (whose latent copies meet at its centre lines)."""
    return stack.resampled.get("gan", {}).get("layout") in ("gan", "random", "lattice", "window", "quilt", "mend")


def map_verdicts(m: MapReport, torus: bool = False, tolerances: dict | None = None
                 ) -> list[tuple[str, object, object, str, object]]:
    """Rows ``(key, source value, tile value, target text, Verdict)`` of a map's figures, in order
    (``torus``: see :func:`made_on_a_torus`; ``tolerances``: the map's own, from the stack's verdict)."""
    bounds = targets(tolerances)
    present = {k for k, v in [*m.metrics.items(), *m.source_metrics.items()] if v is not None}
    order = _metric_order()
    keys = [k for k in order if k in present] + sorted(present - set(order))
    return [(k, m.source_metrics.get(k), m.metrics.get(k), target_text(bounds.get(k)),
             verdict(k, m.metrics.get(k), bounds.get(k), torus)) for k in keys]


def failing_figures(stack: StackReport) -> list[str]:
    """``"map: figure"`` for the figures outside their targets: the stack's own list when it has one."""
    return [text for _, text in _failing(stack)]


def _failing(stack: StackReport) -> list[tuple[str | None, str]]:
    """``(figure key or None, "map: figure")`` for :func:`failing_figures`."""
    torus = made_on_a_torus(stack)
    if stack.failing or stack.verdict:  # the verdict's own list (empty where it passed)
        return [_readable_failing(f, torus) for f in stack.failing]
    out = []
    for m in stack.maps:
        out += [(k, f"{_map_name(m)}: {LABELS.get(k, k)} — {v.text}")
                for k, _, _, _, v in map_verdicts(m, torus, _map_tolerances(stack, m)) if v.ok is False]
    return out


def _readable_failing(item: str, torus: bool = False) -> tuple[str | None, str]:
    """``"albedo: scale_ratio 0.62"`` as ``("scale_ratio", "albedo: feature scale vs source — magnified or
    blurred (0.62)")``; an item that is not ``map: key value`` stays as it is, with no key."""
    where, sep, figure_text = item.rpartition(": ")
    parts = figure_text.split()
    if len(parts) != 2 or parts[0] not in LABELS:
        return None, item
    try:
        value = float(parts[1])
    except ValueError:
        return None, item
    return parts[0], f"{where}{sep}{LABELS[parts[0]]} — {verdict(parts[0], value, torus=torus).text}"


def _map_tolerances(stack: StackReport, m: MapReport) -> dict:
    return (stack.verdict.get("tolerances") or {}).get(m.asset, {})


def _metrics_table(m: MapReport, torus: bool = False, tolerances: dict | None = None) -> str:
    main, minor = [], []
    for key, source, new, target, v in map_verdicts(m, torus, tolerances):
        cls = "" if v.ok is None else ("ok" if v.ok else "bad")
        row = (f'<th title="{esc(key)}">{esc(LABELS.get(key, key))}</th><td>{esc(fmt(source))}</td>'
               f'<td>{esc(fmt(new))}</td><td>{esc(target)}</td><td class="v {cls}">{esc(v.text)}</td>')
        (main if v.target else minor).append(row)
    if not main and not minor:
        return ""
    rows = "".join(f"<tr>{r}</tr>" for r in main)
    lines = torus and any(v.ok is False and k in SEAM_KEYS for k, _, _, _, v in map_verdicts(m, torus, tolerances))
    note = f'<p class="note muted">{esc(TORUS_NOTE)}</p>' if lines else ""
    if minor:
        rows += '<tr class="sep"><td colspan="5">other figures (no target)</td></tr>'
        rows += "".join(f'<tr class="minor">{r}</tr>' for r in minor)
    return ('<div class="figs"><table class="metrics"><tr><th>figure</th><th>source as is</th><th>new tile</th>'
            f'<th>tolerance</th><th>reads</th></tr>{rows}</table>{note}</div>')


def _geometry(stack: StackReport) -> ViewGeometry | None:
    view = stack.previews.view
    if not view:
        return None
    return ViewGeometry(window=tuple(view["window"]), tile_extent=tuple(view["tile_extent"]), size=tuple(view["size"]))


def _repeats(r: tuple[float, float]) -> str:
    return " x ".join(f"{v:g}" if float(v).is_integer() else f"{v:.2f}" for v in r)


#: Seams listed in words and drawn per map (strongest first); the JSON report has them all.
SEAMS_SHOWN = 6


def seam_segments(g: ViewGeometry, seams: list[dict], tile_size: tuple[int, int]) -> list[tuple]:
    """Each seam (tile texels) drawn in every repeat of the tile in the picture, as ``(x1, y1, x2, y2, label)``."""
    h, w = tile_size
    (nx, ny), (W, H) = g.tile_repeats, g.size
    px, py = W / nx, H / ny  # one repeat, in picture px
    out = []
    for s in seams:
        label = f"{figure_text(s['figure'])}: {s['map']}, {'x' if s['axis'] == 'x' else 'y'}={s['position']}"
        for kx in range(int(np.ceil(nx))):
            for ky in range(int(np.ceil(ny))):
                ox, oy = kx * px, ky * py
                if s["axis"] == "x":
                    x = ox + s["position"] / w * px
                    seg = (x, oy + s["start"] / h * py, x, oy + (s["end"] + 1) / h * py)
                else:
                    y = oy + s["position"] / h * py
                    seg = (ox + s["start"] / w * px, y, ox + (s["end"] + 1) / w * px, y)
                if 0 <= seg[0] <= W and 0 <= seg[1] <= H:  # the label once, on the first repeat
                    out.append((*(min(v, lim) for v, lim in zip(seg, (W, H, W, H))), label if kx == ky == 0 else ""))
    return out


def _pair(stack: StackReport, g: ViewGeometry, source, tile, what: str, seams: list[dict] | None = None) -> str:
    source_lines = overlay_svg(g.size, g.lines((1.0, 1.0)))
    tile_lines = overlay_svg(g.size, g.lines(g.tile_extent), g.lines(g.tile_extent, 0.5))
    if seams and stack.tile_size:
        tile_lines += seams_svg(g.size, seam_segments(g, seams, tuple(stack.tile_size)))
    uv = stack.uv_scale or (1.0, 1.0)
    what = f" {what}" if what else ""
    return (
        figure(source, f"source{what}, {_repeats(g.source_repeats)} repeats (as authored)", source_lines)
        + figure(tile, f"new tile{what}, {_repeats(g.tile_repeats)} repeats (UV scale {fmt(tuple(uv))})", tile_lines)
    )


def _why(stack: StackReport) -> str:
    if stack.status is StackStatus.LEFT_ALONE:
        reason = ": ".join(x for x in (stack.intent, stack.intent_reason) if x) or stack.message or "not meant to tile"
        return f'<div class="why info"><b>Left alone</b>: {esc(reason)}</div>'
    if stack.status in (StackStatus.FAILED, StackStatus.PLANNED):
        return ""
    q = stack.q.get("passed") if stack.q else None
    q_text = ("" if q is None else
              "The discriminator's view (not part of the verdict): no seam in its centre bands (Q passed)." if q else
              "The discriminator's view (not part of the verdict): it still sees a seam in its centre bands "
              "(Q not passed).")
    v = stack.verdict
    if v:
        size = tuple(v.get("size") or stack.tile_size or (0, 0))
        seams = v.get("seams", [])
        items = [f"seam in {'the maps together' if s['map'] == 'stack' else s['map']}: "
                 f"{Seam(**s).where(size)} ({figure_text(s['figure'])} above the seam threshold; marked in red on the "
                 f"repeats below)" for s in seams[:SEAMS_SHOWN]]
        if len(seams) > SEAMS_SHOWN:
            items.append(f"and {len(seams) - SEAMS_SHOWN} more seams (all in the JSON report)")
        items += [f"not faithful: {f}" for f in v.get("failing", [])]
        if items:
            lis = "".join(f"<li>{esc(t)}</li>" for t in items)
            gan = stack.resampled.get("gan") or {}
            advice = structure_advice(gan.get("lattice") or {}, gan.get("layout"))  # what to do, where joins show
            todo = f"<p><b>What to do</b>: {esc(advice)}.</p>" if advice else ""
            return f'<div class="why bad"><b>Not passed</b><ul>{lis}</ul>{todo}{esc(q_text)}</div>'
        return (f'<div class="why ok"><b>Passed: seamless and faithful.</b> No seam at the wrap, the centre lines or '
                f'inside any map, and every fidelity figure is inside the tolerance its source sets. {esc(q_text)}</div>')
    failing = _failing(stack)
    if failing:
        items = "".join(f"<li>{esc(text)}</li>" for _, text in failing)
        return f'<div class="why bad"><b>Outside their targets</b><ul>{items}</ul>{esc(q_text)}</div>'
    return f'<div class="why info">{esc(q_text)}</div>' if q_text else ""


def stack_html(stack: StackReport) -> str:
    """One stack's section of the page."""
    intent = ""
    if stack.intent and stack.status is not StackStatus.LEFT_ALONE:
        intent = f'<p class="intent muted">tiling intent: <b>{esc(stack.intent)}</b>' + (
            f" — {esc(stack.intent_reason)}" if stack.intent_reason else "") + "</p>"
    shown_below = stack.status is StackStatus.NOT_PASSED and stack.verdict  # the "Not passed" box lists it
    message = (f"<p>{esc(stack.message)}</p>" if stack.message and stack.status is not StackStatus.LEFT_ALONE
               and not shown_below else "")
    main, more = stack_facts(stack)
    p = loaded(stack.previews)  # read from the run's cache while this stack is drawn, then let go
    stages = ""
    if p.levels:
        stages = ('<p class="muted">How the tile was built, stage by stage (the first map, one texel per sample): '
                  'where a plank or a joint first breaks is the stage to look at.</p><div class="row">'
                  + "".join(figure(px, caption, lossless=True) for caption, px in p.levels) + "</div>")
    details = (f"<details><summary>run details</summary><table class=facts>{more}</table>{stages}</details>"
               if more or stages else "")
    blocks = []
    g = _geometry(stack)
    if g is not None and (p.lit_tile is not None or p.lit_note):
        lit = _pair(stack, g, p.lit_source, p.lit_tile, "lit") if p.lit_tile is not None else ""
        blocks.append(f'<div class="block"><h3>Material, lit from a grazing angle</h3>'
                      f'<div class="row">{lit}<p class="note muted">{esc(p.lit_note)}.{_LIT_HINT if lit else ""}</p></div></div>')
    if p.asset_tile is not None and p.asset_source is not None:
        blocks.append('<div class="block"><h3>On the asset, through the UV turn</h3><div class="row">'
                      + figure(p.asset_source, "source as authored, on the same UVs")
                      + figure(p.asset_tile, "new tile through its authored UV turn and scale") + "</div></div>")
    for m in stack.maps:
        pictures = ""
        if g is not None and m.node in p.tile_view:
            seams = [s for s in stack.verdict.get("seams", []) if s["map"] in (m.asset, "stack")][:SEAMS_SHOWN]
            pictures = _pair(stack, g, p.source_view.get(m.node), p.tile_view.get(m.node), "", seams)
        out = f' → {esc(Path(m.output).name)}' if m.output else ""
        blocks.append(
            f'<div class="block"><h3>{esc(_map_name(m))} <span class="muted">({esc(m.channels)}, '
            f"{esc(m.color_space)}) @{esc(m.asset)}@{out}</span></h3>"
            f'<div class="row">{pictures}{_metrics_table(m, made_on_a_torus(stack), _map_tolerances(stack, m))}</div></div>'
        )
    if p.discriminator is not None:
        blocks.append('<div class="block">' + figure(p.discriminator, "discriminator map; seam bands tinted", lossless=True) + "</div>")
    return (
        f'<section class="stack" id="{esc(stack.id)}"><h2>&lt;{esc(stack.material.strip("<>"))}&gt;</h2>'
        f'<span class="badge {esc(stack.status.value)}">{esc(stack.status.value)}</span>{intent}{message}'
        f'{_why(stack)}<table class="facts">{main}</table>{details}{"".join(blocks)}</section>'
    )


def _findings(report: Report) -> str:
    items = "".join(f"<li><code>{esc(f.severity.value)}</code> {esc(f.where)}: {esc(f.message)}</li>" for f in report.findings)
    return f"<h2>Findings</h2><ul class=findings>{items}</ul>" if items else ""


def _variants(report: Report) -> str:
    """The variant selections explored on each stage and the materials found under each."""
    parts = []
    for v in report.variants:
        rows = "".join(
            f"<tr><td>{esc(s['label'] or 'as the stage selects')}</td>"
            f"<td>{esc(', '.join(s['materials']) or 'none')}</td></tr>" for s in v["selections"])
        parts.append(f"<h3>{esc(v['source'])}</h3><p class=muted>{esc(v['note'])}</p>"
                     f"<table class=facts><tr><th>variant selection</th><th>materials found</th></tr>{rows}</table>")
    return f"<h2>Variant selections explored</h2>{''.join(parts)}" if parts else ""


def render_html(report: Report, title: str = "seamless-usd report", back: str | None = None) -> str:
    """The whole page of one run (or one source of a library run, ``back`` the link to the library's page)."""
    counts = report.counts()
    summary = "".join(f"<span><b>{v}</b> {esc(k.replace('_', ' '))}</span>" for k, v in counts.items() if v)
    layers = "".join(f"<li>{esc(p)}</li>" for p in report.layers_written)
    made = counts.get(StackStatus.PASSED.value, 0) + counts.get(StackStatus.REUSED.value, 0)
    edited = len(report.layers_written)
    status = (f"interrupted (Ctrl-C or SIGTERM): {f'{edited} layer(s) or document(s) written' if edited else 'no stage edited'}"
              if report.interrupted else
              "some stacks failed or did not pass" if not report.ok else
              "all stacks made passed" if made else
              "no stack made: each is left alone or planned" if report.stacks else "no texture stack found")
    body = (
        (f'<p><a href="{esc(back)}">&larr; the library\'s report</a></p>' if back else "")
        + f'<h1>{esc(title)}</h1><p class="muted">{esc(", ".join(report.sources))} · seamless-usd '
        f"{esc(report.tool_version)} · {esc(status)} (exit code {report.exit_code})</p>"
        f'<p class="summary">{summary}</p>'
        + (f"<h2>Layers and documents written</h2><ul>{layers}</ul>" if layers else "")
        + _findings(report)
        + _variants(report)
        + "".join(stack_html(s) for s in report.stacks)
    )
    return page(title, body)


def write_html(report: Report, path: Path) -> Path:
    """The report as one page at ``path``; the pages an earlier library report left beside it are removed."""
    path = Path(path)
    atomic_write_text(path, render_html(report))
    clear_stale_pages(path)
    return path


def write_json(report: Report, path: Path) -> Path:
    path = Path(path)
    atomic_write_text(path, json.dumps(report.to_dict(), indent=2))
    return path


def source_report(report: Report, source: str) -> Report:
    """The part of a library report that belongs to one source file."""
    stacks = [s for s in report.stacks if s.source == source]
    materials = {s.material for s in stacks}
    return Report(
        sources=[source],
        stacks=stacks,
        findings=[f for f in report.findings  # each finding of a run's file names it; else, by material or place
                  if (f.source == source if f.source else f.material in materials or source in f.where)],
        tool_version=report.tool_version,
        unreadable=[u for u in report.unreadable if u == source],
        variants=[v for v in report.variants if v["source"] == source],
        interrupted=report.interrupted,
    )
