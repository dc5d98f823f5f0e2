"""One options dataclass shared by the Python API, the CLI and the DCC hooks."""
from __future__ import annotations

import os

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from seamless_usd.errors import UsageError

__all__ = ["Options", "ProgressEvent", "REFINE_MODES", "TILE_SIZES", "check_device"]


@dataclass(frozen=True)
class ProgressEvent:
    """What a long run reports: a stack starting/finishing, or training/sampling progress."""

    kind: str  # "stack-start", "stage" (``detail``: a long step begins, in words), "train", "sample", "stack-done";
    #            "report": a library report's page written
    #            (``index``: pages written, ``total``: pages, ``stack_id`` empty)
    stack_id: str
    index: int  # 0-based index of the stack among the stacks to process
    total: int  # stacks to process in this run
    detail: Any = None  # synthesis progress record for "train"/"sample"; for "stack-done" the job's result (its
    #                     outcome, with ``passed``, or the exception it ended in)


#: Values of ``Options.refine`` and ``Options.tile_size`` (the CLI's choices); ``TILE_SIZES`` is also
#: ``synthesis.tile.TILE_SIZES``, kept apart so that options load without torch.
REFINE_MODES = ("on", "gan", "off")
TILE_SIZES = ("source", "paper")


@dataclass(frozen=True)
class Options:
    """How to process: everything the CLI can say, as one value.

    ``mode`` is a :class:`seamless_usd.authoring.WriteMode` (new layer by default, in place with
    backups, or dry run). ``output_dir`` defaults to ``<stage dir>/tileable``; it is required for an
    in-memory stage with an anonymous root layer.
    """

    preset: str = "default"  # synthesis preset name (see seamless_usd.synthesis.PRESETS)
    materials: tuple[str, ...] = ()  # fnmatch patterns on material paths; empty = all
    mode: Any = None  # WriteMode; None means WriteMode.NEW_LAYER
    plan_mode: Any = None  # DRY_RUN: which writing mode to plan for (WriteMode.NEW_LAYER or IN_PLACE)
    output_layer: Path | None = None  # NEW_LAYER: where the override layer goes (default scene.seamless.usda)
    output_dir: Path | None = None  # where tileable maps go (default <stage dir>/tileable)
    device: str | None = None  # "cpu", "cuda", "cuda:1"; None picks CUDA when present
    seed: int = 0
    report: Path | None = None  # HTML report path; the JSON report goes beside it (.json)
    cache_dir: Path | None = None  # trained models and checkpoints; None = the user's cache dir
    max_size: int | None = None  # working-resolution cap (longest side, px); None = native size
    max_pixels: int | None = 1 << 28  # images whose header claims more pixels are refused before decoding
    iterations: int | None = None  # override the preset's training iterations
    seeds: int | None = None  # override the preset's seeds trained side by side (the best tile is kept)
    scheduler: str | None = None  # None: in this process; "local:N": N local Dask workers; "tcp://host:port"
    jobs: int | None = None  # stacks trained at once (local workers); None: 1 in process, N for local:N
    refine: str = "on"  # "on": the GAN tile refined to the source's resolution or a tile cut from the source
    #                     (lattice periods, one window or a quilt) when that passes or scores better; "gan": the
    #                     refined GAN tile only; "off": the pure SeamlessGAN tile
    tile_size: str = "source"  # "source": tile has the source's pixel size; "paper": the paper's 2c x 2c tile
    straighten: bool = False  # turn a stack whose lines run at an angle until they run along the axes, and tile
    #                         that; the turn is authored in the asset's UVs, so the asset looks as before
    write_straight: bool = False  # straighten (implies it) with no UV turn: the tile is written straight and the
    #                               pattern on the asset turns by the angle
    force: bool = False  # process every stack whatever its tiling intent (uv-atlas, already-tileable, other)
    force_materials: tuple[str, ...] = ()  # fnmatch patterns of materials processed whatever their intent
    progress: Callable[[ProgressEvent], None] | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        """The command line's rules, for the API and the hooks: a value it would refuse is a UsageError here, when
        the options are made, not a TypeError part-way through a run."""
        for name, valid in (("refine", REFINE_MODES), ("tile_size", TILE_SIZES)):
            if getattr(self, name) not in valid:
                raise UsageError(f"Options.{name} must be one of {', '.join(valid)}; got {getattr(self, name)!r}")
        for name in ("materials", "force_materials"):  # one pattern given as itself, not as its letters
            if isinstance(getattr(self, name), str):
                object.__setattr__(self, name, (getattr(self, name),))
            patterns = getattr(self, name)
            if not isinstance(patterns, (tuple, list)) or not all(isinstance(p, str) for p in patterns):
                raise UsageError(f"Options.{name} must be a pattern or a list of patterns (strings); got {patterns!r}")
            object.__setattr__(self, name, tuple(patterns))
        for name in ("output_layer", "output_dir", "report", "cache_dir"):
            value = getattr(self, name)
            if value == "":  # an empty setting (a hook's empty field): the default, not the working folder
                object.__setattr__(self, name, None)
            elif value is not None and not isinstance(value, (str, os.PathLike)):
                raise UsageError(f"Options.{name} must be a path; got {value!r}")
        for name in ("seed", "seeds", "iterations", "max_pixels", "max_size", "jobs"):
            value = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
                raise UsageError(f"Options.{name} must be a whole number; got {value!r}")
        if not 0 <= self.seed <= MAX_SEED:
            raise UsageError(f"seed {self.seed}: must be from 0 to {MAX_SEED}")
        for name in ("seeds", "iterations", "max_pixels", "jobs"):
            value = getattr(self, name)
            if value is not None and value < 1:
                raise UsageError(f"{name} {value}: must be at least 1")
        if self.progress is not None and not callable(self.progress):
            raise UsageError(f"Options.progress must be a function of one progress event; got {self.progress!r}")

    def with_(self, **changes: Any) -> "Options":
        return replace(self, **changes)

    def summary(self) -> dict[str, Any]:
        """JSON-friendly view for reports (no callables)."""
        out = {}
        for name in (
            "preset", "materials", "mode", "plan_mode", "output_layer", "output_dir", "device", "seed",
            "cache_dir", "max_size", "max_pixels", "iterations", "seeds", "scheduler", "jobs", "refine", "tile_size",
            "straighten", "write_straight", "force", "force_materials",
        ):
            value = getattr(self, name)
            if isinstance(value, Path):
                value = str(value)
            elif isinstance(value, tuple):
                value = list(value)
            elif hasattr(value, "value"):
                value = value.value
            out[name] = value
        return out


#: The largest seed torch and numpy both take.
MAX_SEED = (1 << 32) - 1


def check_device(name: str) -> None:
    """A usage error, before any work, for a device that does not exist here."""
    import torch

    try:
        device = torch.device(name)
    except RuntimeError:
        raise UsageError(f"--device {name!r} is not a device name; use cpu, cuda or cuda:N") from None
    if device.type == "cuda":
        if not torch.cuda.is_available():
            raise UsageError(f"--device {name}: this machine has no usable CUDA device; use --device cpu or leave it out")
        if device.index is not None and device.index >= torch.cuda.device_count():
            raise UsageError(f"--device {name}: only {torch.cuda.device_count()} CUDA device(s) here")
    elif device.type != "cpu":
        raise UsageError(f"--device {name}: only cpu and cuda devices are supported")
