"""Training: schedule, determinism, checkpoints, resume, safe loading, local VGG weights."""
import pickle

import time

import numpy as np
import pytest
import torch

from seamless_usd.synthesis import MapInput, TrainedModel, get_preset, train
from seamless_usd.synthesis.gan.checkpoint import CHECKPOINT_NAME
from seamless_usd.synthesis.gan.features import VGG19_CFG, VGG19Features, build_feature_extractor
from seamless_usd.synthesis.gan.schedule import learning_rate


pytestmark = pytest.mark.usefixtures("one_thread")  # tiny networks: fastest and steadiest on one thread


def _stack(seed=0):
    rng = np.random.default_rng(seed)
    return [MapInput("albedo", rng.uniform(-1, 1, (48, 48, 3)).astype(np.float32)),
            MapInput("roughness", rng.uniform(-1, 1, (48, 48, 1)).astype(np.float32))]


def _same(a: TrainedModel, b: TrainedModel) -> bool:
    sa, sb = a.G.state_dict() | a.D.state_dict(), b.G.state_dict() | b.D.state_dict()
    return sa.keys() == sb.keys() and all(torch.equal(sa[k], sb[k]) for k in sa)


def test_learning_rate_schedule_is_the_papers():
    lrs = [learning_rate(s, 50_000, 2e-4, (0.6, 0.8), 5.0) for s in (0, 29_999, 30_000, 39_999, 40_000, 49_999)]
    assert lrs == pytest.approx([2e-4, 2e-4, 4e-5, 4e-5, 8e-6, 8e-6])


def test_same_seed_same_weights_other_seed_differs():
    cfg = get_preset("tiny").replace(iterations=3)
    a, b, c = train(_stack(), cfg, seed=5), train(_stack(), cfg, seed=5), train(_stack(), cfg, seed=6)
    assert _same(a, b) and not _same(a, c)
    assert a.hash == b.hash != c.hash


def test_progress_reports_iterations_rate_and_losses():
    seen, clock = [], []
    began = time.perf_counter()
    train(_stack(), get_preset("tiny").replace(iterations=3), progress=lambda p: (seen.append(p), clock.append(time.perf_counter())))
    assert [p.iteration for p in seen] == [1, 2, 3] and all(p.total == 3 for p in seen)
    for p, t in zip(seen, clock):
        # the training's clock runs inside this call: its elapsed time is at most ours, its rate at least ours
        assert 0 < p.elapsed_s <= t - began and p.it_per_s >= p.iteration / (t - began), (p, t - began)
        assert (p.eta_s > 0) == (p.iteration < 3)
    assert seen[-1].eta_s == 0
    assert {"d", "g", "g_adv", "l1", "style"} <= set(seen[-1].losses)


def test_killed_training_resumes_and_equals_uninterrupted(tmp_path):
    cfg = get_preset("tiny").replace(iterations=6, checkpoint_every=2)
    straight = train(_stack(), cfg, seed=1)

    def kill_at_3(p):
        if p.iteration == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        train(_stack(), cfg, seed=1, checkpoint_dir=tmp_path, progress=kill_at_3)
    steps = []
    resumed = train(_stack(), cfg, seed=1, checkpoint_dir=tmp_path, progress=lambda p: steps.append(p.iteration))
    assert steps == [3, 4, 5, 6]  # restarted after the checkpoint at 2, ended at the same total
    assert resumed.step == 6 and _same(straight, resumed)
    # a finished checkpoint loads as a model
    loaded = TrainedModel.load(tmp_path / CHECKPOINT_NAME)
    assert loaded.step == 6 and loaded.hash == straight.hash and _same(straight, loaded)


def test_checkpoint_of_another_run_is_refused(tmp_path):
    cfg = get_preset("tiny").replace(iterations=2)
    train(_stack(0), cfg, checkpoint_dir=tmp_path)
    with pytest.raises(ValueError, match="another stack"):
        train(_stack(1), cfg, checkpoint_dir=tmp_path)


class _Evil:
    def __reduce__(self):
        return (print, ("unpickled!",))


def test_loading_refuses_pickles(tmp_path):
    path = tmp_path / "model.safetensors"
    path.write_bytes(pickle.dumps({"G.weight": _Evil()}))
    with pytest.raises(ValueError, match="refusing"):
        TrainedModel.load(path)
    torch_file = tmp_path / CHECKPOINT_NAME
    torch.save({"obj": _Evil()}, torch_file)
    with pytest.raises(ValueError, match="refusing"):
        TrainedModel.load(torch_file)


def test_model_save_load_roundtrip(tmp_path):
    model = train(_stack(), get_preset("tiny").replace(iterations=2))
    model.save(tmp_path / "m.safetensors")
    back = TrainedModel.load(tmp_path / "m.safetensors")
    assert _same(model, back) and back.names == ["albedo", "roughness"] and back.channels == [3, 1]


def _write_vgg(path, upto: int):
    """A VGG19-shaped state dict (torchvision key names) of random weights, layers 0..upto."""
    g = torch.Generator().manual_seed(0)
    state, idx, cin = {}, 0, 3
    for v in VGG19_CFG:
        if idx > upto:
            break
        if v == "M":
            idx += 1
            continue
        state[f"features.{idx}.weight"] = torch.randn(v, cin, 3, 3, generator=g) * 0.05
        state[f"features.{idx}.bias"] = torch.zeros(v)
        cin, idx = v, idx + 2
    torch.save(state, path)
    return state


def test_vgg19_weights_load_from_a_local_file(tmp_path):
    path = tmp_path / "vgg19.pth"
    state = _write_vgg(path, upto=11)
    net = VGG19Features(path, layers=(1, 6, 11))
    assert torch.equal(net.features[5].weight, state["features.5.weight"])
    feats = net(torch.zeros(1, 3, 32, 32))
    assert [f.shape[1] for f in feats] == [64, 128, 256]
    with pytest.raises(AssertionError, match="lacks"):
        VGG19Features(path)  # default layers need up to relu5_1
    from safetensors.torch import save_file
    save_file(state, str(tmp_path / "vgg19.safetensors"))
    net2 = VGG19Features(tmp_path / "vgg19.safetensors", layers=(1, 6, 11))
    assert all(torch.equal(a, b) for a, b in zip(net(torch.ones(1, 3, 16, 16)), net2(torch.ones(1, 3, 16, 16))))
    # and through the config, used by training
    cfg = get_preset("tiny").replace(style_features="vgg19", vgg_weights=str(path), iterations=1)
    with pytest.raises(AssertionError, match="lacks"):
        build_feature_extractor(cfg)
    with pytest.raises(ValueError, match="vgg_weights"):
        build_feature_extractor(get_preset("tiny").replace(style_features="vgg19"))


def test_seam_training_option_trains_on_tiled_latents():
    cfg = get_preset("tiny").replace(iterations=3, seam_training_prob=1.0)
    seen = []
    model = train(_stack(), cfg, progress=seen.append)
    assert all(p.losses["l1"] == 0 for p in seen)  # tiled-latent steps have no pixel-aligned target
    assert all(torch.isfinite(p).all() for p in model.G.parameters())
    assert model.hash != train(_stack(), get_preset("tiny").replace(iterations=3)).hash
