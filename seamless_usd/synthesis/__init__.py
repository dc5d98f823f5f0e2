"""SeamlessGAN engine: train on a texture stack, sample a tileable stack. Knows nothing about USD.

>>> from seamless_usd.synthesis import MapInput, get_preset, train, sample
>>> import numpy as np
>>> maps = [MapInput("albedo", np.zeros((64, 64, 3), np.float32))]
>>> result = sample(train(maps, get_preset("tiny")), maps)   # doctest: +SKIP
"""
import os

# Threads that sleep instead of spinning at OpenMP barriers: on a busy machine (other jobs on the same
# cores) spinning made 2-thread training 5-10x slower than 1 thread (benchmarks/speed.py). Only takes
# effect when this package is imported before torch; an explicit setting always wins.
os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

from .config import PRESETS, SynthesisConfig, get_preset
from .lattice import LATTICE_TARGET
from .refine import RefineConfig, RefineResult, refine
from .sample import SamplingProgress, sample
from .tile import MadeTile, downsample_maps, make_tile, written_lattice_ratio
from .train import TrainedModel, train
from .types import Candidate, MapInput, QResult, TileResult, TrainingProgress

__all__ = ["SynthesisConfig", "PRESETS", "get_preset", "MapInput", "train", "sample", "TrainedModel",
           "TileResult", "QResult", "Candidate", "TrainingProgress", "SamplingProgress",
           "RefineConfig", "RefineResult", "refine", "MadeTile", "make_tile", "downsample_maps", "LATTICE_TARGET",
           "written_lattice_ratio"]
