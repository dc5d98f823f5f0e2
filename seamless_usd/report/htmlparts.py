"""Shared pieces of the report pages: style sheet, escaping, number formats, pictures with overlays."""
from __future__ import annotations

import html

import numpy as np

from seamless_usd.report.png import png_data_uri
from seamless_usd.report.target import GENERATOR
from seamless_usd.report.webimage import image_data_uri

__all__ = ["CSS", "OVERLAY_TOGGLE", "esc", "fmt", "figure", "overlay_svg", "seams_svg", "page"]

CSS = """
*{box-sizing:border-box}
body{font:14px/1.45 system-ui,-apple-system,"Segoe UI",sans-serif;margin:0;color:#1d1f23;background:#f4f5f7}
main{padding:16px 24px 40px;max-width:1400px}
h1{font-size:22px;margin:0 0 4px} h2{font-size:17px;margin:0;display:inline} h3{font-size:14px;margin:0 0 6px}
.muted{color:#5d6470} code{font-size:12px}
.bar{position:sticky;top:0;z-index:5;background:#1d2330;color:#e8ebf2;padding:7px 24px;display:flex;gap:22px;align-items:center;font-size:13px}
.bar label{cursor:pointer;user-select:none} .bar .key{display:inline-block;width:18px;height:0;border-top:2px solid;vertical-align:middle;margin:0 3px 0 8px}
.toggle{position:absolute;opacity:0;width:1px;height:1px}
.bar label.tog::before{content:"\\2610";font-size:16px;margin-right:6px}
#overlay-toggle:checked ~ .bar label.tog::before{content:"\\2611"}
#overlay-toggle:focus-visible ~ .bar label.tog{outline:2px solid #8ab4ff}
.overlay{display:none;position:absolute;left:0;top:0;width:100%;height:100%;pointer-events:none}
#overlay-toggle:checked ~ main .overlay{display:block}
.overlay line{vector-effect:non-scaling-stroke;stroke-width:1.5}
.overlay .border{stroke:#00e5ff} .overlay .centre{stroke:#ff3df5;stroke-dasharray:6 4}
.seams{position:absolute;left:0;top:0;width:100%;height:100%}
.seams line{vector-effect:non-scaling-stroke;stroke:#ff1744;stroke-width:2;stroke-linecap:round;opacity:.8}
.seams text{fill:#ff1744;font:bold 12px sans-serif;paint-order:stroke;stroke:#fff;stroke-width:3px}
.summary span{display:inline-block;margin-right:14px}
.stack{background:#fff;border:1px solid #d9dce3;border-radius:8px;padding:14px 18px;margin:18px 0}
.badge{display:inline-block;border-radius:10px;padding:1px 9px;font-size:12px;font-weight:600;margin-left:8px;vertical-align:2px}
.passed{background:#d8f3dc;color:#1b5e20}.not-passed{background:#fff3cd;color:#7a5a00}
.failed{background:#fde2e1;color:#9b1c1c}.reused,.planned{background:#e3e8f4;color:#283b6a}
.left-alone{background:#eceff1;color:#37474f}
.intent{margin:4px 0 0} .why{margin:8px 0;padding:6px 10px;border-radius:6px}
.why.ok{background:#eef8f0} .why.bad{background:#fdf0ef} .why.info{background:#f1f3f6}
.why ul{margin:2px 0 0 18px;padding:0}
table.facts{border-collapse:collapse;margin:8px 0} table.facts td{padding:1px 14px 1px 0;vertical-align:top}
details{margin:4px 0 8px} summary{cursor:pointer;color:#3a4a6b}
.row{display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start}
.block{border-top:1px solid #e6e8ee;padding-top:10px;margin-top:12px}
figure{margin:0;width:320px} figcaption{font-size:12px;color:#4c5361;margin-top:2px}
.view{position:relative;line-height:0;border:1px solid #c9ccd6;background:#ddd}
.view img{width:100%;height:auto;display:block}
img.plain{width:256px;height:auto;border:1px solid #c9ccd6;image-rendering:pixelated}
.figs{flex:1 1 440px;min-width:0;max-width:600px}
table.metrics{font-size:12.5px;border-collapse:collapse;width:100%}
table.metrics td,table.metrics th{padding:2px 6px;text-align:right;border-bottom:1px solid #eef0f4;white-space:nowrap}
table.metrics th:first-child,table.metrics td.v{text-align:left;white-space:normal} table.metrics th:first-child{font-weight:500}
table.metrics td.v{min-width:150px} table.metrics th:last-child{text-align:left}
.note{flex:1 1 240px;max-width:420px;font-size:13px}
td.v.ok{color:#1b5e20} td.v.bad{color:#a31515;font-weight:600}
table.metrics tr.minor td,table.metrics tr.minor th{color:#6b7280;font-size:11.5px}
table.metrics tr.sep td{border-bottom:0;padding-top:8px;color:#6b7280;font-size:11.5px;text-align:left}
.findings li{margin:2px 0}
"""

#: The page-wide checkbox that shows the tile borders and centre lines over the pictures (CSS only).
OVERLAY_TOGGLE = (
    '<input type="checkbox" id="overlay-toggle" class="toggle">'
    '<div class="bar"><label class="tog" for="overlay-toggle">show tile borders and centre lines</label>'
    '<span><span class="key" style="color:#00e5ff"></span>repeat borders'
    '<span class="key" style="color:#ff3df5;border-top-style:dashed"></span>tile centre lines</span></div>'
)


def esc(value: object) -> str:
    return html.escape(str(value))


def fmt(value: object) -> str:
    """A figure for people: 3 significant digits, sequences as ``a x b``, None as ``-``."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, float):
        return f"{value:.3g}"
    if isinstance(value, (list, tuple)):
        return " x ".join(fmt(v) for v in value)
    return str(value)


def overlay_svg(size: tuple[int, int], borders: tuple[list[float], list[float]],
                centres: tuple[list[float], list[float]] | None = None) -> str:
    """An SVG laid over a picture of ``size = (W, H)`` px: border lines and (dashed) centre lines."""
    w, h = size
    parts = []
    for cls, (xs, ys) in (("border", borders), ("centre", centres or ([], []))):
        parts += [f'<line class="{cls}" x1="{x:.2f}" y1="0" x2="{x:.2f}" y2="{h}"/>' for x in xs]
        parts += [f'<line class="{cls}" x1="0" y1="{y:.2f}" x2="{w}" y2="{y:.2f}"/>' for y in ys]
    return (f'<svg class="overlay" viewBox="0 0 {w} {h}" preserveAspectRatio="none" aria-hidden="true">'
            f'{"".join(parts)}</svg>')


def seams_svg(size: tuple[int, int], segments: list[tuple]) -> str:
    """An always-visible SVG over a picture of ``size = (W, H)``: each seam ``(x1, y1, x2, y2, label[, shown])`` as a
    red line with its label in its tooltip, and the label's figure written beside the middle of the line unless
    ``shown`` is False (a repeat of a seam already written) or a stronger seam's figure is written there already
    (segments come strongest first: two wraps both seamed put both figures at the picture's corner, the weaker
    drawn over the stronger)."""
    if not segments:
        return ""
    w, h = size
    lines, texts, placed = [], [], []
    for x1, y1, x2, y2, label, *rest in segments:
        lines.append(f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}"><title>{esc(label)}</title></line>')
        if not label or (rest and not rest[0]):
            continue
        vertical = abs(x2 - x1) < abs(y2 - y1)
        tx = x1 + 4 if vertical else (x1 + x2) / 2
        ty = (y1 + y2) / 2 if vertical else y1 + 14
        tx, ty = min(max(tx, 2.0), w - 40.0), min(max(ty, 14.0), h - 4.0)
        if all(abs(tx - px) > 46 or abs(ty - py) > 18 for px, py in placed):  # a bold 12 px figure and its halo
            placed.append((tx, ty))
            texts.append(f'<text x="{tx:.1f}" y="{ty:.1f}">{esc(label.split(":")[0])}</text>')
    return (f'<svg class="seams" viewBox="0 0 {w} {h}" preserveAspectRatio="none" role="img" '
            f'aria-label="seams found">{"".join(lines + texts)}</svg>')


def figure(pixels: np.ndarray | None, caption: str, overlay: str = "", lossless: bool = False) -> str:
    """A ``<figure>`` with the picture embedded (WebP/JPEG, PNG when ``lossless``) and its overlay."""
    if pixels is None:
        return ""
    h, w = pixels.shape[:2]
    src = png_data_uri(np.ascontiguousarray(pixels)) if lossless else image_data_uri(pixels)
    if lossless:
        return f'<figure><img class="plain" src="{src}" width="{w}" height="{h}" alt="{esc(caption)}"><figcaption>{esc(caption)}</figcaption></figure>'
    return (f'<figure><div class="view"><img src="{src}" width="{w}" height="{h}" alt="{esc(caption)}">'
            f'{overlay}</div><figcaption>{esc(caption)}</figcaption></figure>')


def page(title: str, body: str, extra_css: str = "", toggle: bool = True) -> str:
    """A whole self-contained HTML document (its head marks it as this tool's: :data:`.target.GENERATOR`)."""
    return (f'<!doctype html><html lang="en"><head><meta charset="utf-8">'
            f'{GENERATOR}'
            f'<meta name="viewport" content="width=device-width,initial-scale=1"><link rel="icon" href="data:,">'
            f"<title>{esc(title)}</title><style>{CSS}{extra_css}</style></head><body>"
            f'{OVERLAY_TOGGLE if toggle else ""}<main>{body}</main></body></html>\n')
