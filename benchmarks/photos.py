#!/usr/bin/env python3
"""Real photos of materials, made tileable by the product and by its peers, judged and pictured.

For every photo in ``--photos`` (default ``benchmarks/photos``, see its ``SOURCES.md``; longest side capped
at ``--size``; a texture its publisher made to tile, through a plain window of it, which does not), as one
colour map:

- ``seamless-usd``: the product's tile. ``--cut-only`` (the default) stops where the product would train
  SeamlessGAN: the tiles cut from the source (lattice, window, the source mended, a quilt), tried in turn,
  the first that passes written; ``--gan`` lets a stack whose cuts all fail train with ``--preset``.
- ``img2texture`` (PyPI, the project's ``bench`` extra): a crossfade of the photo's halves.
- ``resynthesizer`` (GIMP's Resynthesizer, GPL-3.0, run in its own environment by ``--resynth-python``):
  the photo offset by half, a band over the seam cross re-synthesised from the rest of it
  (``benchmarks/peers/resynthesizer_tile.py``).

Each tile is judged by the product's verdict against its source (the one ``passed``), with the time it
took. Writes ``photos.md`` / ``photos.json`` and, per photo and method, ``tiles/NAME__METHOD.jpg`` (the tile
repeated 3 x 3 at the source's texel scale, the source beside it) and ``tiles/NAME__METHOD_zoom.png`` (the
tile's centre and its wrap corner, zoomed 3x), to look at.

    .venv/bin/python benchmarks/photos.py --resynth-python .peers/bin/python --out /tmp/photos
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

from methods import img2texture_tile, resynthesizer_tile  # noqa: E402
from results_io import write_results  # noqa: E402

PHOTOS = HERE / "photos"
METHODS = ("seamless-usd", "img2texture", "resynthesizer")
ZOOM_SIDE = 96  # px of the tile shown zoomed 3x, at its centre and at its wrap corner


#: A photo its publisher made to tile is judged through a window of it: this share of each side, from this
#: share in (a plain window of a photo does not tile).
WINDOW, WINDOW_AT = 0.75, 0.1


def tileable_photos(folder: Path) -> set[str]:
    """The files ``SOURCES.md`` marks as made to tile by their publisher (its "Tileable" column says "yes"); for
    ``photos/full/`` (the 2048 px versions, listed in the folder above's ``SOURCES.md`` as "(+ full/)"), the folder
    above's."""
    sources = folder / "SOURCES.md"
    if not sources.is_file():
        sources = folder.parent / "SOURCES.md"
    if not sources.is_file():
        return set()
    out = set()
    for line in sources.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) > 2 and cells[2] == "yes":
            out.add(cells[0].split()[0])
    return out


def load_photo(path: Path, size: int, window: bool = False) -> np.ndarray:
    """The photo as an sRGB colour map in the network domain [-1, 1], its longest side at most ``size``;
    ``window``: a WINDOW share of each side of it, from WINDOW_AT in (see :data:`WINDOW`)."""
    from PIL import Image

    with Image.open(path) as im:
        im = im.convert("RGB")
        if window:
            w, h = im.size
            im = im.crop((round(w * WINDOW_AT), round(h * WINDOW_AT), round(w * (WINDOW_AT + WINDOW)),
                          round(h * (WINDOW_AT + WINDOW))))
        scale = size / max(im.size)
        if scale < 1:
            im = im.resize((max(1, round(im.size[0] * scale)), max(1, round(im.size[1] * scale))),
                           Image.Resampling.LANCZOS)
        return np.asarray(im, dtype=np.float32) / 127.5 - 1.0


def to_uint8(a: np.ndarray) -> np.ndarray:
    return np.clip(np.rint((a + 1.0) * 127.5), 0, 255).astype(np.uint8)


def product_tile(pixels: np.ndarray, gan: bool, preset: str, seed: int) -> tuple[np.ndarray, dict]:
    """The product's tile of a one-map stack and how it was made."""
    from seamless_usd.synthesis import MapInput, get_preset, make_tile
    from seamless_usd.synthesis.candidates import best_cut

    maps = [MapInput("color", pixels)]
    if gan:
        made = make_tile(maps, get_preset(preset), seed=seed)
        return made.maps["color"], {"kind": made.layout_kind, "gan": made.gan is not None,
                                    "candidates": made.lattice.get("candidates"),
                                    "difference_worst": made.lattice.get("difference_worst"),
                                    **({"levelled": made.levelled} if made.levelled else {}),
                                    **({"evened": made.evened} if made.evened else {})}
    cut, made_so = best_cut(maps, True, seed)  # as the product does: levelled or evened where no cut of it passes
    if cut.kind is None:
        raise ValueError("no tile can be cut from this photo")
    return cut.tiles["color"], {"kind": cut.kind, "gan": False, "candidates": cut.notes.get("candidates"),
                                "difference_worst": cut.figures.get("difference_worst"), "cut_passes": cut.passes,
                                **made_so}


def pictures(name: str, method: str, tile: np.ndarray, source: np.ndarray, folder: Path) -> None:
    """The 3 x 3 repeat beside the source at the same texel scale, and the centre and wrap corner zoomed 3x."""
    from PIL import Image

    folder.mkdir(parents=True, exist_ok=True)
    rep = np.tile(to_uint8(tile), (3, 3, 1))
    src = to_uint8(source)
    sheet = np.full((rep.shape[0], rep.shape[1] + 16 + src.shape[1], 3), 255, np.uint8)
    sheet[:, :rep.shape[1]] = rep
    sheet[:src.shape[0], rep.shape[1] + 16:] = src
    Image.fromarray(sheet).save(folder / f"{name}__{method}.jpg", quality=90)
    h, w = tile.shape[:2]
    s = min(ZOOM_SIDE, h, w)
    rolled = np.roll(to_uint8(tile), (s // 2, s // 2), (0, 1))  # the wrap corner in the crop's middle
    crops = [to_uint8(tile)[h // 2 - s // 2: h // 2 - s // 2 + s, w // 2 - s // 2: w // 2 - s // 2 + s], rolled[:s, :s]]
    zoom = np.concatenate([np.kron(c, np.ones((3, 3, 1), np.uint8)) for c in crops], axis=1)
    Image.fromarray(zoom).save(folder / f"{name}__{method}_zoom.png")


def _shown(path) -> str | None:
    """A path for the results: relative to the repository when inside it, else its last two parts."""
    if path is None:
        return None
    p = Path(path).resolve()
    try:
        return str(p.relative_to(HERE.parent))
    except ValueError:
        return str(Path(*p.parts[-2:]))


def run_photo(path: Path, a: argparse.Namespace, window: bool) -> dict:
    from seamless_usd.verdict import judge

    source = load_photo(path, a.size, window)
    row = {"photo": path.name, "size": list(source.shape[:2]), "window": window}
    for method in a.methods:
        t0 = time.perf_counter()
        try:
            if method == "seamless-usd":
                tile, info = product_tile(source, a.gan, a.preset, a.seed)
            elif method == "img2texture":
                tile, info = img2texture_tile(source), {}
            else:
                tile, synthesis_s = resynthesizer_tile(source, False, a.resynth_python, a.band)
                info = {"synthesis_s": round(synthesis_s, 2)}
        except Exception as exc:  # a peer that cannot make this photo is recorded, the run goes on
            row[method] = {"error": f"{type(exc).__name__}: {exc}"}
            continue
        seconds = time.perf_counter() - t0
        # a tile of another size (img2texture crops) is judged against the source as it is: the verdict
        # compares texel scales, not sizes; a tile cut from the photo with its light levelled or its lattice evened,
        # against the photo made so (as the product judges it)
        from seamless_usd.pipeline.madefrom import made_values

        against = made_values([source], [False], levelled=bool(info.get("levelled")),
                              evened=bool(info.get("evened")))[0]
        verdict = judge([tile], [against], [False], ["color"])
        # the product's status: the verdict, and for our cut whether its joins hide where they are gated (a mend of
        # long lines, a quilt): such a cut is never written as passed
        passed = verdict.passed and info.get("cut_passes", True)
        row[method] = {"passed": passed, "seamless": verdict.seamless, "faithful": verdict.faithful,
                       "strongest": round(verdict.strongest, 3), "margin": verdict.margin,
                       "reasons": verdict.reasons(2), "seconds": round(seconds, 2), "tile": list(tile.shape[:2]),
                       **info}
        if a.out:
            pictures(path.stem, method, tile, source, a.out / "tiles")
    return row


def markdown(rows: list[dict], a: argparse.Namespace, load: tuple[float, float]) -> str:
    lines = ["# Real photos made tileable", "",
             f"{len(rows)} photos (longest side at most {a.size} px), "
             f"{'cuts only' if not a.gan else 'with SeamlessGAN where no cut passes, preset ' + a.preset}; "
             f"load {load[0]:.2f} before, {load[1]:.2f} after. `passed` is the product's verdict on each tile "
             "against its source.", "",
             "| method | passed | of | median s |", "|---|---:|---:|---:|"]
    for m in a.methods:
        done = [r[m] for r in rows if m in r and "error" not in r[m]]
        sec = float(np.median([d["seconds"] for d in done])) if done else float("nan")
        lines.append(f"| {m} | {sum(d['passed'] for d in done)} | {len(done)} | {sec:.2f} |")
    lines += ["", "| photo | size | " + " | ".join(a.methods) + " |", "|---|---|" + "---|" * len(a.methods)]
    for r in rows:
        cells = []
        for m in a.methods:
            d = r.get(m, {})
            if "error" in d:
                cells.append("error")
                continue
            extra = f" {d['kind']}" if "kind" in d else ""
            if d.get("difference_worst") is not None:
                extra += f" d={d['difference_worst']:.3f}"
            if d.get("levelled"):
                extra += f" levelled {100 * d['levelled']['moved']:.0f} %"
            if d.get("evened"):
                extra += f" evened {d['evened']['moved']:.1f} px"
            cells.append(f"{'passed' if d['passed'] else 'not passed'} {d['strongest']:.2f}{extra}, {d['seconds']:.1f} s")
        name = r["photo"] + (" (window)" if r.get("window") else "")
        lines.append(f"| {name} | {r['size'][1]}x{r['size'][0]} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--photos", type=Path, default=PHOTOS)
    p.add_argument("--size", type=int, default=512, help="longest side (px) the photos are brought down to")
    p.add_argument("--methods", default=",".join(METHODS))
    p.add_argument("--gan", action="store_true", help="train SeamlessGAN where no cut passes (minutes a photo)")
    p.add_argument("--preset", default="default")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--resynth-python", help="the Python of an environment holding PyPI resynthesizer (default: "
                                            "RESYNTH_PYTHON)")
    p.add_argument("--band", type=float, default=0.15, help="Resynthesizer's band over each seam, a share of the side")
    p.add_argument("--only", help="comma-separated photo names (stems) to run")
    p.add_argument("--out", type=Path, default=HERE / "results" / "photos")
    a = p.parse_args(argv)
    a.methods = [m for m in a.methods.split(",") if m]
    unknown = set(a.methods) - set(METHODS)
    if unknown:
        p.error(f"unknown methods {sorted(unknown)}; valid: {', '.join(METHODS)}")
    a.resynth_python = a.resynth_python or os.environ.get("RESYNTH_PYTHON")
    if "resynthesizer" in a.methods and not a.resynth_python:
        a.methods.remove("resynthesizer")
        print("resynthesizer left out: pass --resynth-python (see benchmarks/peers/resynthesizer_tile.py)")
    paths = sorted(q for q in a.photos.iterdir() if q.suffix.lower() in (".jpg", ".jpeg", ".png"))
    if a.only:
        keep = set(a.only.split(","))
        paths = [q for q in paths if q.stem in keep]
    if not paths:
        raise SystemExit(f"error: no photos in {a.photos}")
    load0 = os.getloadavg()[0]
    rows, made_to_tile = [], tileable_photos(a.photos)
    for i, path in enumerate(paths):
        row = run_photo(path, a, path.name in made_to_tile)
        rows.append(row)
        print(f"[{i + 1}/{len(paths)}] {path.name}: " + ", ".join(
            f"{m} {'error' if 'error' in row[m] else ('passed' if row[m]['passed'] else 'not passed')}"
            for m in a.methods if m in row), flush=True)
    load = (load0, os.getloadavg()[0])
    # paths as the settings name them, never the machine's: the repository's own relative to it, others by name
    data = {"settings": {k: (_shown(v) if isinstance(v, Path) or k == "resynth_python" else v)
                         for k, v in vars(a).items()},
            "load": load, "rows": rows}
    page, _ = write_results(a.out, "photos", markdown(rows, a, load), data)
    print(page.read_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
