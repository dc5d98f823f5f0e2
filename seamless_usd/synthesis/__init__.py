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
# OMP_WAIT_POLICY=PASSIVE is set by the package itself (seamless_usd/__init__.py), before torch is first imported.
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
