#!/usr/bin/env python3
"""SeamlessGAN end to end on one stack, on the GPU when present: training, the crop search, the refinement.

Reads a three-map stack (the MaterialX brick: base colour, normal, roughness) resized to ``--size`` px,
forces the GAN path (the cheap cut is not tried, as with ``--method gan``), and prints one JSON line:
the device, the engine's precision and compile choice, the training rate (iterations a second over the
last half of the run, so torch.compile's first steps are not counted), each stage's time, the peak memory
(the GPU's allocator on CUDA, the process's resident set on the CPU), and the time the preset's full
iteration count would take at that rate.

Needs only torch, numpy, safetensors and Pillow, so it runs on a bare GPU machine beside a copy of the
repository:

    python3 benchmarks/gpu.py --preset paper --iterations 3000 --size 512           # CUDA when present
    .venv/bin/python benchmarks/gpu.py --preset tiny --size 128 --device cpu        # the CPU check
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

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))  # the package, uninstalled, when run from a bare copy of the repository
TEXTURES = HERE.parent.parent / "shared" / "textures"
MAPS = (("brick_base_gray", 3, False), ("brick_normal", 3, True), ("brick_roughness", 1, False))


def load_stack(folder: Path, size: int):
    """The brick maps at ``size`` px (Lanczos), as the synthesis engine's inputs in [-1, 1]."""
    from PIL import Image

    from seamless_usd.synthesis import MapInput

    maps = []
    for name, channels, normal in MAPS:
        path = folder / f"{name}.jpg"
        if not path.is_file():
            raise SystemExit(f"error: {path} is missing; pass --textures FOLDER holding the MaterialX brick maps")
        with Image.open(path) as im:
            im = im.convert("RGB" if channels == 3 else "L").resize((size, size), Image.Resampling.LANCZOS)
            pixels = np.asarray(im, dtype=np.float32).reshape(size, size, channels) / 127.5 - 1.0
        maps.append(MapInput(name, pixels, is_normal=normal))
    return maps


def steady_rate(points: list[tuple[int, float]]) -> float:
    """Iterations a second over the second half of the run (compilation and warm-up excluded).

    >>> steady_rate([(10, 5.0), (20, 6.0), (30, 7.0), (40, 8.0)])
    10.0
    """
    if len(points) < 2:
        return points[-1][0] / max(points[-1][1], 1e-9) if points else 0.0
    (i0, t0), (i1, t1) = points[len(points) // 2 - (len(points) % 2 == 0)], points[-1]
    if i1 == i0:
        return i1 / max(t1, 1e-9)
    return (i1 - i0) / max(t1 - t0, 1e-9)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--preset", default="paper")
    p.add_argument("--iterations", type=int, help="train this many iterations instead of the preset's (the full run's "
                                                  "time is extrapolated from the measured rate)")
    p.add_argument("--size", type=int, default=512, help="side of the stack (px)")
    p.add_argument("--device", help="cpu, cuda, cuda:N (default: CUDA when present)")
    p.add_argument("--compile", choices=("auto", "on", "off"), default=None, help="override the preset's torch.compile")
    p.add_argument("--textures", type=Path, default=TEXTURES, help="folder holding brick_*.jpg")
    p.add_argument("--out", type=Path, help="also write the figures (JSON) and the tile's first map (PNG) here")
    a = p.parse_args(argv)

    import torch

    from seamless_usd.synthesis import get_preset
    from seamless_usd.synthesis.gan.engine import engine_for
    from seamless_usd.synthesis.precision import pick_device
    from seamless_usd.synthesis.refinement.refine import RefineConfig
    from seamless_usd.synthesis.tile import make_tile

    preset = get_preset(a.preset)
    config = preset.replace(**({"iterations": a.iterations} if a.iterations else {}),
                            **({"compile": a.compile} if a.compile else {}),
                            progress_every=max(1, min(preset.progress_every, 50)),
                            checkpoint_every=10 ** 9)  # no checkpoints: the run is timed, not kept
    device = pick_device(a.device)
    plan = engine_for(config, device)
    maps = load_stack(a.textures, a.size)
    points: list[tuple[int, float]] = []

    def progress(kind, info):
        if kind == "train":
            points.append((info.iteration, info.elapsed_s))

    if device.type == "cuda":
        torch.cuda.reset_peak_memory_stats(device)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    made = make_tile(maps, config, refine_config=RefineConfig(lattice=False), device=device, progress=progress)
    if device.type == "cuda":
        torch.cuda.synchronize(device)
    wall = time.perf_counter() - t0
    rate = steady_rate([(i, t) for i, t in points if i <= config.iterations])
    figures = {
        "device": (torch.cuda.get_device_name(device) if device.type == "cuda"
                   else f"cpu ({platform.processor() or 'x86-64'})"),
        "torch": torch.__version__, "threads": torch.get_num_threads(), "preset": a.preset, "size": a.size,
        "maps": len(maps), "seeds": config.seeds, "precision": plan.precision, "compiled": plan.compile,
        "iterations": config.iterations, "it_per_s": round(rate, 2),
        "stages_s": {k: round(v, 2) for k, v in made.timings.items()},
        "wall_s": round(wall, 1),
        "full_run_min": round((preset.iterations * config.seeds / max(rate, 1e-9)) / 60, 1),
        "full_run_iterations": preset.iterations,
        "peak_gib": round((torch.cuda.max_memory_allocated(device) if device.type == "cuda"
                           else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024) / 2 ** 30, 2),
        "peak_kind": "GPU allocator" if device.type == "cuda" else "process resident set",
        "gan_crop": list(made.gan.maps[maps[0].name].shape[:2]) if made.gan else None,
        "q_passed": made.q_passed, "tile": list(made.tile_size), "load_at_start": round(load, 2),
    }
    print(json.dumps(figures))
    if a.out:
        from PIL import Image

        a.out.mkdir(parents=True, exist_ok=True)
        (a.out / f"gpu_{a.preset}_{a.size}.json").write_text(json.dumps(figures, indent=1) + "\n")
        first = made.maps[maps[0].name]
        Image.fromarray(np.clip((first + 1) * 127.5 + 0.5, 0, 255).astype(np.uint8)).save(
            a.out / f"gpu_{a.preset}_{a.size}.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
