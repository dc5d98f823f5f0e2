"""Self-contained HTML report: one page per run, pictures embedded as data URIs."""
from __future__ import annotations

import html
import json
from pathlib import Path

from seamless_usd.fileio import atomic_write_text
from seamless_usd.metrics import METRIC_KEYS
from seamless_usd.report.model import Report, StackReport
from seamless_usd.report.png import png_data_uri

__all__ = ["render_html", "render_index", "write_html", "write_json", "write_library_html"]

_CSS = """
body{font:14px/1.45 system-ui,-apple-system,Segoe UI,sans-serif;margin:24px;color:#1d1f23;background:#fafafa}
h1{font-size:22px;margin:0 0 4px} h2{font-size:17px;margin:0} .muted{color:#667}
.summary span{display:inline-block;margin-right:14px}
.stack{background:#fff;border:1px solid #dde;border-radius:8px;padding:14px 16px;margin:18px 0}
.badge{display:inline-block;border-radius:10px;padding:1px 9px;font-size:12px;font-weight:600;margin-left:8px}
.passed{background:#d8f3dc;color:#1b5e20}.not-passed{background:#fff3cd;color:#7a5a00}
.failed{background:#fde2e1;color:#9b1c1c}.reused,.planned{background:#e3e8f4;color:#283b6a}
table.facts{border-collapse:collapse;margin:8px 0}
table.facts td{padding:2px 12px 2px 0;vertical-align:top}
.maps{display:flex;flex-wrap:wrap;gap:16px;margin-top:10px}
.map{border-top:1px solid #eef;padding-top:8px}
.pair{display:flex;gap:10px} figure{margin:0} figcaption{font-size:12px;color:#556}
img{image-rendering:pixelated;border:1px solid #ccd;width:256px;height:auto}
table.metrics{font-size:12px;border-collapse:collapse} table.metrics td,table.metrics th{padding:1px 8px;text-align:right}
.findings li{margin:2px 0} code{font-size:12px}
"""

_METRIC_ORDER = METRIC_KEYS


def _esc(value: object) -> str:
    return html.escape(str(value))


def _img(pixels, caption: str) -> str:
    if pixels is None:
        return ""
    return f'<figure><img src="{png_data_uri(pixels)}" alt="{_esc(caption)}"><figcaption>{_esc(caption)}</figcaption></figure>'


def _fmt(value: object) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        return f"{value:.3g}"
    if isinstance(value, (list, tuple)):
        return " x ".join(_fmt(v) for v in value)
    return str(value)


def _policy_text(record: dict) -> str | None:
    """``{"policy": {...}, "working_size": [W, H], "maps": [...]}`` as one readable line."""
    if not record:
        return None
    policy = record.get("policy", {})
    cap = policy.get("max_size")
    text = f"cap {cap} px" if cap else "native size (no cap)"
    text += f", common size: {policy.get('common', 'largest')}, filter {policy.get('filter', 'auto')}"
    changed = [m for m in record.get("maps", []) if m.get("resampled")]
    if changed:
        text += "; resampled: " + ", ".join(
            f"@{m['asset']}@ {m['original_size'][0]}x{m['original_size'][1]}" for m in changed
        )
    else:
        text += "; no map resampled"
    return text


def _metrics_table(new: dict, source: dict) -> str:
    present = {k for k, v in [*new.items(), *source.items()] if v is not None}
    keys = [k for k in _METRIC_ORDER if k in present] + sorted(present - set(_METRIC_ORDER))
    if not keys:
        return ""
    rows = "".join(
        f"<tr><th>{_esc(k)}</th><td>{_fmt(source.get(k, '-'))}</td><td>{_fmt(new.get(k, '-'))}</td></tr>"
        for k in keys
    )
    return f'<table class="metrics"><tr><th></th><th>source as is</th><th>new tile</th></tr>{rows}</table>'


def _stack_html(stack: StackReport) -> str:
    facts = {
        "source": stack.source,
        "crop size (h x w)": stack.crop_size,
        "tile size (h x w)": stack.tile_size,
        "working size (w x h)": stack.working_size,
        "working resolution": _policy_text(stack.resampled),
        "UV scale": stack.uv_scale,
        "Q": ", ".join(f"{k} {_fmt(v)}" for k, v in stack.q.items()) or None,
        "candidates tried": stack.candidates or None,
        "timings (s)": ", ".join(f"{k} {v:.1f}" for k, v in stack.timings.items()) or None,
        "device / precision": f"{stack.device} / {stack.precision}" if stack.device else None,
        "model hash": stack.model_hash or None,
        "same as": stack.duplicate_of,
        "result from": stack.origin or None,
        "peak memory (MB)": stack.peak_rss_mb or None,
    }
    rows = "".join(
        f"<tr><td class=muted>{_esc(k)}</td><td>{_esc(_fmt(v))}</td></tr>" for k, v in facts.items() if v
    )
    maps = []
    for m in stack.maps:
        pair = _img(stack.previews.source_2x2.get(m.node), "source, tiled 2x2") + _img(
            stack.previews.tile_2x2.get(m.node), "new tile, tiled 2x2"
        )
        maps.append(
            f'<div class="map"><div><b>{_esc(", ".join(m.roles))}</b> <span class=muted>'
            f"({_esc(m.channels)}, {_esc(m.color_space)}) @{_esc(m.asset)}@"
            f'{" → " + _esc(Path(m.output).name) if m.output else ""}</span></div>'
            f'<div class="pair">{pair}</div>{_metrics_table(m.metrics, m.source_metrics)}</div>'
        )
    disc = _img(stack.previews.discriminator, "discriminator map; seam bands outlined")
    message = f"<p>{_esc(stack.message)}</p>" if stack.message else ""
    return (
        f'<section class="stack" id="{_esc(stack.id)}"><h2>&lt;{_esc(stack.material.strip("<>"))}&gt;'
        f'<span class="badge {stack.status.value}">{stack.status.value}</span></h2>{message}'
        f'<table class="facts">{rows}</table><div class="maps">{"".join(maps)}'
        f'{"<div class=map>" + disc + "</div>" if disc else ""}</div></section>'
    )


def render_html(report: Report, title: str = "seamless-usd report") -> str:
    counts = report.counts()
    summary = "".join(f"<span><b>{v}</b> {k}</span>" for k, v in counts.items() if v)
    findings = "".join(f"<li><code>{_esc(f.severity.value)}</code> {_esc(f.where)}: {_esc(f.message)}</li>" for f in report.findings)
    layers = "".join(f"<li>{_esc(p)}</li>" for p in report.layers_written)
    stacks = "".join(_stack_html(s) for s in report.stacks)
    status = "all stacks passed" if report.ok else "some stacks failed or did not pass"
    return f"""<!doctype html><html lang="en"><head><meta charset="utf-8">
<title>{_esc(title)}</title><style>{_CSS}</style></head><body>
<h1>{_esc(title)}</h1><p class="muted">{_esc(", ".join(report.sources))} · seamless-usd {_esc(report.tool_version)} · {_esc(status)} (exit code {report.exit_code})</p>
<p class="summary">{summary}</p>
{"<h2>Layers and documents written</h2><ul>" + layers + "</ul>" if layers else ""}
{"<h2>Findings</h2><ul class=findings>" + findings + "</ul>" if findings else ""}
{stacks}
</body></html>
"""


def write_html(report: Report, path: Path) -> Path:
    path = Path(path)
    atomic_write_text(path, render_html(report))
    return path


def write_json(report: Report, path: Path) -> Path:
    path = Path(path)
    atomic_write_text(path, json.dumps(report.to_dict(), indent=2))
    return path


def _source_report(report: Report, source: str) -> Report:
    """The part of a library report that belongs to one source file."""
    stacks = [s for s in report.stacks if s.source == source]
    materials = {s.material for s in stacks}
    return Report(
        sources=[source],
        stacks=stacks,
        findings=[f for f in report.findings if f.material in materials or source in f.where],
        tool_version=report.tool_version,
        unreadable=[u for u in report.unreadable if u == source],
    )


def render_index(report: Report, pages: dict[str, str], title: str = "seamless-usd library report") -> str:
    """The library page: one row per source with its counts and a link to its own report."""
    rows = []
    for source in report.sources:
        part = _source_report(report, source)
        counts = part.counts()
        cells = "".join(f"<td>{counts[k] or ''}</td>" for k in ("passed", "not-passed", "failed", "reused", "trained", "from_cache"))
        state = "unreadable" if part.unreadable else ("ok" if part.ok else "needs a look")
        link = pages.get(source)
        name = f'<a href="{_esc(link)}">{_esc(source)}</a>' if link else _esc(source)
        rows.append(f"<tr><td>{name}</td>{cells}<td>{_esc(state)}</td></tr>")
    problems = "".join(
        f"<li><code>{_esc(f.severity.value)}</code> {_esc(f.where)}: {_esc(f.message)}</li>"
        for f in report.findings if f.severity.value == "error"
    )
    counts = report.counts()
    summary = "".join(f"<span><b>{v}</b> {k}</span>" for k, v in counts.items() if v)
    total = report.timings.get("total")
    return f"""<!doctype html><html lang="en"><head><meta charset="utf-8">
<title>{_esc(title)}</title><style>{_CSS}
table.lib{{border-collapse:collapse;background:#fff}} table.lib td,table.lib th{{border:1px solid #dde;padding:3px 8px;text-align:left}}</style></head><body>
<h1>{_esc(title)}</h1><p class="muted">{len(report.sources)} files · seamless-usd {_esc(report.tool_version)} · exit code {report.exit_code}{f" · {total:.0f} s" if total else ""}</p>
<p class="summary">{summary}</p>
<table class="lib"><tr><th>file</th><th>passed</th><th>not passed</th><th>failed</th><th>reused</th><th>trained</th><th>from cache</th><th>state</th></tr>{"".join(rows)}</table>
{"<h2>Failures</h2><ul class=findings>" + problems + "</ul>" if problems else ""}
</body></html>
"""


def write_library_html(report: Report, path: Path) -> Path:
    """The index page at ``path`` and one report per source beside it (``<stem>.files/``)."""
    from seamless_usd.pipeline.naming import slug

    path = Path(path)
    folder = path.with_name(f"{path.stem}.files")
    folder.mkdir(parents=True, exist_ok=True)
    pages: dict[str, str] = {}
    for n, source in enumerate(report.sources, 1):
        page = folder / f"{n:04d}-{slug(Path(source).stem, 40)}.html"
        atomic_write_text(page, render_html(_source_report(report, source), title=f"seamless-usd: {Path(source).name}"))
        pages[source] = f"{folder.name}/{page.name}"
    atomic_write_text(path, render_index(report, pages))
    return path
