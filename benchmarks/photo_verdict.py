"""The verdict on real photos judged on their own, exactly as ``seamless-usd check`` judges a picture.

The photos are ``benchmarks/photos`` (see its ``SOURCES.md``): textures their publishers made to tile (Poly
Haven, ambientCG), and photos and crops that do not tile. Each variant is written as an 8-bit PNG at the
photo's size and judged from that file by :func:`seamless_usd.verdict.alone.judge_alone`, the reading and rule
``check`` and the scan's ``already-tileable`` share.

Seamless (only from photos made to tile)
    ``whole``      the file as published;
    ``rolled``     rolled by a third and a fifth;
    ``turned``     turned 90 degrees, then rolled.
Seamed
    ``whole``      a photo that does not tile, as it is;
    ``window``     a plain window (75 % of each side, from 10 % in) of any photo;
    ``half-roll``  that window rolled by half: its wrap is clean, its seams run through the middle.

The 2048 px versions in ``full/`` (four photos made to tile) are added the same way, written as 16-bit PNGs.

Split: the *tuning* part (:data:`TUNING`: four structured textures made to tile and four others) is what a
rule may be tuned on; the rest is *held back*.

    .venv/bin/python benchmarks/photo_verdict.py            # 33 photos, about 2 minutes
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from photos import PHOTOS, WINDOW, WINDOW_AT, tileable_photos  # noqa: E402
from results_io import write_results  # noqa: E402
from texture_verdict import heading, share_table, table  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
TUNING = frozenset({"tiles_floor_white_1", "tiles_marble_slabs_1", "metal_plate_1", "wood_table_worn_1",
                    "fruit_berries_1", "gravel_1", "sand_damp_1", "grass_sparse_1"})


def variants(pixels: np.ndarray, tileable: bool) -> list[tuple[str, bool, np.ndarray]]:
    """(kind, seamless, pixels) of one photo (``(H, W, 3)`` uint8)."""
    h, w = pixels.shape[:2]
    window = pixels[round(h * WINDOW_AT):round(h * (WINDOW_AT + WINDOW)),
                    round(w * WINDOW_AT):round(w * (WINDOW_AT + WINDOW))]
    out = [("whole", tileable, pixels)]
    if tileable:
        out += [("rolled", True, np.roll(pixels, (h // 3, w // 5), (0, 1))),
                ("turned", True, np.roll(np.rot90(pixels), (w // 5, h // 3), (0, 1)))]
    out += [("window", False, window),
            ("half-roll", False, np.roll(window, (window.shape[0] // 2, window.shape[1] // 2), (0, 1)))]
    return out


def judged(pixels: np.ndarray, folder: Path, name: str, bits: int = 8) -> tuple:
    """(seamed, strongest - margin, seconds, where) of ``pixels`` (uint8) written as an 8- or 16-bit PNG and judged
    as ``check`` does."""
    import OpenImageIO as oiio

    from seamless_usd.verdict.alone import FileMap, judge_alone

    path = folder / f"{name}.png"
    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(w, h, c, oiio.UINT8 if bits == 8 else oiio.UINT16))
    out.write_image(np.ascontiguousarray(pixels if bits == 8 else pixels.astype(np.uint16) * 257))
    out.close()
    t0 = time.perf_counter()
    v, _ = judge_alone([FileMap(str(path))])
    where = v.seams[0].where(v.size) if v.seams else ""
    return (not v.seamless, round(v.strongest - v.margin, 3), round(time.perf_counter() - t0, 3), where)


def markdown(rows: list[dict], shares: list[dict], seconds: float, load: float) -> str:
    lines = [*heading("Real photos judged on their own", "`benchmarks/photo_verdict.py` on `benchmarks/photos`",
                      len(rows), seconds, load), *share_table(shares, rules=False)]
    lines += ["", "| picture | part | label | verdict | strongest - margin | first seam |", "|---|---|---|---|---:|---|"]
    for r in rows:
        seamed, figure, _, where = r["rules"]["verdict"]
        right = seamed != r["seamless"]
        call = "seamed" if seamed else "seamless"
        lines.append(f"| {r['name']} | {r['split']} | {'seamless' if r['seamless'] else 'seamed'} | "
                     f"{call if right else f'**{call}** (wrong)'} | {figure:+.2f} | {where} |")
    times = sorted(r["rules"]["verdict"][2] for r in rows)
    lines += ["", f"The verdict took {np.median(times):.2f} s per picture (median), {times[-1]:.2f} s at most, "
                  "reading from the file."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    from PIL import Image

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--photos", type=Path, default=PHOTOS)
    ap.add_argument("--out", type=Path, default=RESULTS)
    a = ap.parse_args(argv)
    made_to_tile = tileable_photos(a.photos)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    rows = []
    photos = [(p, 8, "") for p in sorted(a.photos.glob("*.jpg"))]
    photos += [(p, 16, "-2048") for p in sorted((a.photos / "full").glob("*.jpg"))]  # full size, as 16-bit files
    with tempfile.TemporaryDirectory() as tmp:
        for path, bits, tag in photos:
            with Image.open(path) as im:
                pixels = np.asarray(im.convert("RGB"))
            split = "tuning" if path.stem in TUNING else "held-back"
            for kind, seamless, px in variants(pixels, path.name in made_to_tile):
                name = f"{path.stem}{tag}-{kind}"
                r = {"verdict": judged(px, Path(tmp), name, bits)}
                rows.append({"name": name, "photo": path.name, "kind": kind, "split": split, "seamless": seamless,
                             "size": list(px.shape[:2]), "rules": r})
                print(f"{name:40s} {'seamless' if seamless else 'seamed  '} {'S' if r['verdict'][0] else '-'} "
                      f"{r['verdict'][1]:+.2f} {r['verdict'][3]}", flush=True)
    shares = table(rows)
    seconds = time.perf_counter() - t0
    md, _ = write_results(a.out, "photo_verdict", markdown(rows, shares, seconds, load),
                          {"items": rows, "shares": shares, "seconds": round(seconds, 1), "load": load})
    for s in shares:
        print(f"{s['part']:10s} seamless {100 * s['seamless_right']:5.1f} %  seamed {100 * s['seamed_right']:5.1f} %")
    print(md)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
