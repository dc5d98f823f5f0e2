"""Training and sampling settings for SeamlessGAN, and the named presets."""
from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass

__all__ = ["SynthesisConfig", "PRESETS", "get_preset", "side_by_side_seeds"]


@dataclass(frozen=True)
class SynthesisConfig:
    """Every knob of training and sampling; defaults are the paper's (section 5) unless noted."""

    # --- networks ---
    k: int = 128  # source crop size; the target crop is 2k (paper: 128). Multiple of 8.
    ngf: int = 64  # generator width at full resolution; the latent x0 has 2*ngf channels
    ndf: int = 64  # discriminator width of its first layer (doubles per layer, PatchGAN)
    n_res_blocks: int = 5  # residual blocks after the encoder (paper: l = 5)
    upsample: str = "transposed"  # decoder x2 steps: "transposed" (stride-2 3x3, the paper) or "resize"
    #                               (nearest x2 + 3x3 conv: no checkerboard, 4x the FLOPs of those layers)
    init_std: float = 0.02  # N(0, 0.02) weight init, standard for pix2pix-style GANs

    # --- training ---
    iterations: int = 50_000  # paper: 50 000 at batch size 1
    lr: float = 2e-4  # Adam learning rate for G and D (paper)
    betas: tuple[float, float] = (0.5, 0.999)  # pix2pix/Zhou et al. Adam betas; 0.5 damps GAN oscillation
    lr_milestones: tuple[float, ...] = (0.6, 0.8)  # fractions of the run where lr is divided (paper: 30k, 40k of 50k)
    lr_decay: float = 5.0  # divisor applied at each milestone (paper)
    lambda_adv: float = 1.0  # adversarial weight
    lambda_l1: float = 10.0  # per-map L1 weight (paper)
    lambda_style: float = 1.0  # per-map Gram style weight
    style_features: str = "random"  # "random" (seeded, no download) or "vgg19" (needs vgg_weights)
    vgg_weights: str | None = None  # local VGG19 state dict (torchvision key names); no downloads, ever
    style_scales: int = 4  # random extractor: number of scales (each halves resolution)
    style_channels: int = 32  # random extractor: channels per scale; small so style does not dominate the step
    style_seed: int = 1234  # random extractor filters are fixed by this seed, independent of the training seed
    seam_training_prob: float = 0.0  # beyond the paper: fraction of G steps fed a 2x2-tiled latent (off by default)
    batch: int = 1  # crops per optimiser step (paper: 1); the loss is the mean of the per-crop losses
    d_every: int = 1  # beyond the paper: D is updated on every d_every-th step only, G on every step (paper: 1)
    style_every: int = 1  # beyond the paper: the style loss on every style_every-th G step only, weighted that
    #                       many times (the same expected gradient for a cheaper step; paper: 1)
    seeds: int = 1  # beyond the paper: independent trainings of the stack (seeds seed, seed+1, ...), run side by
    #                 side on the CPU's cores; the tile whose fidelity figures are best is kept (synthesis.seeds)

    # --- run control ---
    checkpoint_every: int = 500  # iterations between checkpoints (one is always written at the end)
    progress_every: int = 10  # iterations between progress callbacks
    precision: str = "auto"  # "auto" (CUDA: bf16/fp16, CPU: fp32), "fp32", "bf16", "fp16"
    workers: int = 0  # CPU threads computing the crops of a step in parallel; 0 (auto): one per crop, up to torch's
    #                   threads, and one thread in all for a single crop of a small network; N: N workers sharing
    #                   torch's threads as intra-op threads
    compile: str = "auto"  # torch.compile the training step: "auto" (on for CUDA, off on the CPU), "on", "off"

    # --- sampling (paper section 4.2) ---
    tiling: str = "circular"  # "circular": one period of the infinitely tiled latent (exactly periodic, 4x cheaper);
    #                           "repeat": literal 2x2 repeat, decode 4c, keep the central 2c (paper)
    c_min: int = 100  # smallest crop side tried (paper)
    crop_step: int = 16  # decrease of the larger crop side between sizes (pixels)
    crops_per_size: int = 3  # random crops per size below c_max (paper); c_max has exactly one
    max_candidates: int | None = None  # stop the search after this many candidates (None: until c_min)
    gamma: float = 1.0  # Q threshold factor, tau = gamma * min(D outside the bands) (paper)
    band_fraction: float = 0.2  # width of each search band as a fraction of the dimension (paper)
    chunk_pixels: int = 1 << 21  # max output pixels a decoder chunk produces at once (memory bound for big tiles)

    def __post_init__(self) -> None:
        assert self.k % 8 == 0 and self.k >= 16, f"k must be a multiple of 8 and >= 16, got {self.k}"
        assert self.precision in ("auto", "fp32", "bf16", "fp16"), f"unknown precision {self.precision!r}"
        assert self.tiling in ("circular", "repeat"), f"tiling must be 'circular' or 'repeat', got {self.tiling!r}"
        assert self.style_features in ("random", "vgg19"), (
            f"style_features must be 'random' or 'vgg19', got {self.style_features!r}")
        assert 0.0 <= self.seam_training_prob <= 1.0, "seam_training_prob is a probability"
        assert self.batch >= 1 and self.workers >= 0, "batch must be >= 1 and workers >= 0"
        assert min(self.d_every, self.style_every, self.seeds) >= 1, "d_every, style_every and seeds must be >= 1"
        assert self.upsample in ("transposed", "resize"), f"upsample must be 'transposed' or 'resize', got {self.upsample!r}"
        assert self.compile in ("auto", "on", "off"), f"compile must be 'auto', 'on' or 'off', got {self.compile!r}"

    def replace(self, **changes) -> "SynthesisConfig":
        return dataclasses.replace(self, **changes)

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> "SynthesisConfig":
        data = json.loads(text)
        for key in ("betas", "lr_milestones"):
            data[key] = tuple(data[key])
        known = {f.name for f in dataclasses.fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in known})

    def training_fields(self) -> dict:
        """The fields that change the trained weights (run control and sampling excluded).

        Fields added after models were first saved enter only when set away from their default, so the
        hashes (and checkpoints) of runs that do not use them stay valid.
        """
        skip = {"checkpoint_every", "progress_every", "tiling", "c_min", "crop_step", "crops_per_size",
                "max_candidates", "gamma", "band_fraction", "chunk_pixels", "vgg_weights", "workers", "compile",
                "seeds"}
        later = {"d_every": 1, "style_every": 1, "upsample": "transposed"}
        return {k: v for k, v in dataclasses.asdict(self).items()
                if k not in skip and not (k in later and v == later[k])}


PRESETS: dict[str, SynthesisConfig] = {
    # The paper's numbers (section 5); meant for a GPU.
    "paper": SynthesisConfig(),
    # CPU presets sized from idle-machine figures (benchmarks/results/speed.md): on one core of the 2-core AVX2
    # host a default step on a three-map stack runs at 7-8 it/s, so 2400 iterations train in about 5.5 min.
    # Doubling 1200 -> 2400 iterations took the maps inside both fidelity targets from 6 to 8 of 12 and the
    # patch-distance median from 1.02 to 0.93 (benchmarks/results/quality.md); draft stays a quick look.
    # Two seeds train side by side, one per core, for 1.09x the wall time of one: the best of the two took
    # the stacks whose tile passes Q from 1 to 3 of 6 and the maps inside every target from 3 to 4 of 12,
    # the medians within noise (docs/decisions.md, "Two seeds side by side").
    "default": SynthesisConfig(k=64, ngf=16, ndf=16, n_res_blocks=4, style_channels=16, iterations=2400,
                               seeds=2, crop_step=32, max_candidates=12, checkpoint_every=200),
    # For structured stacks (planks, stripes, courses) whose GAN layout the default breaks into dashes: four times
    # the default's training. On a 512 px stripes stack the layout's structure figure goes 2.61 (default) -> 2.45
    # (one seed, 485 s) -> 1.82 (two seeds, this preset, 682 s): long whole stripes that still step where the
    # latent copies meet (docs/benchmarks.md, "The GAN's own layout"). Inside the 30 minutes a 512 px stack may
    # take on two cores.
    "long": SynthesisConfig(k=64, ngf=16, ndf=16, n_res_blocks=4, style_channels=16, iterations=9600,
                            seeds=2, crop_step=32, max_candidates=12, checkpoint_every=400),
    "draft": SynthesisConfig(k=32, ngf=16, ndf=16, n_res_blocks=3, style_channels=16, iterations=350,
                             crop_step=64, max_candidates=4, checkpoint_every=100),
    # For tests: trains in about a second.
    "tiny": SynthesisConfig(k=16, ngf=8, ndf=8, n_res_blocks=1, iterations=4, style_scales=2, style_channels=8,
                            c_min=16, crop_step=8, max_candidates=6, checkpoint_every=2, progress_every=1),
}


def side_by_side_seeds(seeds: int, threads: int | None) -> int:
    """Of ``seeds`` seeds, how many train side by side on ``threads`` CPU threads: one per thread, at least one
    (``threads`` None: not known, as on a remote cluster: all of them).

    A job trains the preset's seeds that fit so: a second seed is worth its place where it trains on an idle
    core (1.09x the wall time of one, the best of the two: docs/decisions.md, "Two seeds side by side"). Where
    the cores are taken already (``--jobs 2`` on two cores, each job on one thread) it would train after the
    first and double the stack's training time. Asked for with ``seeds``, every seed is trained.

    >>> side_by_side_seeds(2, 2), side_by_side_seeds(2, 1), side_by_side_seeds(2, None)
    (2, 1, 2)
    """
    return seeds if threads is None else max(1, min(seeds, threads))


def get_preset(name: str) -> SynthesisConfig:
    """Return the preset called ``name``.

    >>> get_preset("tiny").k
    16
    """
    try:
        return PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown synthesis preset {name!r}; valid presets: {', '.join(sorted(PRESETS))}") from None
