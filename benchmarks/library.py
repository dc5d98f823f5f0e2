#!/usr/bin/env python3
"""Library benchmark: wall time of `process` on a synthetic material library, per executor.

Builds a library of N materials (stage files) whose stacks repeat (several files share the same
textures, as material libraries do), then times, each in a fresh cache:

- ``inprocess``: one stack after another in the client, all cores per stack;
- ``local:2`` (or ``--schedulers``): a Dask LocalCluster, one thread per worker;
- then, per scheduler, the same run again on its warm cache (nothing trains; the client finds every
  stack in the cache before starting any executor, so no cluster is started): its wall time as a
  fraction of the cold run is the ``warm / cold`` column (target: at most 10 % for ``local:2``).

It prints a Markdown table and writes ``benchmarks/results/library.md`` / ``.json``, with the
stacks trained, the peak memory per worker process, and the host's load during the run (this
machine is often shared, which the figures must be read against).

    .venv/bin/python benchmarks/library.py --materials 20 --unique 6 --preset draft --max-size 128
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
if str(REPO / "benchmarks") not in sys.path:  # results_io sits beside this script
    sys.path.insert(0, str(REPO / "benchmarks"))

from results_io import write_results  # noqa: E402

SCENE = """#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World"
{{
    def Scope "Looks"
    {{
        def Material "M{n}"
        {{
            token outputs:surface.connect = </World/Looks/M{n}/Surface.outputs:surface>
            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/M{n}/Color.outputs:rgb>
                float inputs:roughness.connect = </World/Looks/M{n}/Rough.outputs:r>
                token outputs:surface
            }}
            def Shader "St"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}
            def Shader "Color"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/{color}@
                float2 inputs:st.connect = </World/Looks/M{n}/St.outputs:result>
                float3 outputs:rgb
            }}
            def Shader "Rough"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/{rough}@
                token inputs:sourceColorSpace = "raw"
                float2 inputs:st.connect = </World/Looks/M{n}/St.outputs:result>
                float outputs:r
            }}
        }}
    }}
}}
"""

# (colour, roughness) pairs from the sample textures; each pair is one unique stack.
PAIRS = [
    ("brick_albedo.png", "brick_roughness.png"),
    ("wood_color.png", "wood_roughness.png"),
    ("cloth.png", "brick_roughness.png"),
    ("brick_albedo.png", "wood_roughness.png"),
    ("wood_color.png", "brick_roughness.png"),
    ("cloth.png", "wood_roughness.png"),
    ("brick_albedo.png", "brick_roughness16.png"),
    ("wood_color.png", "brick_roughness16.png"),
]


def build_library(root: Path, materials: int, unique: int) -> Path:
    lib = root / "library"
    shutil.copytree(REPO / "sample_assets" / "textures", lib / "textures")
    for n in range(materials):
        color, rough = PAIRS[n % unique]
        folder = lib / f"mat{n:03d}"
        folder.mkdir()
        (folder / "material.usda").write_text(SCENE.format(n=0, color=color, rough=rough))
    return lib


def _loadavg() -> float:
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


def timed_run(lib: Path, cache: Path, preset: str, max_size: int | None, scheduler: str | None) -> dict:
    from seamless_usd import Options, process_paths

    for p in lib.rglob("*.seamless.usda"):
        p.unlink()
    for d in lib.rglob("tileable"):
        shutil.rmtree(d)
    options = Options(preset=preset, cache_dir=cache, max_size=max_size, scheduler=scheduler)
    load_before = _loadavg()
    t0 = time.perf_counter()
    report = process_paths([lib], options)
    wall = time.perf_counter() - t0
    counts = report.counts()
    rss = [s.peak_rss_mb for s in report.stacks if s.origin in ("trained", "cache")]
    return {
        "scheduler": scheduler or "inprocess",
        "wall_s": round(wall, 1),
        "exit_code": report.exit_code,
        "files": len(report.sources),
        "stacks": len(report.stacks),
        "trained": counts["trained"],
        "from_cache": counts["from_cache"],
        "reused": counts["reused"],
        "failed": counts["failed"],
        "peak_rss_mb_per_worker": round(max(rss), 1) if rss else None,
        "load_avg_1min": [round(load_before, 2), round(_loadavg(), 2)],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--materials", type=int, default=20)
    parser.add_argument("--unique", type=int, default=6, help=f"unique stacks (at most {len(PAIRS)})")
    parser.add_argument("--preset", default="draft")
    parser.add_argument("--max-size", type=int, default=128)
    parser.add_argument("--schedulers", default="inprocess,local:2")
    parser.add_argument("--out", type=Path, default=REPO / "benchmarks" / "results")
    args = parser.parse_args(argv)
    assert 1 <= args.unique <= len(PAIRS), f"--unique must be 1..{len(PAIRS)}"
    rows = []
    with tempfile.TemporaryDirectory(prefix="seamless-library-") as tmp:
        lib = build_library(Path(tmp), args.materials, args.unique)
        for name in args.schedulers.split(","):
            cache = Path(tmp) / f"cache-{name.replace(':', '-')}"
            scheduler = None if name == "inprocess" else name
            row = timed_run(lib, cache, args.preset, args.max_size, scheduler)
            rows.append(row)
            print(json.dumps(row), flush=True)
            warm = timed_run(lib, cache, args.preset, args.max_size, scheduler)
            warm["scheduler"] = f"{name}, warm cache"
            warm["warm_over_cold"] = round(warm["wall_s"] / row["wall_s"], 3) if row["wall_s"] else None
            rows.append(warm)
            print(json.dumps(warm), flush=True)
    header = ("| run | wall (s) | warm / cold | files | stacks | trained | from cache | reused | failed | "
              "peak RSS / worker (MB) | load avg before/after |")
    lines = [
        f"# Library benchmark\n\n{args.materials} materials in {args.materials} files, {args.unique} unique stacks "
        f"(colour + roughness, {args.max_size or 'native'} px), preset `{args.preset}`, {os.cpu_count()} cores.\n",
        header,
        "|" + "---|" * 11,
    ]
    for r in rows:
        lines.append(
            f"| {r['scheduler']} | {r['wall_s']} | {r.get('warm_over_cold', '')} | {r['files']} | {r['stacks']} | {r['trained']} | {r['from_cache']} | "
            f"{r['reused']} | {r['failed']} | {r['peak_rss_mb_per_worker']} | {r['load_avg_1min'][0]} / {r['load_avg_1min'][1]} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    recorded = {k: str(v) for k, v in vars(args).items()}
    if args.out.resolve().is_relative_to(REPO):
        recorded["out"] = str(args.out.resolve().relative_to(REPO))  # no machine paths in results
    write_results(args.out, "library", text, {"args": recorded, "runs": rows}, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
