"""SeamlessGAN engine: train on a texture stack, sample a tileable stack. Knows nothing about USD.

>>> from seamless_usd.synthesis import MapInput, get_preset, train, sample
>>> import numpy as np
>>> maps = [MapInput("albedo", np.zeros((64, 64, 3), np.float32))]
>>> result = sample(train(maps, get_preset("tiny")), maps)   # doctest: +SKIP
"""
from .config import PRESETS, SynthesisConfig, get_preset
from .sample import SamplingProgress, sample
from .train import TrainedModel, train
from .types import Candidate, MapInput, QResult, TileResult, TrainingProgress

__all__ = ["SynthesisConfig", "PRESETS", "get_preset", "MapInput", "train", "sample", "TrainedModel",
           "TileResult", "QResult", "Candidate", "TrainingProgress", "SamplingProgress"]
