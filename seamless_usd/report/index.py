"""The library index page: a thumbnail card per stack, filterable by status, and a row per file.

Each card shows the result's thumbnail (the lit tile, or the first map's tile), the material, the
file, the status and why: the figures outside their targets, the tiling intent and its reason for
a stack left alone, the error of a failed one. A card links to the stack on its file's own page
(in ``<index stem>.files/``). Filtering is pure CSS (radio buttons), so the page needs no script.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Callable
from pathlib import Path

from seamless_usd.fileio import atomic_write_text
from seamless_usd.report.target import clear_stale_pages
from seamless_usd.naming import slug
from seamless_usd.report.html import failing_figures, render_html, source_report
from seamless_usd.report.htmlparts import esc, page
from seamless_usd.report.model import Report, StackReport, StackStatus
from seamless_usd.report.stored import thumbnail_picture
from seamless_usd.report.webimage import image_data_uri

__all__ = ["FILTER_ORDER", "render_index", "write_library_html", "stack_reason"]

#: Statuses offered as filters, in this order (only those present are shown).
FILTER_ORDER = (StackStatus.PASSED, StackStatus.NOT_PASSED, StackStatus.FAILED, StackStatus.LEFT_ALONE,
                StackStatus.REUSED, StackStatus.PLANNED)

_INDEX_CSS = """
.filters{margin:12px 0 10px;display:flex;gap:8px;flex-wrap:wrap}
.filters label{cursor:pointer;border:1px solid #b9bfcc;border-radius:14px;padding:2px 12px;background:#fff;user-select:none}
.cards{display:grid;grid-template-columns:repeat(auto-fill,minmax(220px,1fr));gap:14px}
.card{background:#fff;border:1px solid #d9dce3;border-radius:8px;padding:10px;display:flex;flex-direction:column;gap:4px}
.card a.thumb{display:block;line-height:0}
.card a.thumb{text-decoration:none}
.card img,.card .ph{width:100%;height:auto;aspect-ratio:1/1;object-fit:cover;border:1px solid #c9ccd6;border-radius:4px}
.card .ph{display:flex;align-items:center;justify-content:center;background:repeating-linear-gradient(45deg,#f0f1f4,#f0f1f4 8px,#e7e9ee 8px,#e7e9ee 16px);color:#5d6470;font-size:13px;line-height:1.3;text-align:center;padding:8px}
.card .mat{font-weight:600;word-break:break-all} .card .file{font-size:12px;color:#5d6470;word-break:break-all}
.card .reason{font-size:12.5px}
main>h2{display:block;margin:22px 0 6px}
table.lib{border-collapse:collapse;background:#fff} table.lib td,table.lib th{border:1px solid #dde;padding:3px 8px;text-align:left}
"""


def stack_reason(stack: StackReport) -> str:
    """One line saying why a stack has its status."""
    if stack.status is StackStatus.LEFT_ALONE:
        return ": ".join(x for x in (stack.intent, stack.intent_reason) if x) or stack.message or "not meant to tile"
    if stack.status is StackStatus.FAILED:
        return stack.message or "failed"
    if stack.status is StackStatus.REUSED:
        return f"same as {stack.duplicate_of}" if stack.duplicate_of else "identical to a stack processed before"
    if stack.status is StackStatus.PLANNED:
        return "would be processed (dry run)"
    if stack.status is StackStatus.NOT_PASSED:
        return stack.message or "not passed"
    failing = failing_figures(stack)
    if failing:
        more = f" (+{len(failing) - 2} more)" if len(failing) > 2 else ""
        return "; ".join(failing[:2]) + more
    if stack.status is StackStatus.PASSED and stack.verdict:
        return "seamless and faithful"
    return "all figures within their targets" if any(m.metrics for m in stack.maps) else (stack.message or "")


def _filter_id(status: StackStatus) -> str:
    return f"f-{status.value}"


def shown_names(sources: list[str]) -> dict[str, str]:
    """Each source file as the library's pages name it: its path under the folder all of them share (every file
    of a library may be a ``scene.usda``), or its name when it is the only one."""
    if len(sources) < 2:
        return {s: Path(s).name for s in sources}
    try:
        common = os.path.commonpath([os.path.dirname(os.path.abspath(s)) for s in sources])
    except ValueError:  # different drives
        return {s: s for s in sources}
    return {s: os.path.relpath(os.path.abspath(s), common) for s in sources}


def _card(stack: StackReport, link: str | None, shown: str) -> str:
    thumb = thumbnail_picture(stack.previews)
    name = stack.material.strip("<>")
    if thumb is not None:
        picture = f'<img src="{image_data_uri(thumb)}" width="{thumb.shape[1]}" height="{thumb.shape[0]}" alt="{esc(name)}">'
    else:
        picture = f'<div class="ph">{esc(stack.status.value.replace("-", " "))}: no picture</div>'
    if link:  # the stack's anchor on its file's page
        target = f"{link}#{stack.id}"
        picture = f'<a class="thumb" href="{esc(target)}">{picture}</a>'
        title = f'<a class="mat" href="{esc(target)}">&lt;{esc(name)}&gt;</a>'
    else:
        title = f'<span class="mat">&lt;{esc(name)}&gt;</span>'
    return (
        f'<div class="card s-{esc(stack.status.value)}" data-status="{esc(stack.status.value)}">{picture}'
        f'<div>{title}<span class="badge {esc(stack.status.value)}">{esc(stack.status.value)}</span></div>'
        f'<div class="file">{esc(shown)}'
        f'{esc(f" (variant {stack.variant})") if stack.variant else ""}</div>'
        f'<div class="reason">{esc(stack_reason(stack))}</div></div>'
    )


def _filters(report: Report) -> tuple[str, str, str]:
    """(radio inputs, their labels, the CSS rules that hide the other cards)."""
    counts = report.counts()
    present = [s for s in FILTER_ORDER if counts.get(s.value)]
    inputs = '<input type="radio" name="status-filter" id="f-all" class="toggle" checked>' + "".join(
        f'<input type="radio" name="status-filter" id="{_filter_id(s)}" class="toggle">' for s in present
    )
    labels = f'<label for="f-all">all ({len(report.stacks)})</label>' + "".join(
        f'<label for="{_filter_id(s)}">{esc(s.value.replace("-", " "))} ({counts[s.value]})</label>' for s in present
    )
    rules = "#f-all:checked ~ .filters label[for=f-all]{background:#1d2330;color:#fff;border-color:#1d2330}" + "".join(
        f"#{_filter_id(s)}:checked ~ .cards .card:not(.s-{s.value}){{display:none}}"
        f"#{_filter_id(s)}:checked ~ .filters label[for={_filter_id(s)}]{{background:#1d2330;color:#fff;border-color:#1d2330}}"
        for s in FILTER_ORDER
    )
    return inputs, labels, rules


def _files_table(report: Report, pages: dict[str, str]) -> str:
    rows = []
    for source in report.sources:
        part = source_report(report, source)
        counts = part.counts()
        cells = "".join(f"<td>{counts[k] or ''}</td>" for k in
                        ("passed", "not-passed", "failed", "left-alone", "reused", "trained", "from_cache"))
        state = "unreadable" if part.unreadable else ("ok" if part.ok else "needs a look")
        link = pages.get(source)
        name = f'<a href="{esc(link)}">{esc(source)}</a>' if link else esc(source)
        rows.append(f"<tr><td>{name}</td>{cells}<td>{esc(state)}</td></tr>")
    head = "".join(f"<th>{h}</th>" for h in
                   ("file", "passed", "not passed", "failed", "left alone", "reused", "trained", "from cache", "state"))
    return f'<h2>Files</h2><table class="lib"><tr>{head}</tr>{"".join(rows)}</table>'


def render_index(report: Report, pages: dict[str, str], title: str = "seamless-usd library report") -> str:
    """The library page: a card per stack (filterable by status) and a row per source file.

    ``pages`` maps a source to the relative link of its own report page.
    """
    inputs, labels, rules = _filters(report)
    names = shown_names(report.sources)
    # what needs a look first (failed, then not passed), each kind in the files' order: in a library of hundreds of
    # stacks the not-passed ones were scattered among the passed
    first = {StackStatus.FAILED: 0, StackStatus.NOT_PASSED: 1}
    shown = sorted(report.stacks, key=lambda s: first.get(s.status, 2))
    cards = "".join(_card(s, pages.get(s.source), names.get(s.source, Path(s.source).name)) for s in shown)
    problems = "".join(  # a library's files share material paths: each failure names its file
        f"<li><code>{esc(f.severity.value)}</code> {esc(f.where)}: {esc(f.message)}"
        f"{f' <span class=muted>({esc(names.get(f.source, f.source))})</span>' if f.source else ''}</li>"
        for f in report.findings if f.severity.value == "error"
    )
    layers = "".join(f"<li>{esc(str(p))}</li>" for p in report.layers_written)
    counts = report.counts()
    summary = "".join(f"<span><b>{v}</b> {esc(k.replace('_', ' '))}</span>" for k, v in counts.items() if v)
    total = report.timings.get("total")
    body = (
        f'<h1>{esc(title)}</h1><p class="muted">{len(report.sources)} files · {len(report.stacks)} stacks · '
        f'seamless-usd {esc(report.tool_version)} · exit code {report.exit_code}{f" · {total:.0f} s" if total else ""}</p>'
        f'<p class="summary">{summary}</p>'
        + (f"<h2>Failures</h2><ul class=findings>{problems}</ul>" if problems else "")
        + _files_table(report, pages)  # above the cards: a library of hundreds of stacks is read file by file
        + (f"<details><summary>Layers and documents written ({len(report.layers_written)})</summary>"
           f"<ul>{layers}</ul></details>" if layers else "")
        + f'<h2>Stacks</h2>{inputs}<div class="filters">{labels}</div><div class="cards">{cards}</div>'
    )
    return page(title, body, extra_css=_INDEX_CSS + rules, toggle=False)


#: The last line of a library's page: what it was drawn from (:func:`_page_key`), so that a run again that would
#: draw the same page leaves it as it is (drawing the pictures again took 40 s for a library of 200 files).
_KEY_MARK = "<!-- seamless-usd page {} -->\n"


def _page_key(part: Report, title: str, back: str) -> str | None:
    """What a source's page is drawn from, as a digest: its report (less the memory the process that ran each stack
    used: a cached stack's differs by a megabyte from run to run), the pictures' files (named by their content) and
    this version; None where a stack's pictures are held only in memory (made in this run and not kept in a cache),
    which is always drawn."""
    from seamless_usd.version import __version__

    if any(not s.previews.stored and (s.previews.thumbnail is not None or s.previews.tile_view) for s in part.stacks):
        return None
    body = part.to_dict()
    for stack in body["stacks"]:
        stack.pop("peak_rss_mb", None)
    text = json.dumps([body, [s.previews.stored for s in part.stacks], title, back, __version__], sort_keys=True,
                      default=str)
    return hashlib.sha256(text.encode()).hexdigest()


def _kept_key(page_path: Path) -> str | None:
    """The key a page already there was drawn from (its last line), None when it has none or is not there."""
    try:
        with open(page_path, "rb") as fh:
            fh.seek(max(0, page_path.stat().st_size - 200))
            tail = fh.read().decode("utf-8", "replace")
    except OSError:
        return None
    found = re.search(r"<!-- seamless-usd page ([0-9a-f]{64}) -->\s*$", tail)
    return found.group(1) if found else None


def write_library_html(report: Report, path: Path, progress: Callable[[int, int], None] | None = None) -> Path:
    """The index page at ``path`` and one report per source beside it (``<stem>.files/``); ``progress(done,
    total)`` as each page is written (a library's pages take a fraction of a second each)."""
    path = Path(path)
    folder = path.with_name(f"{path.stem}.files")
    folder.mkdir(parents=True, exist_ok=True)
    pages: dict[str, str] = {}
    names = shown_names(report.sources)
    for n, source in enumerate(report.sources, 1):
        target = folder / f"{n:04d}-{slug(Path(source).stem, 40)}.html"
        part, title, back = source_report(report, source), f"seamless-usd: {names[source]}", f"../{path.name}"
        key = _page_key(part, title, back)
        if key is None or _kept_key(target) != key:  # a page the same as the one there is not drawn again
            atomic_write_text(target, render_html(part, title=title, back=back) + _KEY_MARK.format(key or ""))
        pages[source] = f"{folder.name}/{target.name}"
        if progress is not None:
            progress(n, len(report.sources))
    clear_stale_pages(path, frozenset(Path(p).name for p in pages.values()))  # an earlier run's other pages
    atomic_write_text(path, render_index(report, pages))
    return path
