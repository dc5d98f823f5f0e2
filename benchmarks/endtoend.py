#!/usr/bin/env python3
"""The product end to end at full resolution: ``seamless-usd process`` on a scene whose maps are N px.

Builds a one-material scene (UsdPreviewSurface: base colour sRGB, normal raw with scale 2 / bias -1,
roughness raw) from the MaterialX brick images in ``../shared/textures`` (2048 px; larger sizes are
the image resized with Lanczos, which keeps memory and time right but adds no detail), runs the CLI
in a child process with a cold cache, a report and ``--json``, and prints the wall time, the child's
peak resident memory, the status and the per-stage timings the report records.

    .venv/bin/python benchmarks/endtoend.py --size 4096 --preset default --out /tmp/endtoend
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
TEXTURES = HERE.parent.parent / "shared" / "textures"
if str(HERE.parent / "sample_assets") not in sys.path:  # the scene builders of the sample assets
    sys.path.insert(0, str(HERE.parent / "sample_assets"))
MAPS = (("brick_base_gray", "diffuseColor", "sRGB"), ("brick_normal", "normal", "raw"),
        ("brick_roughness", "roughness", "raw"))


def build_scene(folder: Path, size: int, textures: Path = TEXTURES) -> Path:
    """The maps written at ``size`` px beside a scene made with the sample assets' builders: a plane whose
    UVs span one period, bound to a UsdPreviewSurface reading them (the normal map with scale 2, bias -1)."""
    import OpenImageIO as oiio
    from pxr import Gf, Sdf, UsdShade

    from usdkit import bind, new_layer, plane, preview_material

    folder.mkdir(parents=True, exist_ok=True)
    for name, _, _ in MAPS:
        buf = oiio.ImageBuf(str(textures / f"{name}.jpg"))
        if buf.spec().width != size:
            buf = oiio.ImageBufAlgo.resize(buf, "lanczos3", roi=oiio.ROI(0, size, 0, size, 0, 1, 0, buf.nchannels))
        if not buf.write(str(folder / f"{name}_{size}.png"), "uint8"):
            raise SystemExit(f"error: cannot write @{folder / name}_{size}.png@: {buf.geterror()}")
    stage = new_layer(folder / "scene.usda", "World")
    stage.DefinePrim("/World", "Xform")
    look = "/World/Looks/Brick"
    bind(plane(stage, "/World/Wall", 4.0, 1.0, cells=1).GetPrim(), look)
    preview_material(stage, look, {role: (f"./{name}_{size}.png", "r" if role == "roughness" else "rgb", space)
                                   for name, role, space in MAPS})
    normal = UsdShade.Shader(stage.GetPrimAtPath(f"{look}/normalTex"))
    normal.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(2, 2, 2, 1))
    normal.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(Gf.Vec4f(-1, -1, -1, 0))
    stage.Save()
    return folder / "scene.usda"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--size", type=int, default=4096)
    p.add_argument("--preset", default="default")
    p.add_argument("--out", type=Path, required=True, help="folder for the scene, cache, tiles and report")
    a = p.parse_args(argv)
    scene = build_scene(a.out, a.size)
    exe = Path(sys.executable).with_name("seamless-usd")
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    # --force: the whole brick tiles, so the scan would leave it alone as already tileable; this measures the stack
    # processed end to end
    done = subprocess.run([str(exe), "process", str(scene), "--force", "--preset", a.preset, "--cache-dir",
                           str(a.out / "cache"), "--report", str(a.out / "report.html"), "--json"],
                          capture_output=True, text=True)
    wall = time.perf_counter() - t0
    peak_gib = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 2 ** 20  # KiB on Linux
    if done.returncode not in (0, 1):
        print(done.stderr[-3000:], file=sys.stderr)
        return done.returncode
    report = json.loads(done.stdout)
    stack = report["stacks"][0]
    verdict = stack["verdict"]
    print(json.dumps({"size": a.size, "preset": a.preset, "wall_s": round(wall, 1), "peak_gib": round(peak_gib, 2),
                      "load_at_start": round(load, 2), "load_at_end": round(os.getloadavg()[0], 2),
                      "exit_code": done.returncode, "status": stack["status"], "tile": stack.get("tile_size"),
                      "layout": (stack["resampled"].get("gan") or {}).get("layout"),
                      "seams": len(verdict.get("seams", [])),
                      "failing": verdict.get("failing", []),
                      "timings_s": {k: round(v, 1) for k, v in stack.get("timings", {}).items()}}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
