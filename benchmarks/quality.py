#!/usr/bin/env python3
"""Quality benchmark: are the tiles seamless, and faithful to the source?

For every map of a set of real texture stacks, and for each method (SeamlessGAN trained with a
preset, and the ``naive`` and ``crossfade`` baselines of ``benchmarks/baselines.py``), computes
the metrics of :mod:`seamless_usd.metrics` (seam ratios, periodic-plus-smooth score, detail
ratios, SSIM and Gram distance to the source), and writes:

- ``<out>/quality.json``: every figure, with the run's settings;
- ``<out>/quality.md``: the same as Markdown tables, with the targets (`seamless_usd.metrics.TARGETS`) checked;
- ``<out>/tiles/<stack>__<map>__<method>.jpg``: the 2x2 tiling of the method's tile (left) beside
  the naive 2x2 tiling of the input (right), for every method but ``naive``.

Stacks: the bundled samples (``brick``, ``wood``, ``cloth``) and windows of the MaterialX images in
``../shared/textures`` (``mx_*``; ``--textures-dir`` overrides the folder), defined in
``benchmarks/stacks.py``. The tables are written by ``benchmarks/quality_md.py``.

Run from anywhere, e.g.::

    .venv/bin/python benchmarks/quality.py --preset default
    .venv/bin/python benchmarks/quality.py --methods naive,crossfade   # baselines only, seconds
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import time
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
if str(HERE) not in sys.path:  # the baselines sit beside this script
    sys.path.insert(0, str(HERE))

from methods import (SYNTHESIS_METHODS, MethodResult, img2texture_tile, preset_config, resynthesizer_tile,  # noqa: E402
                     run_synthesis, to_source_grid)
from baselines import BASELINES  # noqa: E402
from quality_md import TARGETS, fmt, to_markdown  # noqa: E402,F401 (re-exported)
from pictures import PICTURE_MAX, crops, side_by_side, write_picture  # noqa: E402,F401 (re-exported)
from results_io import write_results  # noqa: E402
from stacks import (FULLRES_STACKS, QUALITY_STACKS, SHARED_DIR, STACKS, MapFile, StackSpec,  # noqa: E402,F401
                    load_stack)

from seamless_usd import metrics as M  # noqa: E402
from seamless_usd.synthesis.lattice.cut import find_lattice, lattice_ratio  # noqa: E402
from seamless_usd.verdict.joins import inside_figures  # noqa: E402

__all__ = [
    "MapFile",
    "StackSpec",
    "STACKS",
    "METHODS",
    "TARGETS",
    "load_stack",
    "run",
    "main",
]

DEFAULT_OUT = HERE / "results"
#: Methods by name, in the order the tables list them.
METHODS: tuple[str, ...] = (*SYNTHESIS_METHODS, "img2texture", "resynthesizer", *BASELINES)

def _log(line: str) -> None:
    print(line, flush=True)  # flushed: long runs are often watched through a redirected file


# --------------------------------------------------------------------------------------------
# Methods
# --------------------------------------------------------------------------------------------


def run_baseline(name: str, stack: dict[str, tuple[np.ndarray, bool]]) -> MethodResult:
    """Apply baseline ``name`` to every map of a stack."""
    fn = BASELINES[name]
    t0 = time.perf_counter()
    tiles = {k: fn(px, is_normal) for k, (px, is_normal) in stack.items()}
    return MethodResult(tiles, time.perf_counter() - t0)


def _jsonable(v):
    if isinstance(v, (np.generic,)):
        return v.item()
    if isinstance(v, tuple):
        return [_jsonable(x) for x in v]
    return v


def default_features() -> tuple[Callable | None, str]:
    """The synthesis engine's default style feature extractor as a numpy callable, and a note.

    It is the seeded random multi-scale CNN that ``SynthesisConfig()``'s defaults build
    (``style_features="random"`` with the default scales, channels and seed), whatever the preset,
    so Gram distances compare across presets and methods. Maps go in as the engine feeds them
    (``to_rgb_batch``: grey repeated, two channels padded, RGBA as RGB + AAA). Returns
    ``(None, reason)`` when torch or the engine is not available; the Gram distance is then
    ``null``.
    """
    try:
        import torch

        from seamless_usd.synthesis.config import SynthesisConfig
        from seamless_usd.synthesis.gan.features import build_feature_extractor, to_rgb_batch
    except ImportError as exc:
        return None, f"Gram distance left out: {exc}"
    config = SynthesisConfig()
    net = build_feature_extractor(config).eval()

    def features(img: np.ndarray) -> list[np.ndarray]:
        x = torch.from_numpy(np.ascontiguousarray(np.moveaxis(img, -1, 0), dtype=np.float32))[None]  # (1, C, H, W)
        with torch.no_grad():
            feats = net(to_rgb_batch(x))  # [(N, K, h, w)], N = 2 for RGBA
        return [f[i].float().numpy() for f in feats for i in range(f.shape[0])]

    note = (
        "Gram distance: mean over layers of ||G(tile) - G(source)|| / ||G(source)|| with the synthesis "
        f"engine's default random feature extractor ({config.style_scales} scales x "
        f"{config.style_channels} channels, seed {config.style_seed}), tile repeated to the source's size"
    )
    return features, note


# --------------------------------------------------------------------------------------------
# The run
# --------------------------------------------------------------------------------------------


def inner_figures(res: MethodResult, stack: dict[str, tuple[np.ndarray, bool]]) -> dict[str, dict]:
    """Per map, what lies inside the tile (``seamless_usd.verdict.joins.inside_figures``): bad joins, the copies'
    coherence and the structure figure, against the source on the tile's texel grid."""
    names = list(stack)
    refs = [res.references[k] if res.references else stack[k][0] for k in names]
    figures = inside_figures([res.tiles[k] for k in names], refs, [stack[k][1] for k in names], names)
    return dict(zip(names, figures))


def _round(v):
    """4 decimals; None for a missing or infinite figure (JSON has no infinity)."""
    return None if v is None or not np.isfinite(v) else round(float(v), 4)


def run(
    stacks: Sequence[str],
    methods: Sequence[str],
    *,
    preset: str = "default",
    seed: int = 0,
    overrides: dict | None = None,
    out: Path = DEFAULT_OUT,
    textures_dir: Path = SHARED_DIR,
    max_size: int | None = None,
    gram: bool = True,
    pictures: bool = True,
    log: Callable[[str], None] = _log,
    command: str | None = None,
    update: bool = False,
    crops_too: bool = False,
) -> dict:
    """Run the benchmark and write ``quality.json``, ``quality.md`` and the pictures.

    ``update`` keeps the rows of the other methods from the ``quality.json`` already in ``out``, so
    one method can be re-run (a preset changed) while the rest of the table stands.

    Returns
    -------
    dict
        The content of ``quality.json``.
    """
    features, gram_note = default_features() if gram else (None, "Gram distance left out (--no-gram)")
    log(gram_note)
    rows: list[dict] = []
    notes: list[str] = [gram_note]
    result = {
        "settings": {
            "command": command,
            "preset": preset if set(methods) & set(SYNTHESIS_METHODS) else None,
            "seed": seed,
            "stacks": {},  # filled as stacks finish
            "methods": list(methods),
            "max_size": max_size,
            "domain": "network domain: 2 v - 1 of file values v in [0, 1]; normal maps as vectors",
            "band_fraction": M.BAND_FRACTION,
            "highpass_sigma": M.HIGHPASS_SIGMA,
            "python": platform.python_version(),
            "numpy": np.__version__,
        },
        "targets": [{"metric": k, "op": op, "value": v} for k, op, v in TARGETS],
        "notes": notes,
        "results": rows,
        "complete": False,
    }
    if set(methods) & set(SYNTHESIS_METHODS):  # presets are tuned over time: keep what this run used
        config = preset_config(preset, overrides)
        result["settings"]["preset_config"] = json.loads(config.to_json())
    kept: list[dict] = []
    if update and (out / "quality.json").exists():
        previous = json.loads((out / "quality.json").read_text())
        kept = [r for r in previous["results"] if r["method"] not in methods or r["stack"] not in stacks]
        others = {r["method"] for r in kept}
        result["settings"]["methods"] = [m for m in METHODS if m in others or m in methods]
        result["settings"]["command"] = (f"{command} (rows of {', '.join(methods)} on {', '.join(stacks)}; "
                                         f"the other rows from {previous['settings'].get('command')})")
        for key in ("preset", "preset_config"):
            result["settings"].setdefault(key, previous["settings"].get(key))
        result["settings"]["stacks"] = dict(previous["settings"].get("stacks", {}))
    order = {m: i for i, m in enumerate(METHODS)}
    stack_order = {n: i for i, n in enumerate(STACKS)}

    def merged() -> None:  # the kept rows and this run's, in stack then method order
        result["results"] = sorted(kept + rows, key=lambda r: (stack_order.get(r["stack"], 99), order[r["method"]]))
    for stack_name in stacks:
        stack = load_stack(stack_name, textures_dir, max_size)
        result["settings"]["stacks"][stack_name] = STACKS[stack_name].note
        synthesis = [m for m in methods if m in SYNTHESIS_METHODS]
        if synthesis:
            log(f"{stack_name}: {', '.join(synthesis)} ...")
            made = run_synthesis(stack, synthesis, preset, seed, log, overrides)
        source_lattice = find_lattice([px for px, _ in stack.values()])
        for method in methods:
            log(f"{stack_name}: {method} ...")
            if method in SYNTHESIS_METHODS and method not in made:
                log(f"  {method}: not applicable to {stack_name}")
                continue
            if method in SYNTHESIS_METHODS:
                res = made[method]
            elif method == "img2texture":
                t0 = time.perf_counter()
                res = MethodResult({k: img2texture_tile(px, n) for k, (px, n) in stack.items()}, time.perf_counter() - t0)
            elif method == "resynthesizer":  # each map on its own: the peer cannot keep a stack aligned
                made_maps = {k: resynthesizer_tile(px, n) for k, (px, n) in stack.items()}
                res = MethodResult({k: t for k, (t, _) in made_maps.items()}, sum(s for _, s in made_maps.values()),
                                   {"synthesis_s": round(sum(s for _, s in made_maps.values()), 2)})
            else:
                res = run_baseline(method, stack)
            refs = [res.references[k] if res.references else px for k, (px, _) in stack.items()]  # same grid
            ratio = lattice_ratio([res.tiles[k] for k in stack], refs,
                                  find_lattice(refs) if res.references else source_lattice)
            inner = inner_figures(res, stack)
            for map_name, (src_full, is_normal) in stack.items():
                tile = res.tiles[map_name]
                src = res.references[map_name] if res.references else src_full  # same texel scale
                m = M.map_metrics(tile, src, is_normal, features=features)
                m.update(inner[map_name])
                row = {
                    "stack": stack_name,
                    "map": map_name,
                    "method": method,
                    "is_normal": is_normal,
                    "source_size": list(src.shape[:2]),
                    "tile_size": list(tile.shape[:2]),
                    **{k: _round(v) for k, v in m.items()},
                    "seconds": round(res.seconds, 2),
                    "peak_rss_gib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2 ** 20, 2),  # so far
                    "lattice_ratio": _round(ratio),  # the stack's, on every map's row
                    **res.info,
                }
                rows.append(row)
                if pictures and method != "naive":
                    name = f"{stack_name}__{map_name}__{method}.jpg"
                    shown = to_source_grid(tile, src, src_full)
                    write_picture(out / "tiles" / name, side_by_side(shown, src_full, is_normal))
                    row["picture"] = f"tiles/{name}"
                    if crops_too or max(src_full.shape[:2]) > PICTURE_MAX:  # texels as they are, 1x and 3x
                        for zoom in (1, 3):
                            crop = f"{stack_name}__{map_name}__{method}__{zoom}x.jpg"
                            write_picture(out / "tiles" / crop, crops(shown, src_full, is_normal, zoom))
                            row[f"crop_{zoom}x"] = f"tiles/{crop}"
                log(
                    f"  {map_name:<10} scale {fmt(m['scale_ratio'])}  patch {fmt(m['patch_distance'])}  "
                    f"seam x {m['seam_ratio_x']:.2f} y {m['seam_ratio_y']:.2f}  "
                    f"centre x {m['centre_seam_x']:.2f} y {m['centre_seam_y']:.2f}  "
                    f"p+s {m['ps_score']:.3f}  detail {m['detail_ratio']:.2f}  ssim {m['ssim']:.3f}"
                )
        merged()
        # after every stack, so a long run leaves its figures as it goes
        write_results(out, "quality", to_markdown(result), result, end="\n")
    result["complete"] = True
    merged()
    page, figures = write_results(out, "quality", to_markdown(result), result, end="\n")
    log(f"wrote @{page}@ and @{figures}@")
    return result


def _names(text: str, valid: Sequence[str], what: str) -> list[str]:
    names = [n.strip() for n in text.split(",") if n.strip()]
    bad = [n for n in names if n not in valid]
    if bad or not names:
        raise SystemExit(f"unknown {what} {', '.join(bad) or '(none)'}; valid: {', '.join(valid)}")
    return names


def main(argv: Sequence[str] | None = None) -> int:
    """Command line entry; returns the exit code."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--preset", default="default", help="SeamlessGAN preset (default: %(default)s)")
    p.add_argument("--stacks", default=None, help=f"comma-separated, from: {', '.join(STACKS)}; or 'fullres' for the full-resolution set "
                   f"({', '.join(FULLRES_STACKS)}) (default: {', '.join(QUALITY_STACKS)}, where available)")
    p.add_argument("--methods", default=",".join(METHODS), help=f"comma-separated, from: {', '.join(METHODS)} (default: all)")
    p.add_argument("--seed", type=int, default=0, help="training and sampling seed (default: %(default)s)")
    p.add_argument("--iterations", type=int, default=None,
                   help="override the preset's training iterations (quality-vs-time curves)")
    p.add_argument("--batch", type=int, default=None, help="override the preset's crops per training step")
    p.add_argument("--seeds", type=int, default=None, help="override the preset's seeds trained side by side")
    p.add_argument("--upsample", choices=("transposed", "resize"), default=None,
                   help="override the preset's decoder upsampling")
    p.add_argument("--style-every", type=int, default=None, help="override the preset's steps per style-loss step")
    p.add_argument("--d-every", type=int, default=None, help="override the preset's steps per discriminator step")
    p.add_argument("--update", action="store_true",
                   help="keep the rows of other methods and other stacks of the quality.json already in --out "
                        "(re-run some methods or stacks only)")
    p.add_argument("--out", type=Path, default=DEFAULT_OUT, help="output folder (default: benchmarks/results)")
    p.add_argument("--textures-dir", type=Path, default=SHARED_DIR, help="MaterialX images for the mx_* stacks (default: ../shared/textures from the repository root)")
    p.add_argument("--max-size", type=int, default=None, help="downscale inputs to at most this many px (quick runs)")
    p.add_argument("--threads", type=int, default=None, help="torch CPU threads for SeamlessGAN (default: torch's choice)")
    p.add_argument("--no-gram", action="store_true", help="leave out the Gram distance (no torch needed)")
    p.add_argument("--no-pictures", action="store_true", help="do not write the 2x2 PNGs")
    p.add_argument("--crops", action="store_true",
                   help="also write 1x and 3x crops of the texels for stacks of any size (always above 768 px)")
    p.add_argument("--resynth-python", help="the Python of an environment holding PyPI resynthesizer, for the "
                                            "resynthesizer method (default: RESYNTH_PYTHON; without either, left out)")
    a = p.parse_args(argv)
    methods = _names(a.methods, METHODS, "method")
    if a.resynth_python:
        os.environ["RESYNTH_PYTHON"] = a.resynth_python
    if "resynthesizer" in methods and not os.environ.get("RESYNTH_PYTHON"):
        methods.remove("resynthesizer")
        print("note: resynthesizer left out (pass --resynth-python; see benchmarks/peers/resynthesizer_tile.py)",
              file=sys.stderr)
    if a.stacks is None:
        stacks = [n for n in QUALITY_STACKS if STACKS[n].folder == "samples" or a.textures_dir.is_dir()]
        if len(stacks) < len(QUALITY_STACKS):
            print(f"note: @{a.textures_dir}@ not found; running the sample stacks only", file=sys.stderr)
    else:
        stacks = list(FULLRES_STACKS) if a.stacks == "fullres" else _names(a.stacks, list(STACKS), "stack")
        if not a.textures_dir.is_dir() and any(STACKS[n].folder == "shared" for n in stacks):
            print(
                f"error: the mx_* stacks need the MaterialX images in @{a.textures_dir}@ "
                "(see ../shared/textures/README.md); pass --textures-dir or leave them out",
                file=sys.stderr,
            )
            return 2
    if a.threads is not None:
        import torch

        torch.set_num_threads(max(1, a.threads))
    if set(methods) & set(SYNTHESIS_METHODS):
        try:
            from seamless_usd.synthesis import get_preset

            get_preset(a.preset)
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
    try:
        run(
            stacks,
            methods,
            preset=a.preset,
            seed=a.seed,
            overrides={"iterations": a.iterations, "batch": a.batch, "seeds": a.seeds, "upsample": a.upsample,
                       "style_every": a.style_every, "d_every": a.d_every},
            out=a.out,
            textures_dir=a.textures_dir,
            max_size=a.max_size,
            gram=not a.no_gram,
            pictures=not a.no_pictures,
            crops_too=a.crops,
            command=" ".join(["benchmarks/quality.py", *(sys.argv[1:] if argv is None else argv)]),
            update=a.update,
        )
    except (FileNotFoundError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
