"""Shapes, channels and presets of the SeamlessGAN engine."""
import time

import numpy as np
import pytest
import torch

from seamless_usd.synthesis import MapInput, PRESETS, get_preset, sample, train
from seamless_usd.synthesis.gan.networks import Discriminator, Generator
from seamless_usd.synthesis.gan.train import build_networks


pytestmark = pytest.mark.usefixtures("one_thread")  # tiny networks: fastest and steadiest on one thread


def _stack(h=64, w=80, seed=0):
    rng = np.random.default_rng(seed)
    return [MapInput("albedo", rng.uniform(-1, 1, (h, w, 3)).astype(np.float32)),
            MapInput("roughness", rng.uniform(-1, 1, (h, w, 1)).astype(np.float32)),
            MapInput("normal", rng.uniform(-1, 1, (h, w, 3)).astype(np.float32), is_normal=True)]


def test_generator_doubles_size_with_one_decoder_per_map():
    G = Generator(7, [3, 1, 3], ngf=8, n_res_blocks=1)
    outs = G(torch.zeros(1, 7, 16, 24))  # (N, C, H, W)
    assert [tuple(o.shape) for o in outs] == [(1, 3, 32, 48), (1, 1, 32, 48), (1, 3, 32, 48)]
    assert all(o.abs().max() <= 1 for o in outs)
    assert G.encode(torch.zeros(1, 7, 16, 24)).shape == (1, 16, 8, 12)  # x0 at half resolution, 2*ngf channels


@pytest.mark.parametrize("upsample", ["transposed", "resize"])
def test_both_upsampling_kinds_double_the_size(upsample):
    G = Generator(7, [3, 1], ngf=8, n_res_blocks=1, upsample=upsample)
    assert [tuple(o.shape) for o in G(torch.zeros(1, 7, 16, 24))] == [(1, 3, 32, 48), (1, 1, 32, 48)]


def test_resize_convolution_has_no_checkerboard_on_a_flat_input():
    """A flat latent through a x2 step: the transposed convolution's uneven overlap gives the four
    pixel phases different values (the checkerboard); nearest x2 + 3x3 conv gives one flat value."""
    torch.manual_seed(0)
    flat = torch.ones(1, 8, 12, 12)
    for upsample, checkered in (("transposed", True), ("resize", False)):
        dec = Generator(3, [3], ngf=4, n_res_blocks=1, upsample=upsample).decoders[0]
        with torch.no_grad():
            y = dec.up1[0](flat)[0, :, 4:-4, 4:-4]  # (C, 2H, 2W) away from the borders
        phases = torch.stack([y[:, i::2, j::2].mean() for i in (0, 1) for j in (0, 1)])
        spread = float(phases.max() - phases.min()) / (float(y.abs().mean()) + 1e-12)
        assert (spread > 0.1) == checkered, (upsample, spread)


def test_discriminator_is_a_patch_map_of_probabilities():
    D = Discriminator(7, ndf=8)
    d = D(torch.randn(1, 7, 64, 64))
    assert d.shape[:2] == (1, 1) and d.shape[2] > 1 and d.shape[3] > 1
    assert ((d > 0) & (d < 1)).all()
    assert sum(isinstance(m, torch.nn.Conv2d) for m in D.modules()) == 5


def test_init_is_normal_0_002_and_seeded():
    cfg = get_preset("tiny").replace(ngf=32)
    G1, _ = build_networks(cfg, [3, 1], seed=3)
    G2, _ = build_networks(cfg, [3, 1], seed=3)
    w = torch.cat([p.flatten() for n, p in G1.named_parameters() if n.endswith("weight")])
    assert abs(w.std().item() - 0.02) < 0.002 and abs(w.mean().item()) < 0.002
    assert all(torch.equal(a, b) for a, b in zip(G1.parameters(), G2.parameters()))


def test_train_and_sample_shapes_per_map_rectangular():
    maps = _stack(64, 80)
    model = train(maps, get_preset("tiny"))
    began = time.perf_counter()
    result = sample(model, maps)
    wall = time.perf_counter() - began
    c_h, c_w = result.crop_size
    assert c_w / c_h == pytest.approx(80 / 64, rel=0.1)
    for m in maps:
        out = result.maps[m.name]
        assert out.shape == (2 * c_h, 2 * c_w, m.channels) and out.dtype == np.float32
        assert np.isfinite(out).all() and np.abs(out).max() <= 1
    n = result.maps["normal"]
    assert np.allclose(np.linalg.norm(n, axis=2), 1, atol=1e-4)  # normals come back unit length
    assert result.model_hash == model.hash and result.device == "cpu"
    # the search's time holds every candidate's and fits in the call's
    assert result.candidates and sum(c.seconds for c in result.candidates) <= result.timings["search_s"] <= wall


def test_presets_registry_and_clear_error():
    assert set(PRESETS) == {"paper", "default", "long", "draft", "tiny"}
    paper = get_preset("paper")
    assert (paper.k, paper.n_res_blocks, paper.iterations, paper.lambda_l1, paper.lr) == (128, 5, 50_000, 10.0, 2e-4)
    # long: the default's networks and search, four times the training
    default, long = get_preset("default"), get_preset("long")
    assert long.iterations == 4 * default.iterations and long.training_fields() == {
        **default.training_fields(), "iterations": long.iterations}
    with pytest.raises(ValueError, match="default, draft, long, paper, tiny"):
        get_preset("fast")


def test_stack_validation_messages():
    a = MapInput("a", np.zeros((32, 32, 3), np.float32))
    b = MapInput("b", np.zeros((32, 40, 1), np.float32))
    with pytest.raises(AssertionError, match="share H, W"):
        train([a, b], get_preset("tiny"))
    with pytest.raises(AssertionError, match="1..4 channels"):
        MapInput("c", np.zeros((8, 8, 5), np.float32))
