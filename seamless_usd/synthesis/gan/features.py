"""Feature extractors for the Gram style loss: a seeded random multi-scale CNN (default) or local VGG19 weights.

Nothing is ever downloaded. Both take (N, 3, H, W) images in [-1, 1] and return a list of feature maps.
"""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import torch
import torch.nn.functional as F
from safetensors import SafetensorError
from safetensors.torch import load_file
from torch import nn

__all__ = ["RandomFeatures", "VGG19Features", "FEATURE_EXTRACTORS", "build_feature_extractor", "to_rgb_batch",
           "gram", "style_loss", "load_state_dict_file"]


class RandomFeatures(nn.Module):
    """Fixed random filters at several scales (3x3 conv + ReLU, then 2x average pooling).

    Random, untrained filters are known to give usable Gram texture statistics; the filters are drawn
    from ``seed`` with He scaling so activations keep a similar magnitude at every scale.
    """

    def __init__(self, scales: int = 4, channels: int = 32, seed: int = 1234):
        super().__init__()
        g = torch.Generator().manual_seed(seed)
        convs = []
        cin = 3
        for _ in range(scales):
            conv = nn.Conv2d(cin, channels, 3, padding=1, bias=False)
            with torch.no_grad():
                conv.weight.copy_(torch.randn(conv.weight.shape, generator=g) * (2.0 / (cin * 9)) ** 0.5)
            convs.append(conv)
            cin = channels
        self.convs = nn.ModuleList(convs)
        self.requires_grad_(False)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:  # (N, 3, H, W) -> [(N, ch, H/2^i, W/2^i)]
        feats = []
        for i, conv in enumerate(self.convs):
            if i:
                x = F.avg_pool2d(x, 2)
            x = F.relu(conv(x))
            feats.append(x)
        return feats


# Indices of relu1_1, relu2_1, relu3_1, relu4_1, relu5_1 in torchvision's vgg19().features.
VGG19_CFG = [64, 64, "M", 128, 128, "M", 256, 256, 256, 256, "M", 512, 512, 512, 512, "M", 512, 512, 512, 512]
VGG19_STYLE_LAYERS = (1, 6, 11, 20, 29)


class VGG19Features(nn.Module):
    """VGG19 convolutional trunk up to the deepest requested ReLU, with weights from a local file.

    The file is a state dict with torchvision key names (``features.0.weight``, ...), as safetensors or a
    ``torch.save`` file (loaded with ``weights_only=True``). Only layers up to the deepest used one are needed.
    """

    MEAN = (0.485, 0.456, 0.406)
    STD = (0.229, 0.224, 0.225)

    def __init__(self, weights_path: str | Path, layers: tuple[int, ...] = VGG19_STYLE_LAYERS):
        super().__init__()
        self.layers = tuple(sorted(layers))
        modules: list[nn.Module] = []
        cin = 3
        for v in VGG19_CFG:
            if len(modules) > self.layers[-1]:
                break
            if v == "M":
                modules.append(nn.MaxPool2d(2))
            else:
                modules += [nn.Conv2d(cin, v, 3, padding=1), nn.ReLU(inplace=False)]
                cin = v
        self.features = nn.Sequential(*modules[: self.layers[-1] + 1])
        state = load_state_dict_file(weights_path)
        wanted = self.features.state_dict()
        missing = [k for k in wanted if f"features.{k}" not in state]
        assert not missing, f"VGG19 weights file {Path(weights_path).name} lacks {missing[:4]}... (torchvision key names expected)"
        for k, v in wanted.items():
            got = state[f"features.{k}"]
            assert got.shape == v.shape, f"VGG19 weight features.{k}: expected shape {tuple(v.shape)}, got {tuple(got.shape)}"
        self.features.load_state_dict({k: state[f"features.{k}"].float() for k in wanted})
        self.register_buffer("mean", torch.tensor(self.MEAN).view(1, 3, 1, 1), persistent=False)
        self.register_buffer("std", torch.tensor(self.STD).view(1, 3, 1, 1), persistent=False)
        self.requires_grad_(False)

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:  # (N, 3, H, W) in [-1, 1]
        x = ((x + 1) * 0.5 - self.mean) / self.std
        feats = []
        for i, m in enumerate(self.features):
            x = m(x)
            if i in self.layers:
                feats.append(x)
        return feats


def load_state_dict_file(path: str | Path) -> dict[str, torch.Tensor]:
    """Tensors from a safetensors file, or a torch.save file with ``weights_only=True`` (never a full unpickle)."""
    path = Path(path)
    try:
        return load_file(str(path))
    except (SafetensorError, OSError, ValueError) as e:
        if path.suffix == ".safetensors":
            raise ValueError(f"{path.name}: not a valid safetensors file ({e})") from e
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as e:  # noqa: BLE001
        raise ValueError(f"{path.name}: refusing to load; only safetensors or weights-only torch files are accepted ({e})") from e
    assert isinstance(state, dict), f"{path.name}: expected a state dict, got {type(state).__name__}"
    return state


FEATURE_EXTRACTORS: dict[str, Callable[..., nn.Module]] = {
    "random": lambda cfg: RandomFeatures(cfg.style_scales, cfg.style_channels, cfg.style_seed),
    "vgg19": lambda cfg: VGG19Features(_need(cfg.vgg_weights)),
}


def _need(path: str | None) -> str:
    if not path:
        raise ValueError("style_features='vgg19' needs vgg_weights: a local path to VGG19 weights (no downloads)")
    return path


def build_feature_extractor(config) -> nn.Module:
    try:
        make = FEATURE_EXTRACTORS[config.style_features]
    except KeyError:
        raise ValueError(f"unknown style_features {config.style_features!r}; valid: {', '.join(FEATURE_EXTRACTORS)}") from None
    return make(config)


def to_rgb_batch(x: torch.Tensor) -> torch.Tensor:
    """(N, C, H, W) with C in 1..4 -> (N', 3, H, W): grey repeated, 2 channels padded, RGBA split into RGB + AAA."""
    c = x.shape[1]
    if c == 1:
        return x.expand(-1, 3, -1, -1)
    if c == 2:
        return torch.cat([x, torch.zeros_like(x[:, :1])], 1)
    if c == 3:
        return x
    assert c == 4, f"expected 1..4 channels, got {c}"
    return torch.cat([x[:, :3], x[:, 3:].expand(-1, 3, -1, -1)], 0)


def gram(f: torch.Tensor) -> torch.Tensor:  # (N, C, H, W) -> (N, C, C), normalised by C*H*W, in fp32
    n, c, h, w = f.shape
    f = f.float().reshape(n, c, h * w)
    return f @ f.transpose(1, 2) / (c * h * w)


def style_loss(extractor: nn.Module, fake: torch.Tensor, real: torch.Tensor) -> torch.Tensor:
    """Sum over layers of the Gram-matrix MSE of ``fake`` vs ``real`` (N, C, H, W), relative to the real Gram's
    mean square, so the loss is about 1 for unrelated textures whatever the extractor's scale.

    Each image of the batch is compared and normalised on its own and the batch mean is returned, so a
    batch of N crops gives the mean of the N one-crop losses.
    """
    ff = extractor(to_rgb_batch(fake))
    with torch.no_grad():
        fr = extractor(to_rgb_batch(real))
    total = fake.new_zeros((), dtype=torch.float32)
    for a, b in zip(ff, fr):
        ga, gb = gram(a), gram(b)  # (N', C, C)
        total = total + ((ga - gb).square().mean((1, 2)) / (gb.square().mean((1, 2)) + 1e-8)).mean()
    return total
