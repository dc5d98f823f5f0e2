"""The training engine: device/precision/compile selection (GPU logic checked without a GPU), crop workers,
and the numerics of several-crop steps."""
import numpy as np
import pytest
import torch

from seamless_usd.synthesis import MapInput, get_preset, train
from seamless_usd.synthesis.config import SynthesisConfig
from seamless_usd.synthesis.gan.data import training_crops
from seamless_usd.synthesis.gan.engine import CropWorkers, compile_cache_dir, engine_for, maybe_compile, plan_engine
from seamless_usd.synthesis.gan.features import build_feature_extractor, style_loss
from seamless_usd.synthesis.precision import choose_precision
from seamless_usd.synthesis.gan.step import Batch, StepFunctions, d_loss, g_loss, generate, training_step
from seamless_usd.synthesis.gan.train import build_networks

CHANNELS = [3, 1, 4]  # RGB, grey and RGBA: every branch of the style loss's channel handling
CONFIG = get_preset("tiny").replace(k=16, ngf=8, ndf=8, n_res_blocks=1, batch=2)


# --- selection logic ------------------------------------------------------------------------------------

def test_cuda_plan_uses_bf16_autocast_one_stacked_batch_and_the_compiled_step():
    plan = plan_engine(get_preset("default"), "cuda", threads=2, cuda_bf16=True)
    assert (plan.precision, plan.stacked, plan.compile, plan.workers, plan.grad_scaler) == ("bf16", True, True, 1, False)
    assert "bf16" in plan.reason and "compiled" in plan.reason


def test_cuda_without_bf16_falls_back_to_fp16_with_loss_scaling():
    plan = plan_engine(get_preset("default"), "cuda", threads=2, cuda_bf16=False)
    assert (plan.precision, plan.grad_scaler) == ("fp16", True)


def test_cuda_plan_respects_explicit_settings():
    plan = plan_engine(get_preset("default").replace(compile="off", precision="fp32"), "cuda", threads=2, cuda_bf16=True)
    assert (plan.precision, plan.compile, plan.grad_scaler) == ("fp32", False, False)


@pytest.mark.parametrize("batch, workers, threads, expect", [
    (2, 0, 2, (2, 1)),  # one crop per core
    (2, 0, 1, (1, 1)),  # a one-thread batch worker: crops one after another
    (1, 0, 2, (1, 2)),  # one crop: intra-op threads
    (4, 0, 2, (2, 1)),  # never more workers than cores
    (4, 1, 2, (1, 2)),  # the user asked for one worker
    (2, 0, 16, (2, 8)),
])
def test_cpu_plan_gives_each_core_whole_crops(batch, workers, threads, expect):
    plan = plan_engine(SynthesisConfig(batch=batch, workers=workers), "cpu", threads=threads)
    assert (plan.workers, plan.intra_threads) == expect
    assert plan.precision == "fp32" and not plan.compile and not plan.stacked and not plan.grad_scaler


def test_small_networks_run_one_crop_on_one_thread():
    small = plan_engine(SynthesisConfig(batch=1, ngf=16), "cpu", threads=2)
    assert (small.workers, small.intra_threads) == (1, 1)
    assert plan_engine(SynthesisConfig(batch=1, ngf=64), "cpu", threads=2).intra_threads == 2
    asked = plan_engine(SynthesisConfig(batch=1, ngf=16, workers=1), "cpu", threads=2)  # explicit: all threads
    assert (asked.workers, asked.intra_threads) == (1, 2)


def test_cpu_compile_is_opt_in_and_then_stacked_on_one_worker():
    assert not plan_engine(SynthesisConfig(), "cpu", threads=2).compile
    plan = plan_engine(SynthesisConfig(batch=2, compile="on"), "cpu", threads=2)
    assert (plan.compile, plan.stacked, plan.workers) == (True, True, 1)


def test_precision_choice_per_device():
    assert choose_precision("auto", "cpu") == "fp32"  # native bf16 or not: no faster, and thread-dependent
    assert choose_precision("auto", "cuda", cuda_bf16=True) == "bf16"
    assert choose_precision("fp16", "cpu") == "fp16"


def test_this_machine_gets_a_cpu_plan_when_no_gpu_is_asked_for():
    plan = engine_for(get_preset("default").replace(batch=2), torch.device("cpu"))
    assert plan.device_type == "cpu" and plan.workers == min(2, torch.get_num_threads())
    one = engine_for(get_preset("default"), torch.device("cpu"))  # one crop of a small network: one thread
    assert (one.workers, one.intra_threads) == (1, 1)


def test_compile_cache_lives_in_the_user_cache_unless_set(monkeypatch, tmp_path):
    monkeypatch.delenv("TORCHINDUCTOR_CACHE_DIR", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert compile_cache_dir() == tmp_path / "seamless-usd" / "torch-compile"
    monkeypatch.setenv("TORCHINDUCTOR_CACHE_DIR", str(tmp_path / "mine"))
    assert compile_cache_dir() == tmp_path / "mine"
    plan = plan_engine(SynthesisConfig(), "cpu", threads=1)
    fn = lambda x: x + 1  # noqa: E731
    assert maybe_compile(fn, plan) is fn  # eager plans run the function itself


def test_crop_workers_restore_the_callers_threads():
    before = torch.get_num_threads()
    plan = plan_engine(SynthesisConfig(batch=2), "cpu", threads=2)
    with CropWorkers(plan) as workers:
        assert workers.map(lambda a, b: a * b, [1, 2, 3], [4, 5, 6]) == [4, 10, 18]
        assert torch.get_num_threads() == plan.intra_threads
    assert torch.get_num_threads() == before


# --- numerics -------------------------------------------------------------------------------------------

def _maps(seed=0, size=48):
    rng = np.random.default_rng(seed)
    return [MapInput(f"m{i}", rng.uniform(-1, 1, (size, size, c)).astype(np.float32), i == 0)
            for i, c in enumerate(CHANNELS)]


def _weights(model) -> torch.Tensor:
    return torch.cat([p.detach().flatten() for p in [*model.G.parameters(), *model.D.parameters()]])


def test_weights_do_not_depend_on_how_many_crop_workers_ran():
    maps = _maps()
    cfg = CONFIG.replace(iterations=3, batch=3)
    one = train(maps, cfg.replace(workers=1), seed=4)
    two = train(maps, cfg.replace(workers=2), seed=4)
    assert one.engine.workers == 1 and two.engine.workers == min(2, torch.get_num_threads())
    assert torch.equal(_weights(one), _weights(two))
    assert one.hash == two.hash  # workers are run control, not part of the training


def test_batch_is_part_of_the_training():
    maps = _maps()
    a = train(maps, CONFIG.replace(iterations=2, batch=1), seed=0)
    b = train(maps, CONFIG.replace(iterations=2, batch=2), seed=0)
    assert a.hash != b.hash and not torch.equal(_weights(a), _weights(b))


def _one_step(stacked: bool, batch: Batch, fns: StepFunctions | None = None):
    G, D = build_networks(CONFIG, CHANNELS, seed=1)
    ext = build_feature_extractor(CONFIG)
    opt_g = torch.optim.SGD(G.parameters(), lr=1.0)  # SGD, so the update is the gradient itself
    opt_d = torch.optim.SGD(D.parameters(), lr=1.0)
    before = [p.detach().clone() for p in [*G.parameters(), *D.parameters()]]
    losses = training_step(G, D, opt_g, opt_d, ext, batch, CHANNELS, CONFIG, torch.device("cpu"), "fp32",
                           stacked=stacked, fns=fns)
    steps = [b - p.detach() for b, p in zip(before, [*G.parameters(), *D.parameters()])]
    return losses, steps


def test_micro_batches_give_the_same_step_as_one_stacked_batch():
    g = torch.Generator().manual_seed(0)
    target = torch.rand(2, sum(CHANNELS), 32, 32, generator=g) * 2 - 1  # (N, C, 2k, 2k)
    batch = Batch(target[:, :, 4:20, 8:24], target)
    lm, sm = _one_step(False, batch)
    ls, ss = _one_step(True, batch)
    for key in lm:
        assert lm[key] == pytest.approx(ls[key], rel=1e-5, abs=1e-6), key
    for a, b in zip(sm, ss):  # equal up to float summation order, relative to each tensor's scale
        assert float((a - b).abs().max()) <= 1e-3 * float(a.abs().max()) + 1e-9
    assert max(float(s.abs().max()) for s in sm) > 1e-4  # the step did move the weights


def test_style_loss_of_a_batch_is_the_mean_of_the_per_crop_losses():
    ext = build_feature_extractor(CONFIG)
    g = torch.Generator().manual_seed(3)
    for c in (1, 3, 4):
        fake, real = torch.rand(2, c, 32, 32, generator=g), torch.rand(2, c, 32, 32, generator=g)
        both = style_loss(ext, fake, real)
        each = [style_loss(ext, fake[i: i + 1], real[i: i + 1]) for i in range(2)]
        assert float(both) == pytest.approx(float(sum(each) / 2), rel=1e-5)


def test_the_first_crop_of_a_step_is_the_one_crop_runs_always_saw():
    rng = np.random.default_rng([7, 11])
    expect = tuple(int(rng.integers(0, hi)) for hi in (100 - 32 + 1, 90 - 32 + 1, 17, 17))
    assert training_crops(7, 11, 100, 90, 16) == expect
    assert training_crops(7, 11, 100, 90, 16, index=1) != expect


@pytest.mark.parametrize("seam", [False, True], ids=["crop", "tiled-latent"])
def test_the_compiled_step_is_whole_graphs_and_computes_the_eager_step(seam):
    """The compiled step (the GPU default): generate, D's loss and G's loss with style each trace without a
    graph break (a break splits the graph and, on a loss read as a float, recompiles every step), and the step
    through their AOTAutograd forward and backward graphs gives the eager step's losses and gradients. The
    graphs run without a code generator (``aot_eager``): which kernels inductor emits for them is torch's
    business and differs between the GPU and this CPU anyway."""
    g = torch.Generator().manual_seed(0)
    target = torch.rand(2, sum(CHANNELS), 32, 32, generator=g) * 2 - 1  # (N, C, 2k, 2k)
    batch = Batch(target[:, :, 8:16, 8:16] if seam else target[:, :, 4:20, 8:24], target, seam)
    from torch._dynamo.utils import counters

    compiled = StepFunctions(*(torch.compile(f, backend="aot_eager", dynamic=False)  # as maybe_compile does
                               for f in (generate, d_loss, g_loss)))
    eager_losses, eager_steps = _one_step(True, batch)
    torch._dynamo.reset()
    counters.clear()
    losses, steps = _one_step(True, batch, compiled)
    assert not counters["graph_break"], dict(counters["graph_break"])  # a float() of a loss inside is one
    assert set(losses) == set(eager_losses) == {"d", "g", "g_adv", "l1", "style"}
    for key in eager_losses:
        assert losses[key] == pytest.approx(eager_losses[key], rel=1e-5, abs=1e-6), key
    for a, b in zip(eager_steps, steps):  # SGD with lr 1: the update is the gradient
        assert float((a - b).abs().max()) <= 1e-4 * float(a.abs().max()) + 1e-9
    assert max(float(s.abs().max()) for s in steps) > 1e-4  # the step did move the weights


def test_maybe_compile_builds_with_inductor_and_keeps_its_graphs(monkeypatch, tmp_path):
    """With the plan's compile on, a piece of the step (the adversarial loss on D's logits, forward and
    backward) runs through inductor's real code generator (C++ kernels here, built scalar, to compile faster:
    no vector instruction set is offered, which also spares the compiler probes inductor runs for each one,
    10 s of g++) with the eager result and gradient, and its graphs land in the cache directory, so a second
    run skips the compile. The whole step's graphs are checked above, without a code generator."""
    import torch._inductor.config as inductor_config
    import torch._inductor.cpu_vec_isa as vec_isa

    from seamless_usd.synthesis.gan.step import _bce

    monkeypatch.setenv("TORCHINDUCTOR_CACHE_DIR", str(tmp_path / "graphs"))
    monkeypatch.setattr(inductor_config.cpp, "simdlen", 1)
    monkeypatch.setattr(vec_isa, "supported_vec_isa_list", [])
    monkeypatch.setattr(inductor_config, "compile_threads", 1)  # a few kernels: no pool of compile workers
    plan = plan_engine(CONFIG.replace(compile="on"), "cpu", threads=1)
    assert plan.compile and compile_cache_dir() == tmp_path / "graphs"
    assert maybe_compile(_bce, plan_engine(CONFIG, "cpu", threads=1)) is _bce  # compile off: the function itself
    logits = torch.randn(2, 1, 6, 6, generator=torch.Generator().manual_seed(2))
    results = []
    for fn in (_bce, maybe_compile(_bce, plan)):
        x = logits.clone().requires_grad_(True)
        loss = fn(x, True)
        loss.backward()
        results.append((float(loss), x.grad))
    (eager, eager_grad), (built, built_grad) = results
    assert built == pytest.approx(eager, rel=1e-5) and eager > 0
    assert torch.allclose(built_grad, eager_grad, rtol=1e-5, atol=1e-7) and float(eager_grad.abs().max()) > 0
    assert any(p.suffix == ".cpp" for p in (tmp_path / "graphs").rglob("*")), "no kernel was built"
    assert any(p.is_file() for p in (tmp_path / "graphs" / "fxgraph").rglob("*")), "no compiled graph was cached"
