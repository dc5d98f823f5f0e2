"""Synthesis: a texture stack in, a tileable stack out. Knows nothing about USD.

Three methods, one folder each, composed by ``tile.make_tile``:

- ``gan/``: SeamlessGAN, trained at the working resolution; its latent tiling gives the tileable layout;
- ``refinement/``: toroidal exemplar refinement, which brings that layout to full resolution with
  source texels;
- ``lattice/``: the lattice cut, for textures that repeat (bricks, tiles, weaves).

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
from .gan.sample import SamplingProgress, sample
from .gan.train import TrainedModel, train
from .lattice.cut import LATTICE_TARGET
from .refinement.refine import RefineConfig, RefineResult, refine
from .tile import MadeTile, downsample_maps, make_tile, structure_advice, written_lattice_ratio
from .types import Candidate, MapInput, QResult, TileResult, TrainingProgress

__all__ = ["SynthesisConfig", "PRESETS", "get_preset", "MapInput", "train", "sample", "TrainedModel",
           "TileResult", "QResult", "Candidate", "TrainingProgress", "SamplingProgress",
           "RefineConfig", "RefineResult", "refine", "MadeTile", "make_tile", "downsample_maps", "LATTICE_TARGET",
           "written_lattice_ratio", "structure_advice"]
