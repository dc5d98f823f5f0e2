#!/usr/bin/env python3
"""Speed benchmark of the SeamlessGAN engine (prints figures; not a test).

Measures, in one run and interleaved (the machine is shared and its speed drifts):

- large fp32 and bf16 matmul peaks (GFLOP/s);
- training it/s and crops/s per preset and per variant (threads, crops per step, style loss off), and
  the achieved FLOP/s of a training step (FLOPs counted with ``torch.utils.flop_counter``) as a
  fraction of both peaks; OpenMP wait policies; the top ops of a step; ``--compile``: torch.compile
  cold and warm (``steps.py``);
- sampling: time and peak RSS for one candidate at c_max, and for the preset's whole search, at 512 and
  2048 px (each in a fresh subprocess so that RSS is its own);
- end to end (``--e2e PRESET``): train + sample a 512 px three-map stack made from the bundled brick
  maps, and write the 2x2 tiling of each output map beside the naive 2x2 tiling of its input.

    .venv/bin/python benchmarks/speed.py                  # steps + sampling, about 10 minutes
    .venv/bin/python benchmarks/speed.py --e2e draft      # end-to-end run of one preset

It refuses to run when the 1-minute load average is above 1.5 (``--allow-load`` records flagged
figures), and it records the load average beside every figure.
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

if str(HERE) not in sys.path:  # steps.py sits beside this script
    sys.path.insert(0, str(HERE))

from seamless_usd.synthesis import MapInput, get_preset, sample, train  # noqa: E402
from seamless_usd.synthesis.precision import cpu_supports_bf16, resolve_precision  # noqa: E402
from seamless_usd.synthesis.gan.train import TrainedModel, build_networks  # noqa: E402
from pictures import side_by_side, write_picture  # noqa: E402
from results_io import write_results  # noqa: E402
from steps import (CHANNELS, bench_compile, bench_seeds, bench_steps, bench_wait_policy, load_average,  # noqa: E402
                   profile_step)

MAX_LOAD = 1.5  # 1-minute load average above which figures are refused (or, with --allow-load, flagged)


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
        write_picture(tiles / f"speed_{preset}__brick512__{m.name}.png",
                          side_by_side(res.maps[m.name], m.pixels, m.is_normal))
    rec = {"preset": preset, "train_s": t1 - t0, "sample_s": t2 - t1, "total_s": t2 - t0,
           "iterations": cfg.iterations, "crop_size": list(res.crop_size), "q_passed": res.q_passed,
           "candidates": len(res.candidates), "precision": res.precision}
    print(f"  end-to-end {preset}: train {rec['train_s']:.0f} s + sample {rec['sample_s']:.0f} s = "
          f"{rec['total_s'] / 60:.1f} min; crop {res.crop_size}, Q passed={res.q_passed}, {len(res.candidates)} candidates")
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
        rec = {"seconds": time.perf_counter() - t0, "q_margin": res.q.margin, "q_passed": res.q_passed, "maps": {}}
        for m in maps:
            tile = res.maps[m.name]
            rolled = np.roll(tile, (tile.shape[0] // 2, tile.shape[1] // 2), (0, 1))
            rec["maps"][m.name] = M.seam_ratios(rolled, is_normal=m.is_normal)
        out[str(p)] = rec
        print(f"  seam_training_prob={p}: {rec['seconds']:.0f} s, Q margin {res.q.margin:+.3f}, centre seam x/y "
              + ", ".join(f"{n} {v['seam_ratio_x']:.2f}/{v['seam_ratio_y']:.2f}" for n, v in rec["maps"].items()),
              flush=True)
    return {"preset": preset, "results": out}


def speed_md(record: dict) -> str:
    """The figures of ``speed.json`` as Markdown tables."""
    m = record.get("machine", {})
    lines = ["# Speed benchmark", "", f"Written by `benchmarks/speed.py`. Machine: {m.get('cpu')}, "
             f"{m.get('threads')} threads, torch {m.get('torch')}, CPU capability {m.get('cpu_capability')}, "
             f"native bf16: {m.get('native_bf16')}.", ""]
    flagged = record.get("loaded")
    if flagged:
        lines += [f"> **WARNING: measured on a loaded machine** (1-minute load average {flagged} at the start, above "
                  f"{MAX_LOAD}); these figures understate the hardware.", ""]
    st = record.get("steps")
    if st:
        pk = st["matmul_gflops"]
        lines += ["## Training steps (variants interleaved, median of rounds)", "",
                  f"Precision chosen at run time: **{st['precision']}**. Matmul peaks measured in the same run "
                  f"(2048x2048, 2 threads): fp32 {np.median(pk['fp32']):.1f} GFLOP/s (rounds: "
                  f"{', '.join(f'{v:.1f}' for v in pk['fp32'])}; load {', '.join(f'{v:.2f}' for v in st['matmul_load'])}), "
                  f"bf16 {np.median(pk['bf16']):.2f} GFLOP/s. A crop is one 2k target; an iteration is one optimiser "
                  "step over `batch` crops.", "",
                  "| variant | k | ngf/ndf | res | batch | threads | engine | GFLOP/step | it/s (rounds) | crops/s "
                  "| GFLOP/s | of fp32 peak | load | preset iterations -> minutes |",
                  "|---|---:|---:|---:|---:|---:|---|---:|---|---:|---:|---:|---|---|"]
        for name, v in st["variants"].items():
            lines.append(f"| {name} | {v['k']} | {v['ngf']}/{v['ndf']} | {v['res_blocks']} | {v['batch']} | "
                         f"{v['threads']} | {v['engine']} | {v['gflop_per_step']:.2f} | {v['it_per_s_median']:.2f} "
                         f"({', '.join(f'{r:.2f}' for r in v['it_per_s'])}) | {v['crops_per_s_median']:.2f} | "
                         f"{v['achieved_gflops']:.1f} | {100 * v['fraction_of_fp32_peak']:.0f}% | "
                         f"{', '.join(f'{x:.2f}' for x in v['load'])} | "
                         f"{v['iterations']} -> {v['train_minutes_at_median']:.1f} |")
        lines.append("")
    wp = record.get("wait_policy")
    if wp and "crops_per_s" in wp:
        lines += [f"## OpenMP wait policy and crop workers ({wp['preset']} network, subprocesses interleaved)", "",
                  "| setting | crops/s (rounds) | median | load |", "|---|---|---:|---|"]
        for name, v in wp["crops_per_s"].items():
            lines.append(f"| {name} | {', '.join(f'{r:.2f}' for r in v)} | {wp['median'][name]:.2f} | "
                         f"{', '.join(f'{x:.2f}' for x in wp['load'][name])} |")
        lines.append("")
    sd = record.get("seeds")
    if sd:
        lines += [f"## Two seeds side by side ({sd['preset']} preset, one thread each, {sd['steps']} steps a round)",
                  "", "| run | it/s per round | median | load |", "|---|---|---:|---|",
                  f"| one run alone (1 thread) | {', '.join(f'{r:.2f}' for r in sd['one_run_it_per_s'])} | "
                  f"{sd['one_run_median']:.2f} | {', '.join(f'{x:.2f}' for x in sd['load'])} |"]
        for i in range(2):
            lines.append(f"| seed {i + 1} of 2 side by side | {', '.join(f'{p[i]:.2f}' for p in sd['pair_it_per_s'])} | "
                         f"{sd['pair_median_per_run'][i]:.2f} | |")
        lines += ["", f"Both cores give {sd['pair_median_sum']:.2f} it/s in all "
                  f"({sd['pair_median_sum'] / sd['one_run_median']:.2f}x one run); each seed trains at "
                  f"{min(sd['pair_median_per_run']) / sd['one_run_median']:.0%} of a lone run's speed.", ""]
    cp = record.get("compile")
    if cp:
        lines += [f"## torch.compile ({cp['preset']} preset, {cp['threads']} thread, fresh processes)", "",
                  "| run | first step s (compile included) | then it/s | load |", "|---|---:|---:|---:|"]
        for run in ("cold", "warm", "eager"):
            r = cp[run]
            lines.append(f"| {run if run != 'eager' else 'eager (no compile)'} | {r['first_step_s']:.1f} | "
                         f"{r['it_per_s']:.2f} | {r['load']:.2f} |")
        lines.append("")
    pf = record.get("profile")
    if pf:
        lines += [f"## Profile: top ops by self CPU time ({pf['variant']}, {pf['steps']} steps, "
                  f"{pf['step_ms']:.0f} ms a step under the profiler, load {pf['load']:.2f})", "",
                  "| op | ms per step | share | calls per step |", "|---|---:|---:|---:|"]
        for r in pf["top"]:
            lines.append(f"| `{r['op']}` | {r['self_ms_per_step']:.1f} | {100 * r['share']:.0f}% | "
                         f"{r['calls_per_step']:.0f} |")
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
    return "\n".join(lines)


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
    ap.add_argument("--skip-policy", action="store_true")
    ap.add_argument("--compile", action="store_true", help="also time torch.compile, cold and warm (several minutes)")
    ap.add_argument("--allow-load", action="store_true",
                    help=f"report even when the load average is above {MAX_LOAD} at the start (figures are flagged)")
    ap.add_argument("--whole", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args(argv)
    if a._sample is not None:
        _sample_child(a._sample, a.preset, a.whole)
        return 0
    load = load_average()
    if load > MAX_LOAD and not a.allow_load:
        print(f"error: the 1-minute load average is {load:.2f} (above {MAX_LOAD}): other jobs would slow every "
              "figure down. Wait for an idle machine, or pass --allow-load to record flagged figures.", file=sys.stderr)
        return 2
    RESULTS.mkdir(parents=True, exist_ok=True)
    json_path = RESULTS / "speed.json"
    record = json.loads(json_path.read_text()) if json_path.exists() else {}
    record["machine"] = {"cpu": platform.processor() or platform.machine(), "threads": torch.get_num_threads(),
                         "torch": torch.__version__, "cpu_capability": torch.backends.cpu.get_cpu_capability(),
                         "native_bf16": cpu_supports_bf16(), "load_at_start": load}
    record["loaded"] = load if load > MAX_LOAD else None
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
        if not a.skip_steps:
            record["seeds"] = bench_seeds(a.rounds)
        if not a.skip_policy:
            record["wait_policy"] = bench_wait_policy(a.rounds)
        if not a.skip_steps:
            record["profile"] = profile_step()
        if a.compile:
            record["compile"] = bench_compile()
        if not a.skip_sampling:
            sizes = [int(s) for s in a.sizes.split(",")]
            new = bench_sampling(a.preset, sizes, whole_search_sizes=[512])
            keep = [r for r in record.get("sampling", [])
                    if (r["preset"], r["size"], r["whole_search"]) not in {(n["preset"], n["size"], n["whole_search"]) for n in new}]
            record["sampling"] = keep + new
    write_results(RESULTS, "speed", speed_md(record), record)
    print(f"wrote {json_path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
