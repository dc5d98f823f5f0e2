"""SeamlessGAN networks: generator G2 (shared encoder + residual blocks, one decoder per map) and PatchGAN D.

Every convolution pads explicitly through ``Padded`` so that the whole generator can switch from
reflect padding (training) to circular padding (sampling one period of an infinitely tiled latent).
"""
from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import nn

__all__ = ["Generator", "Discriminator", "ResizeConv", "init_weights"]


class Padded(nn.Module):
    """Pad then convolve; ``mode`` is "reflect"/"zeros" in training and "circular" when sampling periodically."""

    def __init__(self, conv: nn.Conv2d | nn.ConvTranspose2d, pad: int, train_mode: str):
        super().__init__()
        self.conv, self.pad, self.train_mode = conv, pad, train_mode
        self.mode = train_mode
        self.pad_h = True  # chunked sampling turns vertical padding off (rows come from a halo instead)

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # (N, C, H, W)
        p = self.pad
        pads = (p, p, p, p) if self.pad_h else (p, p, 0, 0)
        if self.mode == "zeros":
            x = F.pad(x, pads)
        else:
            x = F.pad(x, pads, mode=self.mode)
        y = self.conv(x)
        if isinstance(self.conv, nn.ConvTranspose2d):
            # A padding-free stride-2 k3 transposed conv on input padded by 1 gives 2(H+2)+1 rows;
            # rows [3, 3 + 2H) are exactly ConvTranspose2d(padding=1, output_padding=1) on the unpadded input.
            h = (x.shape[2] - 2 * p) if self.pad_h else x.shape[2]
            w = x.shape[3] - 2 * p
            top = 3 if self.pad_h else 1
            y = y[:, :, top: top + 2 * h, 3: 3 + 2 * w]
        return y


class ResizeConv(Padded):
    """Nearest-neighbour x2, then a 3x3 convolution (Odena et al. 2016, "Deconvolution and Checkerboard
    Artifacts"): every output pixel sees the same number of inputs, so no checkerboard. 4x the FLOPs of
    the stride-2 transposed convolution it replaces.

    With ``pad_h`` off (chunked sampling) the rows are padded by replication: those rows sit in the
    halo that the chunking throws away.
    """

    def __init__(self, cin: int, cout: int):
        super().__init__(nn.Conv2d(cin, cout, 3, bias=False), 1, "reflect")

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # (N, Cin, H, W) -> (N, Cout, 2H, 2W)
        x = F.interpolate(x, scale_factor=2, mode="nearest")
        x = F.pad(x, (1, 1, 0, 0), mode=self.mode)
        x = F.pad(x, (0, 0, 1, 1), mode=self.mode if self.pad_h else "replicate")
        return self.conv(x)


def _in(ch: int) -> nn.InstanceNorm2d:
    return nn.InstanceNorm2d(ch, affine=False, track_running_stats=False)


def conv_in_relu(cin: int, cout: int, k: int, stride: int = 1) -> list[nn.Module]:
    return [Padded(nn.Conv2d(cin, cout, k, stride=stride, bias=False), k // 2, "reflect"), _in(cout), nn.ReLU(True)]


def up_in_relu(cin: int, cout: int, upsample: str = "transposed") -> list[nn.Module]:
    if upsample == "resize":
        return [ResizeConv(cin, cout), _in(cout), nn.ReLU(True)]
    return [Padded(nn.ConvTranspose2d(cin, cout, 3, stride=2, bias=False), 1, "zeros"), _in(cout), nn.ReLU(True)]


class ResBlock(nn.Module):
    def __init__(self, ch: int):
        super().__init__()
        self.body = nn.Sequential(*conv_in_relu(ch, ch, 3),
                                  Padded(nn.Conv2d(ch, ch, 3, bias=False), 1, "reflect"), _in(ch))

    def forward(self, x: torch.Tensor) -> torch.Tensor:  # (N, 2ngf, h, w)
        return x + self.body(x)


class Decoder(nn.Module):
    """Latent (N, 2ngf, h, w) -> map (N, C, 4h, 4w) in [-1, 1]."""

    def __init__(self, ngf: int, out_ch: int, upsample: str = "transposed"):
        super().__init__()
        half = max(ngf // 2, 4)
        self.up1 = nn.Sequential(*up_in_relu(2 * ngf, ngf, upsample))
        self.up2 = nn.Sequential(*up_in_relu(ngf, half, upsample))
        self.out = Padded(nn.Conv2d(half, out_ch, 7, bias=True), 3, "reflect")

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.out(self.up2(self.up1(x))))


class Generator(nn.Module):
    """G2 of the paper: E (7x7 conv, stride-2 conv) -> x0 -> l residual blocks -> one decoder per map."""

    def __init__(self, in_ch: int, out_channels: list[int], ngf: int, n_res_blocks: int,
                 upsample: str = "transposed"):
        super().__init__()
        self.out_channels = list(out_channels)
        self.encoder = nn.Sequential(*conv_in_relu(in_ch, ngf, 7), *conv_in_relu(ngf, 2 * ngf, 3, stride=2))
        self.res = nn.Sequential(*[ResBlock(2 * ngf) for _ in range(n_res_blocks)])
        self.decoders = nn.ModuleList([Decoder(ngf, c, upsample) for c in out_channels])

    def encode(self, x: torch.Tensor) -> torch.Tensor:  # (N, Cin, H, W) -> (N, 2ngf, H/2, W/2)
        return self.encoder(x)

    def decode(self, x0: torch.Tensor) -> list[torch.Tensor]:  # (N, 2ngf, h, w) -> [(N, C_i, 4h, 4w)]
        x = self.res(x0)
        return [d(x) for d in self.decoders]

    def forward(self, x: torch.Tensor) -> list[torch.Tensor]:  # (N, Cin, k, k) -> [(N, C_i, 2k, 2k)]
        return self.decode(self.encode(x))

    def set_padding(self, periodic: bool) -> None:
        """Circular padding everywhere (periodic sampling) or the training padding."""
        for m in self.modules():
            if isinstance(m, Padded):
                m.mode = "circular" if periodic else m.train_mode


class Discriminator(nn.Module):
    """5-layer PatchGAN over the concatenated stack; ``forward`` gives probabilities, ``logits`` the raw map."""

    def __init__(self, in_ch: int, ndf: int):
        super().__init__()
        layers: list[nn.Module] = []
        ch = in_ch
        for i, (mult, stride) in enumerate([(1, 2), (2, 2), (4, 2), (8, 1)]):
            layers += [nn.Conv2d(ch, ndf * mult, 4, stride=stride, padding=1, bias=False), _in(ndf * mult),
                       nn.LeakyReLU(0.2, True)]
            ch = ndf * mult
        layers.append(nn.Conv2d(ch, 1, 4, stride=1, padding=1, bias=True))
        self.net = nn.Sequential(*layers)

    def logits(self, x: torch.Tensor) -> torch.Tensor:  # (N, Ctot, H, W) -> (N, 1, ~H/8 - 2, ~W/8 - 2)
        return self.net(x)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.sigmoid(self.logits(x))


def init_weights(module: nn.Module, std: float, generator: torch.Generator) -> None:
    """N(0, std) for every conv weight, zeros for biases, drawn from ``generator`` (deterministic)."""
    for m in module.modules():
        if isinstance(m, (nn.Conv2d, nn.ConvTranspose2d)):
            with torch.no_grad():
                m.weight.copy_(torch.randn(m.weight.shape, generator=generator) * std)
                if m.bias is not None:
                    m.bias.zero_()
