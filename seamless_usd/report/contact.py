"""The contact sheet of ``seamless-usd check``: one card per texture or stack, its picture repeated 2 x 2 so the
wrap shows, every seam the verdict found drawn in red on each repeat, its status and where the seams run.

It takes plain values (a :class:`SheetCard` per item), so the page is made the same from any caller; filtering
by status is pure CSS (radio buttons), so the page needs no script.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from seamless_usd.fileio import atomic_write_text
from seamless_usd.metrics import preview_uint8
from seamless_usd.report.htmlparts import esc, page, seams_svg
from seamless_usd.report.webimage import image_data_uri
from seamless_usd.verdict.lines import figure_text

__all__ = ["THUMB", "FAINT", "SheetCard", "thumbnail", "displayed", "render_contact_sheet", "write_contact_sheet"]

#: Side (px) of one repeat of a card's picture.
THUMB = 96

_CSS = """
.sheet{display:grid;grid-template-columns:repeat(auto-fill,minmax(230px,1fr));gap:12px;margin-top:12px}
.card{background:#fff;border:1px solid #d9dce3;border-radius:8px;padding:8px;font-size:12px;overflow-wrap:anywhere}
.card .view{width:100%} .card p{margin:4px 0 0}
.filters label{margin-right:14px;cursor:pointer}
#f-passed:checked ~ main .card:not(.s-passed),#f-not:checked ~ main .card:not(.s-not-passed),
#f-error:checked ~ main .card:not(.s-error){display:none}
"""


@dataclass
class SheetCard:
    """One item of the sheet: its name, status (``passed``, ``not-passed`` or ``error``), the words saying
    where its seams run (or why it could not be judged), its thumbnail and the seams in the thumbnail's own
    pixels."""

    name: str
    status: str
    words: str
    picture: str = ""  # a data: URI of the 2 x 2 repeat (empty: none)
    size: tuple[int, int] = (0, 0)  # (w, h) of one repeat in the thumbnail, px
    seams: list[dict] = field(default_factory=list)  # Seam.as_dict() in the thumbnail's pixels of one repeat


def thumbnail(pixels: np.ndarray, side: int = THUMB, linear: bool = False
              ) -> tuple[str, tuple[int, int], float, str]:
    """A picture ``(H, W, C)`` in ``[-1, 1]`` as a 2 x 2 repeat of at most ``side`` px a repeat (data URI), the
    repeat's ``(w, h)``, the scale from the picture's texels to the thumbnail's pixels and what was done to show it
    (:func:`displayed`). ``linear``: its values are linear light (a float OpenEXR's colour), shown through the sRGB
    transfer as a viewer shows them."""
    a = np.asarray(pixels)
    scale = min(1.0, side / max(a.shape[:2]))
    h, w = max(1, round(a.shape[0] * scale)), max(1, round(a.shape[1] * scale))
    ys = (np.arange(h) * a.shape[0] / h).astype(int)
    xs = (np.arange(w) * a.shape[1] / w).astype(int)
    small = np.asarray(a[ys][:, xs], dtype=np.float64)
    small, said = displayed(small, linear)
    rgb = preview_uint8(small)
    return image_data_uri(np.tile(rgb, (2, 2, 1))), (w, h), scale, said


#: A picture whose values span less than this share of the range is shown stretched to its own range.
FAINT = 0.04


def displayed(small: np.ndarray, linear: bool) -> tuple[np.ndarray, str]:
    """``small`` (network domain) as the thumbnail shows it, and what was done to show it ('' when nothing): linear
    light brought down so its 99th percentile is white when it goes above (an HDR picture was a white square), then
    through the sRGB transfer; a picture whose values span under :data:`FAINT` of the range (a 16-bit height map
    holding a few per cent) stretched to its own range (it was a flat square)."""
    said = ""
    v = (small + 1.0) / 2.0  # file values
    if linear:
        from seamless_usd.imaging.transfer import eotf_inverse_srgb

        top = float(np.percentile(v, 99))
        if top > 1.0:
            v = v / top
            said = f"shown exposed x{1 / top:.3g} (its values reach {top:.3g})"
        v = eotf_inverse_srgb(np.clip(v, 0.0, 1.0))
    lo, hi = (float(x) for x in np.percentile(v, (0.5, 99.5)))
    if 0.0 < hi - lo < FAINT:
        v = (v - lo) / (hi - lo)
        said = f"shown stretched x{1 / (hi - lo):.3g} (its values span {100 * (hi - lo):.2g} % of the range)"
    return np.clip(v, 0.0, 1.0) * 2.0 - 1.0, said


def _segments(card: SheetCard) -> list[tuple[float, float, float, float, str, bool]]:
    """Each seam of the card on the picture repeated 2 x 2, four times, strongest first; its figure written on the
    copy nearest the middle only (a wrap's: the line through the middle)."""
    w, h = card.size

    def near_middle(value: float, side: int) -> int:  # the repeat (0 or side) that puts ``value`` nearer ``side``
        return side if value <= side / 2 else 0

    out = []
    for s in sorted(card.seams, key=lambda s: -s["figure"]):
        label = f"{figure_text(s['figure'])}: {s.get('map', 'stack')}"
        run, at, first, last = (s["start"] + s["end"]) / 2, s["position"], s["start"], s["end"] + 1
        for ry in (0, h):
            for rx in (0, w):
                if s["axis"] == "x":
                    shown = rx == near_middle(at, w) and ry == near_middle(run, h)
                    out.append((rx + at, ry + first, rx + at, ry + last, label, shown))
                else:
                    shown = rx == near_middle(run, w) and ry == near_middle(at, h)
                    out.append((rx + first, ry + at, rx + last, ry + at, label, shown))
    return out


def render_contact_sheet(cards: list[SheetCard], title: str = "seamless-usd check", unreadable: Sequence[str] = (),
                         not_judged: Sequence[str] = (), exit_code: int | None = None) -> str:
    """The whole page: a summary (with the inputs that could not be opened, the pictures not judged and the exit
    code, as the command says them), the status filters and a card per item."""
    counts = {k: sum(c.status == k for c in cards) for k in ("passed", "not-passed", "error")}
    things = "texture or stack" if len(cards) == 1 else "textures or stacks"
    opened = f" {len(unreadable)} input(s) could not be opened." if unreadable else ""
    code = f" Exit code {exit_code}." if exit_code is not None else ""
    body = [f"<h1>{esc(title)}</h1><p class=muted>{len(cards)} {things}: {counts['passed']} passed, "
            f"{counts['not-passed']} not passed, {counts['error']} could not be judged.{opened}{code} Each picture is "
            "repeated 2 x 2, so its wrap runs through the middle; red lines are the seams found.</p>"]
    for heading, lines in (("Could not be opened", unreadable),
                           ("Not judged (pictures in folders of scenes that no scene uses)", not_judged)):
        if lines:
            body.append(f"<h2>{esc(heading)}</h2><ul class=findings>"
                        + "".join(f"<li>{esc(line)}</li>" for line in lines) + "</ul>")
    body.append("<div class=sheet>")
    for c in cards:
        view = ""
        if c.picture:
            w, h = c.size
            view = (f'<div class="view"><img src="{c.picture}" width="{2 * w}" height="{2 * h}" alt="{esc(c.name)}">'
                    f"{seams_svg((2 * w, 2 * h), _segments(c))}</div>")
        badge = {"passed": "passed", "not-passed": "not passed", "error": "could not be judged"}[c.status]
        body.append(f'<div class="card s-{c.status}">{view}<p><b>{esc(c.name)}</b>'
                    f'<span class="badge {c.status if c.status != "error" else "failed"}">{badge}</span></p>'
                    f"<p class=muted>{esc(c.words)}</p></div>")
    body.append("</div>")
    filters = ('<input type=radio name=f id=f-all class=toggle checked><input type=radio name=f id=f-passed class=toggle>'
               '<input type=radio name=f id=f-not class=toggle><input type=radio name=f id=f-error class=toggle>'
               '<div class="bar filters"><label for=f-all>all</label><label for=f-passed>passed</label>'
               '<label for=f-not>not passed</label><label for=f-error>could not be judged</label></div>')
    html = page(title, "".join(body), extra_css=_CSS, toggle=False)
    return html.replace("<body>", "<body>" + filters, 1)


def write_contact_sheet(cards: list[SheetCard], path: Path, title: str = "seamless-usd check",
                        unreadable: Sequence[str] = (), not_judged: Sequence[str] = (),
                        exit_code: int | None = None) -> Path:
    """Write the page (:func:`render_contact_sheet`) to ``path`` atomically."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(path, render_contact_sheet(cards, title, unreadable, not_judged, exit_code))
    return path
