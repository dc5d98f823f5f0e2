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
# The presets and the input types are plain Python; every other name is imported when first used (PEP 562), so
# that a run which finds every stack in its cache never pays for importing torch (about 1.5 s).
from importlib import import_module

from .config import PRESETS, SynthesisConfig, get_preset
from .advice import structure_advice, written_lattice_ratio
from .refinement.settings import RefineConfig
from .types import Candidate, MapInput, QResult, TileResult, TrainingProgress

_LAZY = {
    "SamplingProgress": ".gan.sample", "sample": ".gan.sample",
    "TrainedModel": ".gan.train", "train": ".gan.train",
    "LATTICE_TARGET": ".lattice.cut",
    "RefineResult": ".refinement.refine", "refine": ".refinement.refine",
    "MadeTile": ".tile", "downsample_maps": ".tile", "make_tile": ".tile",
}

__all__ = ["SynthesisConfig", "PRESETS", "get_preset", "MapInput", "train", "sample", "TrainedModel",
           "TileResult", "QResult", "Candidate", "TrainingProgress", "SamplingProgress",
           "RefineConfig", "RefineResult", "refine", "MadeTile", "make_tile", "downsample_maps", "LATTICE_TARGET",
           "written_lattice_ratio", "structure_advice"]


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
