"""Latent tiling: the kept centre is one period; chunked decoding equals unchunked (both upsampling kinds)."""
import numpy as np
import pytest
import torch

from seamless_usd.metrics import seam_ratios
from seamless_usd.synthesis import get_preset
from seamless_usd.synthesis.gan.tiling import tile_generate
from seamless_usd.synthesis.gan.train import build_networks


pytestmark = pytest.mark.usefixtures("one_thread")  # tiny networks: fastest and steadiest on one thread


def _seam_ratio(img: torch.Tensor) -> tuple[float, float]:
    """The product's seam ratios (wrap-around step over interior step, per axis) of a (C, H, W) tile."""
    r = seam_ratios(img.permute(1, 2, 0).numpy())
    return r["seam_ratio_x"], r["seam_ratio_y"]


def _model(seed=0, upsample="transposed"):
    G, _ = build_networks(get_preset("tiny").replace(ngf=8, n_res_blocks=2, upsample=upsample), [3, 1], seed=seed)
    return G.eval()


UPSAMPLE = pytest.mark.parametrize("upsample", ["transposed", "resize"])


@UPSAMPLE
def test_circular_tile_is_exactly_periodic(upsample):
    G = _model(upsample=upsample)
    src = torch.rand(1, 4, 32, 48, generator=torch.Generator().manual_seed(1)) * 2 - 1
    with torch.no_grad():
        outs = tile_generate(G, src, "circular")
        # Decoding two periods side by side must repeat the single period exactly.
        x0 = G.encode(src)
        h, w = x0.shape[2:]
        window = torch.roll(x0, (h // 2, w // 2), (2, 3))
        G.set_padding(periodic=True)
        twice = [d(G.res(window.repeat(1, 1, 2, 2))) for d in G.decoders]
        G.set_padding(periodic=False)
    for o, t in zip(outs, twice):
        assert o.shape[2:] == (64, 96)
        assert torch.allclose(t[:, :, :64, :96], o, atol=1e-5) and torch.allclose(t[:, :, 64:, 96:], o, atol=1e-5)
        rx, ry = _seam_ratio(o[0])
        assert rx < 1.5 and ry < 1.5, f"wrap-around step {rx:.2f}x / {ry:.2f}x the interior step"


@UPSAMPLE
def test_repeat_tile_centre_wraps_around_like_its_interior(upsample):
    G = _model(upsample=upsample)
    src = torch.rand(1, 4, 64, 64, generator=torch.Generator().manual_seed(2)) * 2 - 1
    with torch.no_grad():
        outs = tile_generate(G, src, "repeat")
    for o in outs:
        assert o.shape[2:] == (128, 128)
        rx, ry = _seam_ratio(o[0])
        assert rx < 1.5 and ry < 1.5, f"wrap-around step {rx:.2f}x / {ry:.2f}x the interior step"
    seamy = outs[0][0].clone()
    seamy[:, :, :64] += 0.5  # a step at the left/right border: the figure sees it
    assert _seam_ratio(seamy)[0] > 1.5
    # and the circular tile is the limit of the repeat tile: same centre away from the latent borders
    with torch.no_grad():
        circ = tile_generate(G, src, "circular")
    assert np.corrcoef(circ[0].flatten().numpy(), outs[0].flatten().numpy())[0, 1] > 0.95


@UPSAMPLE
def test_chunked_decoding_matches_unchunked(upsample):
    G = _model(3, upsample)
    src = torch.rand(1, 4, 40, 56, generator=torch.Generator().manual_seed(3)) * 2 - 1
    with torch.no_grad():
        full = tile_generate(G, src, "circular", chunk_pixels=None)
        chunked = tile_generate(G, src, "circular", chunk_pixels=16 * 28 * 3)  # 3 latent rows per chunk
    for a, b in zip(full, chunked):
        assert a.shape == b.shape
        assert torch.allclose(a, b, atol=2e-5), (a - b).abs().max()
