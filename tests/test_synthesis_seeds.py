"""Several seeds trained side by side and the tile their figures choose; D and the style loss every n-th step."""
import os

import numpy as np
import pytest
import torch

from seamless_usd.synthesis import MapInput, get_preset, make_tile, train
from seamless_usd.synthesis.gan.checkpoint import CHECKPOINT_NAME, load_checkpoint
from seamless_usd.synthesis.gan.features import build_feature_extractor
from seamless_usd.synthesis.gan.seeds import SeedRun, choose_seed, fidelity_score, seed_checkpoint_dir, train_seeds
from seamless_usd.synthesis.gan.step import Batch, g_loss, generate, training_step
from seamless_usd.synthesis.gan.train import build_networks
from seamless_usd.synthesis.types import QResult, TileResult

TINY = get_preset("tiny").replace(iterations=4)


def _maps(seed=0, size=48):
    rng = np.random.default_rng(seed)
    return [MapInput("albedo", rng.uniform(-1, 1, (size, size, 3)).astype(np.float32)),
            MapInput("rough", rng.uniform(-1, 1, (size, size, 1)).astype(np.float32))]


def _weights(model) -> torch.Tensor:
    return torch.cat([p.detach().flatten() for p in [*model.G.parameters(), *model.D.parameters()]])


# --- seeds -----------------------------------------------------------------------------------------------

def test_each_seed_trains_exactly_as_a_one_seed_run_of_that_seed(tmp_path):
    maps = _maps()
    before = torch.get_num_threads()
    models = train_seeds(maps, TINY.replace(seeds=2), 3, checkpoint_dir=tmp_path)
    assert torch.get_num_threads() == before  # the side-by-side workers leave the caller's threads alone
    alone = [train(maps, TINY, seed=s) for s in (3, 4)]
    for m, a in zip(models, alone):
        assert m.hash == a.hash and torch.equal(_weights(m), _weights(a))
    assert not torch.equal(_weights(models[0]), _weights(models[1]))
    # the first seed checkpoints where a one-seed run does, so either resumes the other's work
    for path in (tmp_path / CHECKPOINT_NAME, tmp_path / "seed-1" / CHECKPOINT_NAME):
        _, meta = load_checkpoint(path)
        assert meta["step"] == TINY.iterations
    assert seed_checkpoint_dir(None, 1) is None


def test_seeds_do_not_change_a_seeds_training_hash():
    maps = _maps()
    assert train(maps, TINY, seed=0).hash == train(maps, TINY.replace(seeds=3), seed=0).hash


def _periodic(size=64, period=8, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size]
    base = np.sin(2 * np.pi * x / period) * np.cos(2 * np.pi * y / period)
    return (0.7 * base + 0.2 * rng.uniform(-1, 1, (size, size)))[..., None].astype(np.float32)


def test_fidelity_score_ranks_a_faithful_tile_above_a_blurred_or_magnified_one():
    src = _periodic(size=128)
    working = [MapInput("h", src)]
    faithful = _periodic(size=128, seed=1)  # the same texture, other noise
    blurred = (src + np.roll(src, 1, 0) + np.roll(src, 1, 1) + np.roll(src, (1, 1), (0, 1))) / 4
    magnified = np.repeat(np.repeat(src[::2, ::2], 2, 0), 2, 1)
    good, scale, patch = fidelity_score({"h": faithful}, working)
    assert set(scale) == set(patch) == {"h"}
    assert good < fidelity_score({"h": blurred}, working)[0]
    assert good < fidelity_score({"h": magnified}, working)[0]


def _run(seed, passed, score):
    q = QResult(passed, 0.5, 0.6, 0.6, np.zeros((2, 2)), np.zeros((2, 2), bool), np.zeros((2, 2), bool))
    tile = TileResult({}, (8, 8), passed, q, [], {}, "", "cpu", "fp32")
    return SeedRun(seed, tile, score=score)


def test_choose_seed_prefers_a_q_pass_then_the_lowest_score_then_seed_order():
    runs = [_run(0, False, 0.5), _run(1, True, 2.0), _run(2, True, 1.5)]
    assert choose_seed(runs).seed == 2
    assert [r.chosen for r in runs] == [False, False, True]
    tie = [_run(0, True, 1.0), _run(1, True, 1.0)]
    assert choose_seed(tie).seed == 0


def test_make_tile_keeps_the_best_seeds_tile_and_reports_every_seed():
    maps = _maps(size=64)
    made = make_tile(maps, TINY.replace(seeds=2), refine_config=None, seed=5)
    assert [s["seed"] for s in made.seeds] == [5, 6]
    [kept] = [s for s in made.seeds if s["chosen"]]
    # each seed trained alone, its figures computed here: a Q pass first, then the lower fidelity score
    alone = {s: make_tile(maps, TINY, refine_config=None, seed=s) for s in (5, 6)}
    figures = {s: (not t.q.passed, fidelity_score(t.maps, maps)[0]) for s, t in alone.items()}
    assert figures[5] != figures[6]
    assert kept["seed"] == min(figures, key=figures.get), (figures, made.seeds)
    for s in made.seeds:  # the figures reported per seed are those of that seed's own tile
        assert s["q_passed"] == (not figures[s["seed"]][0]) and s["score"] == pytest.approx(figures[s["seed"]][1], abs=0.01)  # reported to 2 places
    for name in made.maps:  # the kept tile is that seed's own
        assert np.array_equal(made.maps[name], alone[kept["seed"]].maps[name])
    assert alone[5].seeds == []  # one seed: nothing to choose, no figures computed


# --- D every n-th step -----------------------------------------------------------------------------------

def _step(update_d: bool, stacked: bool):
    cfg = get_preset("tiny").replace(k=16)
    channels = [3, 1]
    G, D = build_networks(cfg, channels, seed=2)
    opt_g, opt_d = torch.optim.SGD(G.parameters(), lr=1.0), torch.optim.SGD(D.parameters(), lr=1.0)
    g = torch.Generator().manual_seed(0)
    target = torch.rand(1, 4, 32, 32, generator=g) * 2 - 1  # (N, C, 2k, 2k)
    d_before = [p.detach().clone() for p in D.parameters()]
    g_before = [p.detach().clone() for p in G.parameters()]
    losses = training_step(G, D, opt_g, opt_d, build_feature_extractor(cfg), Batch(target[:, :, 8:24, 8:24], target),
                           channels, cfg, torch.device("cpu"), "fp32", stacked=stacked, update_d=update_d)
    d_moved = any(not torch.equal(a, b) for a, b in zip(d_before, D.parameters()))
    g_step = [b - a.detach() for b, a in zip(g_before, G.parameters())]
    return losses, d_moved, g_step


@pytest.mark.parametrize("stacked", [False, True])
def test_a_step_without_d_update_leaves_d_alone_and_still_trains_g(stacked):
    losses, d_moved, _ = _step(True, stacked)
    assert d_moved and "d" in losses
    losses, d_moved, g_step = _step(False, stacked)
    assert not d_moved and "d" not in losses and {"g", "g_adv", "l1", "style"} <= set(losses)
    assert max(float(s.abs().max()) for s in g_step) > 1e-4


def test_without_a_d_update_micro_batches_and_the_stacked_batch_give_the_same_g_step():
    _, _, micro = _step(False, stacked=False)
    _, _, stacked = _step(False, stacked=True)
    for a, b in zip(micro, stacked):
        assert float((a - b).abs().max()) <= 1e-3 * float(a.abs().max()) + 1e-9


def test_d_every_is_part_of_the_training_only_when_set():
    maps = _maps()
    base = train(maps, TINY, seed=0)
    every2 = train(maps, TINY.replace(d_every=2), seed=0)
    assert "d_every" not in TINY.training_fields()  # hashes of runs made before the field existed stay valid
    assert every2.hash != base.hash and not torch.equal(_weights(every2), _weights(base))


def test_style_every_skips_the_style_loss_and_weights_it_when_computed():
    cfg = get_preset("tiny").replace(k=16, style_every=3)
    channels = [3, 1]
    G, D = build_networks(cfg, channels, seed=2)
    g = torch.Generator().manual_seed(0)
    target = torch.rand(1, 4, 32, 32, generator=g) * 2 - 1  # (N, C, 2k, 2k)
    batch = Batch(target[:, :, 8:24, 8:24], target)
    ext = build_feature_extractor(cfg)
    with torch.no_grad():
        fake = generate(G, batch)
        with_style, parts = g_loss(D, ext, fake, batch, channels, cfg, torch.device("cpu"), "fp32", True)
        without, skipped = g_loss(D, ext, fake, batch, channels, cfg, torch.device("cpu"), "fp32", False)
    assert "style" in parts and "style" not in skipped and parts["style"] > 0
    expect = float(without) + cfg.lambda_style * 3 * float(parts["style"])  # weighted by the period
    assert float(with_style) == pytest.approx(expect, rel=1e-5)
    maps = _maps()
    assert "style_every" not in TINY.training_fields()
    assert train(maps, TINY.replace(style_every=2), seed=0).hash != train(maps, TINY, seed=0).hash


def test_a_job_trains_the_presets_seeds_that_run_side_by_side_on_its_threads():
    from seamless_usd.pipeline.executors import make_executor
    from seamless_usd.pipeline.options import Options
    from seamless_usd.pipeline.stackjob import JobSettings

    default = Options(preset="default")
    assert JobSettings.from_options(default, 2).seeds is None  # the preset's two, side by side
    assert JobSettings.from_options(default, None).seeds is None  # a remote cluster's threads are not known
    assert JobSettings.from_options(default, 1).seeds == 1  # on one thread a second seed doubles the time
    assert JobSettings.from_options(Options(preset="default", seeds=2), 1).seeds == 2  # asked for: trained
    assert JobSettings.from_options(Options(preset="draft"), 1).seeds is None  # one seed already
    two = make_executor(None, 2)
    assert two.threads_per_job == max(1, (os.cpu_count() or 1) // 2)
    assert make_executor("tcp://127.0.0.1:8786").threads_per_job is None
    inprocess = make_executor(None, 1)
    before = torch.get_num_threads()
    try:  # in this process: the threads torch trains on, as a host application set them
        torch.set_num_threads(1)
        assert inprocess.threads_per_job == 1 and JobSettings.from_options(default, 1).seeds == 1
    finally:
        torch.set_num_threads(before)
    assert inprocess.threads_per_job == before
