#!/usr/bin/env python3
"""Speed benchmark of the SeamlessGAN engine (prints figures; not a test).

Measures, in one run and interleaved (the machine is shared and its speed drifts):

- large fp32 and bf16 matmul peaks (GFLOP/s);
- training it/s per preset and per variant (threads, style loss off), and the achieved FLOP/s of a
  training step (FLOPs counted with ``torch.utils.flop_counter``) as a fraction of both peaks;
- sampling: time and peak RSS for one candidate at c_max, and for the preset's whole search, at 512 and
  2048 px (each in a fresh subprocess so that RSS is its own);
- end to end (``--e2e PRESET``): train + sample a 512 px three-map stack made from the bundled brick
  maps, and write the 2x2 tiling of each output map beside the naive 2x2 tiling of its input.

    .venv/bin/python benchmarks/speed.py                  # steps + sampling, about 5 minutes
    .venv/bin/python benchmarks/speed.py --e2e draft      # end-to-end run of one preset
"""
from __future__ import annotations

import argparse
import json
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import seamless_usd.synthesis  # noqa: F401  (first: sets the OpenMP wait policy before torch loads)
import torch  # noqa: E402

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RESULTS = HERE / "results"

from seamless_usd.synthesis import MapInput, get_preset, sample, train  # noqa: E402
from seamless_usd.synthesis.config import SynthesisConfig  # noqa: E402
from seamless_usd.synthesis.features import build_feature_extractor  # noqa: E402
from seamless_usd.synthesis.precision import cpu_supports_bf16, resolve_precision  # noqa: E402
from seamless_usd.synthesis.step import Batch, training_step  # noqa: E402
from seamless_usd.synthesis.train import TrainedModel, build_networks  # noqa: E402

CHANNELS = [3, 3, 1]  # albedo, normal, roughness


def matmul_gflops(dtype: torch.dtype, n: int = 2048, seconds: float = 1.5) -> float:
    a, b = torch.randn(n, n).to(dtype), torch.randn(n, n).to(dtype)
    a @ b
    reps, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        a @ b
        reps += 1
    return 2 * n**3 * reps / (time.perf_counter() - t0) / 1e9


class StepRunner:
    """Training steps of one configuration on a fixed random batch (crop positions do not change speed)."""

    def __init__(self, cfg: SynthesisConfig, precision: str):
        self.cfg, self.precision, self.dev = cfg, precision, torch.device("cpu")
        self.G, self.D = build_networks(cfg, CHANNELS, seed=0)
        self.ext = build_feature_extractor(cfg)
        self.opt_g = torch.optim.Adam(self.G.parameters(), lr=cfg.lr, betas=cfg.betas)
        self.opt_d = torch.optim.Adam(self.D.parameters(), lr=cfg.lr, betas=cfg.betas)
        k = cfg.k
        target = torch.rand(1, sum(CHANNELS), 2 * k, 2 * k) * 2 - 1  # (N, C, 2k, 2k)
        self.batch = Batch(target[:, :, k // 2: k // 2 + k, k // 2: k // 2 + k], target)

    def step(self) -> None:
        training_step(self.G, self.D, self.opt_g, self.opt_d, self.ext, self.batch, CHANNELS, self.cfg,
                      self.dev, self.precision)

    def flops(self) -> int:
        from torch.utils.flop_counter import FlopCounterMode
        with FlopCounterMode(display=False) as fc:
            self.step()
        return fc.get_total_flops()

    def rate(self, steps: int, threads: int) -> float:
        torch.set_num_threads(threads)
        self.step()  # warm-up (oneDNN primitive creation)
        t0 = time.perf_counter()
        for _ in range(steps):
            self.step()
        return steps / (time.perf_counter() - t0)


def bench_steps(rounds: int, seconds_per_variant: float) -> dict:
    precision = resolve_precision("auto", torch.device("cpu"))
    variants = {
        "paper": (get_preset("paper"), 2),
        "default": (get_preset("default"), 2),
        "default@1thread": (get_preset("default"), 1),
        "default-no-style": (get_preset("default").replace(lambda_style=0.0), 2),
        "default-ngf32": (get_preset("default").replace(ngf=32, ndf=32, n_res_blocks=5, style_channels=32), 2),
        "draft": (get_preset("draft"), 2),
        "draft@1thread": (get_preset("draft"), 1),
    }
    runners = {name: StepRunner(cfg, precision) for name, (cfg, _) in variants.items()}
    flops = {name: r.flops() for name, r in runners.items()}
    rates: dict[str, list[float]] = {name: [] for name in variants}
    peaks: dict[str, list[float]] = {"fp32": [], "bf16": []}
    for rnd in range(rounds):
        torch.set_num_threads(2)
        peaks["fp32"].append(matmul_gflops(torch.float32))
        peaks["bf16"].append(matmul_gflops(torch.bfloat16, n=512 if not cpu_supports_bf16() else 2048, seconds=0.5))
        for name, (cfg, threads) in variants.items():
            probe = runners[name].rate(1, threads)
            steps = max(1, int(seconds_per_variant * probe))
            rates[name].append(runners[name].rate(steps, threads))
            print(f"  round {rnd + 1}/{rounds} {name:18s} {rates[name][-1]:7.2f} it/s", flush=True)
    torch.set_num_threads(2)
    peak32, peak16 = float(np.median(peaks["fp32"])), float(np.median(peaks["bf16"]))
    out = {"precision": precision, "matmul_gflops": {"fp32": peaks["fp32"], "bf16": peaks["bf16"]},
           "variants": {}}
    for name, (cfg, threads) in variants.items():
        r = float(np.median(rates[name]))
        gflops = flops[name] * r / 1e9
        out["variants"][name] = {
            "k": cfg.k, "ngf": cfg.ngf, "ndf": cfg.ndf, "res_blocks": cfg.n_res_blocks, "threads": threads,
            "lambda_style": cfg.lambda_style, "it_per_s": rates[name], "it_per_s_median": r,
            "gflop_per_step": flops[name] / 1e9, "achieved_gflops": gflops,
            "fraction_of_fp32_peak": gflops / peak32, "fraction_of_bf16_peak": gflops / peak16,
            "iterations": cfg.iterations, "train_minutes_at_median": cfg.iterations / r / 60}
    return out


def _steprate_child(preset: str, threads: int, steps: int) -> None:
    """Runs in a subprocess (so the OpenMP wait policy can differ): print the preset's training it/s."""
    print(json.dumps({"it_per_s": StepRunner(get_preset(preset), resolve_precision("auto", torch.device("cpu")))
                      .rate(steps, threads)}))


def bench_wait_policy(rounds: int, preset: str = "default", steps: int = 8) -> dict:
    """2 threads with spinning (ACTIVE) vs sleeping (PASSIVE) OpenMP waits vs 1 thread, interleaved."""
    import os
    variants = {"2 threads, OMP_WAIT_POLICY=ACTIVE": ("ACTIVE", 2), "2 threads, OMP_WAIT_POLICY=PASSIVE": ("PASSIVE", 2),
                "1 thread": ("PASSIVE", 1)}
    out: dict[str, list[float]] = {name: [] for name in variants}
    for _ in range(rounds):
        for name, (policy, threads) in variants.items():
            env = dict(os.environ, OMP_WAIT_POLICY=policy)
            proc = subprocess.run([sys.executable, __file__, "--_steprate", str(threads), "--preset", preset,
                                   "--steps", str(steps)], capture_output=True, text=True, check=True, env=env)
            out[name].append(json.loads(proc.stdout.strip().splitlines()[-1])["it_per_s"])
            print(f"  {preset} {name}: {out[name][-1]:.2f} it/s", flush=True)
    return {"preset": preset, "it_per_s": out, "median": {k: float(np.median(v)) for k, v in out.items()}}


def _sample_child(size: int, preset: str, whole_search: bool) -> None:
    """Runs in a subprocess: sample an (untrained) model on a size x size 3-map stack; print JSON."""
    cfg = get_preset(preset)
    # c_max alone, or the worst case of the whole search: gamma so high that no candidate passes
    cfg = cfg.replace(gamma=1e9) if whole_search else cfg.replace(max_candidates=1)
    G, D = build_networks(cfg, CHANNELS, seed=0)
    dev = torch.device("cpu")
    model = TrainedModel(G.eval(), D.eval(), cfg, "bench", ["albedo", "normal", "roughness"], CHANNELS,
                         [False, True, False], cfg.k, 0, dev, resolve_precision(cfg.precision, dev))
    rng = np.random.default_rng(0)
    maps = [MapInput(n, rng.uniform(-1, 1, (size, size, c)).astype(np.float32), n == "normal")
            for n, c in zip(model.names, CHANNELS)]
    base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    res = sample(model, maps)
    dt = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(json.dumps({"size": size, "preset": preset, "candidates": len(res.candidates), "seconds": dt,
                      "seconds_per_candidate": dt / len(res.candidates), "tile": list(res.maps["albedo"].shape[:2]),
                      "peak_rss_gib": peak / 2**20, "rss_before_gib": base / 2**20}))


def bench_sampling(preset: str, sizes: list[int], whole_search_sizes: list[int]) -> list[dict]:
    out = []
    for size in sizes:
        for whole in ([False, True] if size in whole_search_sizes else [False]):
            cmd = [sys.executable, __file__, "--_sample", str(size), "--preset", preset] + (["--whole"] if whole else [])
            proc = subprocess.run(cmd, capture_output=True, text=True, check=True)
            rec = json.loads(proc.stdout.strip().splitlines()[-1])
            rec["whole_search"] = whole
            print(f"  sample {preset} {size}px {'search' if whole else 'c_max'}: {rec['seconds']:.1f} s "
                  f"({rec['candidates']} candidates), peak RSS {rec['peak_rss_gib']:.2f} GiB", flush=True)
            out.append(rec)
    return out


def load_brick_512() -> list[MapInput]:
    """The bundled 256 px brick maps, upsampled 2x to a 512 px three-map stack in [-1, 1]."""
    import OpenImageIO as oiio
    maps = []
    for name, file, normal in [("albedo", "brick_albedo.png", False), ("normal", "brick_normal.png", True),
                               ("roughness", "brick_roughness.png", False)]:
        px = oiio.ImageBuf(str(ROOT / "sample_assets" / "textures" / file)).get_pixels(oiio.FLOAT)  # (H, W, C)
        px = np.repeat(np.repeat(px, 2, 0), 2, 1) * 2 - 1
        maps.append(MapInput(name, np.ascontiguousarray(px, dtype=np.float32), normal))
    return maps


def write_side_by_side(path: Path, tile: np.ndarray, source: np.ndarray) -> None:
    """2x2 tiling of ``tile`` (left) beside the naive 2x2 tiling of ``source`` (right), 8-bit PNG."""
    import OpenImageIO as oiio
    a, b = np.tile(tile, (2, 2, 1)), np.tile(source, (2, 2, 1))
    h = max(a.shape[0], b.shape[0])
    pad = lambda x: np.pad(x, ((0, h - x.shape[0]), (0, 8), (0, 0)), constant_values=1.0)  # noqa: E731
    img = np.concatenate([pad(a), pad(b)], 1)
    img = ((np.clip(img, -1, 1) + 1) * 127.5).round().astype(np.uint8)
    spec = oiio.ImageSpec(img.shape[1], img.shape[0], img.shape[2], oiio.UINT8)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), spec)
    out.write_image(img)
    out.close()


def end_to_end(preset: str) -> dict:
    maps = load_brick_512()
    cfg = get_preset(preset)
    t0 = time.perf_counter()
    last = [0.0]

    def show(p):
        if time.perf_counter() - last[0] > 30 or p.iteration == p.total:
            last[0] = time.perf_counter()
            print(f"  {p.iteration}/{p.total} {p.it_per_s:.2f} it/s eta {p.eta_s:.0f} s "
                  + " ".join(f"{k}={v:.3f}" for k, v in p.losses.items()), flush=True)

    model = train(maps, cfg, seed=0, progress=show)
    t1 = time.perf_counter()
    res = sample(model, maps, seed=0)
    t2 = time.perf_counter()
    tiles = RESULTS / "tiles"
    tiles.mkdir(parents=True, exist_ok=True)
    for m in maps:
        write_side_by_side(tiles / f"speed_{preset}__brick512__{m.name}.png", res.maps[m.name], m.pixels)
    rec = {"preset": preset, "train_s": t1 - t0, "sample_s": t2 - t1, "total_s": t2 - t0,
           "iterations": cfg.iterations, "crop_size": list(res.crop_size), "passed": res.passed,
           "candidates": len(res.candidates), "precision": res.precision}
    print(f"  end-to-end {preset}: train {rec['train_s']:.0f} s + sample {rec['sample_s']:.0f} s = "
          f"{rec['total_s'] / 60:.1f} min; crop {res.crop_size}, passed={res.passed}, {len(res.candidates)} candidates")
    return rec


def seam_compare(preset: str, probs: tuple[float, ...] = (0.0, 0.3)) -> dict:
    """Beyond the paper: train with a fraction of tiled-latent steps; compare seams at equal iterations.

    The latent copies meet on the tile's centre lines, so seams are measured there: the tile is rolled by
    half its size and ``metrics.seam_ratios`` read across the (now) wrap-around edges (about 1 = no seam),
    plus Q's margin (band minimum minus tau; >= 0 passes) on the c_max candidate.
    """
    from seamless_usd import metrics as M
    maps = load_brick_512()
    out = {}
    for p in probs:
        cfg = get_preset(preset).replace(seam_training_prob=p, max_candidates=1)
        t0 = time.perf_counter()
        res = sample(train(maps, cfg, seed=0), maps, seed=0)
        rec = {"seconds": time.perf_counter() - t0, "q_margin": res.q.margin, "passed": res.passed, "maps": {}}
        for m in maps:
            tile = res.maps[m.name]
            rolled = np.roll(tile, (tile.shape[0] // 2, tile.shape[1] // 2), (0, 1))
            rec["maps"][m.name] = M.seam_ratios(rolled, is_normal=m.is_normal)
        out[str(p)] = rec
        print(f"  seam_training_prob={p}: {rec['seconds']:.0f} s, Q margin {res.q.margin:+.3f}, centre seam x/y "
              + ", ".join(f"{n} {v['seam_ratio_x']:.2f}/{v['seam_ratio_y']:.2f}" for n, v in rec["maps"].items()),
              flush=True)
    return {"preset": preset, "results": out}


def write_markdown(record: dict, path: Path) -> None:
    """The figures of ``speed.json`` as Markdown tables."""
    m = record.get("machine", {})
    lines = ["# Speed benchmark", "", f"Written by `benchmarks/speed.py`. Machine: {m.get('cpu')}, "
             f"{m.get('threads')} threads, torch {m.get('torch')}, CPU capability {m.get('cpu_capability')}, "
             f"native bf16: {m.get('native_bf16')}.", ""]
    st = record.get("steps")
    if st:
        pk = st["matmul_gflops"]
        lines += ["## Training steps (variants interleaved, median of rounds)", "",
                  f"Precision chosen at run time: **{st['precision']}**. Matmul peaks measured in the same run "
                  f"(2048x2048): fp32 {np.median(pk['fp32']):.1f} GFLOP/s (rounds: "
                  f"{', '.join(f'{v:.1f}' for v in pk['fp32'])}), bf16 {np.median(pk['bf16']):.2f} GFLOP/s.", "",
                  "| variant | k | ngf/ndf | res | threads | GFLOP/step | it/s (rounds) | GFLOP/s | of fp32 peak "
                  "| of bf16 peak | preset iterations -> minutes |",
                  "|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---|"]
        for name, v in st["variants"].items():
            lines.append(f"| {name} | {v['k']} | {v['ngf']}/{v['ndf']} | {v['res_blocks']} | {v['threads']} | "
                         f"{v['gflop_per_step']:.2f} | {v['it_per_s_median']:.2f} "
                         f"({', '.join(f'{r:.2f}' for r in v['it_per_s'])}) | {v['achieved_gflops']:.1f} | "
                         f"{100 * v['fraction_of_fp32_peak']:.0f}% | {100 * v['fraction_of_bf16_peak']:.0f}% | "
                         f"{v['iterations']} -> {v['train_minutes_at_median']:.1f} |")
        lines.append("")
    wp = record.get("wait_policy")
    if wp:
        lines += [f"## OpenMP wait policy ({wp['preset']} preset, subprocesses interleaved)", "",
                  "| setting | it/s (rounds) | median |", "|---|---|---:|"]
        for name, v in wp["it_per_s"].items():
            lines.append(f"| {name} | {', '.join(f'{r:.2f}' for r in v)} | {wp['median'][name]:.2f} |")
        lines.append("")
    sm = record.get("sampling")
    if sm:
        lines += ["## Sampling (untrained weights; each row a fresh process)", "",
                  "| preset | input | what | candidates | seconds | s/candidate | tile | peak RSS GiB |",
                  "|---|---:|---|---:|---:|---:|---|---:|"]
        for r in sm:
            lines.append(f"| {r['preset']} | {r['size']} | {'whole search, none passing (worst case)' if r['whole_search'] else 'c_max only'} | "
                         f"{r['candidates']} | {r['seconds']:.1f} | {r['seconds_per_candidate']:.1f} | "
                         f"{r['tile'][0]}x{r['tile'][1]} | {r['peak_rss_gib']:.2f} |")
        lines.append("")
    e2e = record.get("end_to_end")
    if e2e:
        lines += ["## End to end: 512 px brick stack (albedo, normal, roughness)", "",
                  "| preset | iterations | train s | sample s | total min | crop | passed | candidates |",
                  "|---|---:|---:|---:|---:|---|---|---:|"]
        for name, r in e2e.items():
            lines.append(f"| {name} | {r['iterations']} | {r['train_s']:.0f} | {r['sample_s']:.0f} | "
                         f"{r['total_s'] / 60:.1f} | {r['crop_size'][0]}x{r['crop_size'][1]} | {r['passed']} | "
                         f"{r['candidates']} |")
        lines += ["", "Tiles: `results/tiles/speed_<preset>__brick512__<map>.png` (2x2 tiling of the output, "
                  "left; naive 2x2 tiling of the input, right).", ""]
    for key in sorted(k for k in record if k.startswith("seam_training")):
        sc = record[key]
        lines += [f"## Beyond the paper: tiled-latent training steps ({sc['preset']} preset, brick 512, equal iterations)",
                  "", "Centre-line seam ratios (first differences across the lines where latent copies meet; "
                  "about 1 = no seam) and Q margin of the c_max candidate.", "",
                  "| seam_training_prob | seconds | Q margin | " + " | ".join(
                      f"{n} x/y" for n in next(iter(sc["results"].values()))["maps"]) + " |",
                  "|---:|---:|---:|" + "---|" * len(next(iter(sc["results"].values()))["maps"])]
        for p, r in sc["results"].items():
            lines.append(f"| {p} | {r['seconds']:.0f} | {r['q_margin']:+.3f} | " + " | ".join(
                f"{v['seam_ratio_x']:.2f}/{v['seam_ratio_y']:.2f}" for v in r["maps"].values()) + " |")
        lines.append("")
    notes = record.get("notes")
    if notes:
        lines += ["## Notes", ""] + [f"- {n}" for n in notes] + [""]
    path.write_text("\n".join(lines))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds of the step benchmark")
    ap.add_argument("--seconds", type=float, default=6.0, help="seconds per variant per round")
    ap.add_argument("--preset", default="default", help="preset for the sampling benchmark")
    ap.add_argument("--sizes", default="512,2048")
    ap.add_argument("--skip-steps", action="store_true")
    ap.add_argument("--skip-sampling", action="store_true")
    ap.add_argument("--e2e", default=None, help="train + sample a 512 px brick stack with this preset")
    ap.add_argument("--seam-compare", default=None, help="compare seam_training_prob values with this preset")
    ap.add_argument("--probs", default="0,0.3", help="seam_training_prob values for --seam-compare")
    ap.add_argument("--_sample", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--_steprate", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, default=8, help=argparse.SUPPRESS)
    ap.add_argument("--skip-policy", action="store_true")
    ap.add_argument("--whole", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a._steprate is not None:
        _steprate_child(a.preset, a._steprate, a.steps)
        return 0
    if a._sample is not None:
        _sample_child(a._sample, a.preset, a.whole)
        return 0
    RESULTS.mkdir(parents=True, exist_ok=True)
    json_path = RESULTS / "speed.json"
    record = json.loads(json_path.read_text()) if json_path.exists() else {}
    record["machine"] = {"cpu": platform.processor() or platform.machine(), "threads": torch.get_num_threads(),
                         "torch": torch.__version__, "cpu_capability": torch.backends.cpu.get_cpu_capability(),
                         "native_bf16": cpu_supports_bf16()}
    if a.e2e:
        record.setdefault("end_to_end", {})[a.e2e] = end_to_end(a.e2e)
    elif a.seam_compare:
        res = seam_compare(a.seam_compare, tuple(float(p) for p in a.probs.split(",")))
        key = f"seam_training_{a.seam_compare}"
        if key in record and record[key]["preset"] == res["preset"]:
            res["results"] = {**record[key]["results"], **res["results"]}
        record[key] = res
    else:
        if not a.skip_steps:
            record["steps"] = bench_steps(a.rounds, a.seconds)
        if not a.skip_policy:
            record["wait_policy"] = bench_wait_policy(a.rounds)
        if not a.skip_sampling:
            sizes = [int(s) for s in a.sizes.split(",")]
            new = bench_sampling(a.preset, sizes, whole_search_sizes=[512])
            keep = [r for r in record.get("sampling", [])
                    if (r["preset"], r["size"], r["whole_search"]) not in {(n["preset"], n["size"], n["whole_search"]) for n in new}]
            record["sampling"] = keep + new
    json_path.write_text(json.dumps(record, indent=1))
    write_markdown(record, RESULTS / "speed.md")
    print(f"wrote {json_path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
