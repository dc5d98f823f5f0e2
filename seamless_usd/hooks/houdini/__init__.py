"""Houdini USD ROP output processor: the DCC-independent part (no ``hou`` here).

The processor itself is ``husdplugins/outputprocessors/seamless_usd_tileable.py`` in this folder;
Houdini finds it when this folder is on ``HOUDINI_PATH`` (see docs/houdini.md)::

    python -c "import seamless_usd.hooks.houdini as h; print(h.HOUDINI_PATH)"

Its parameters appear on the USD ROP once "Seamless USD: Tileable Textures" is added under
Output Processors; they are :data:`PARMS`, named ``seamlessusd_<setting>``.
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookSettings

__all__ = ["HOUDINI_PATH", "PROCESSOR_NAME", "PARM_PREFIX", "ParmSpec", "PARMS", "settings_from_parms", "save_path_for"]

HOUDINI_PATH = Path(__file__).resolve().parent  # holds husdplugins/outputprocessors/
PROCESSOR_NAME = "seamless_usd_tileable"
PARM_PREFIX = "seamlessusd_"


@dataclass(frozen=True)
class ParmSpec:
    setting: str  # HookSettings field
    label: str
    kind: str  # "toggle" | "string" | "int" | "directory" | "file"
    help: str

    @property
    def name(self) -> str:
        return PARM_PREFIX + self.setting

    @property
    def default(self) -> object:
        value = getattr(HookSettings(), self.setting)
        return ",".join(value) if isinstance(value, tuple) else value


PARMS: tuple[ParmSpec, ...] = (
    ParmSpec("enabled", "Make Textures Tileable", "toggle", "Run SeamlessGAN on the saved material textures"),
    ParmSpec("preset", "Preset", "string", "Synthesis preset (default, draft, paper, ...)"),
    ParmSpec("materials", "Materials", "string", "Glob patterns on material prim paths, comma separated; empty: all"),
    ParmSpec("output_dir", "Output Folder", "directory",
             "Where tileable maps go; empty: 'tileable' beside each saved layer; relative: from that layer's folder"),
    ParmSpec("device", "Device", "string", "cpu, cuda or cuda:N; empty: CUDA when present"),
    ParmSpec("seed", "Seed", "int", "Random seed"),
    ParmSpec("max_size", "Max Size", "int", "Working resolution cap in pixels, longest side; 0: native"),
    ParmSpec("iterations", "Iterations", "int", "Training iterations; 0: the preset's"),
    ParmSpec("seeds", "Seeds", "int", "Seeds trained side by side, the best tile kept; 0: the preset's"),
    ParmSpec("report", "Report", "file", "HTML report path; empty: none"),
    ParmSpec("cache_dir", "Cache Folder", "directory", "Trained models; empty: the user's cache folder"),
    ParmSpec("straighten", "Straighten", "toggle",
             "Tile stacks whose lines run at an angle straight; the UVs turn the tile back, so the look is kept"),
    ParmSpec("dry_run", "Dry Run", "toggle", "Plan only; write nothing"),
    ParmSpec("strict", "Fail Save on Error", "toggle", "Make the ROP fail when a texture stack fails"),
)
assert {p.setting for p in PARMS} == set(common.SETTING_NAMES), "every hook setting needs a Houdini parm"


def settings_from_parms(values: Mapping[str, object]) -> HookSettings:
    """Settings from evaluated parm values (``None`` for a parm the ROP does not have)."""
    present = {k: v for k, v in values.items() if v is not None}
    return common.settings_from_mapping(present, prefix=PARM_PREFIX, strict_keys=False)


def save_path_for(layer_identifier: str, anonymous: bool, layer_save_path: str | None, rop_output: str | None) -> str | None:
    """Where a layer handed to ``processLayer`` will be written.

    Newer Houdini passes it (``layer_save_path``); otherwise a layer on disk is saved to its own
    identifier, and an anonymous layer is taken to be the ROP's output file.

    >>> save_path_for("anon:0x1", True, None, "/shots/a/scene.usd")
    '/shots/a/scene.usd'
    """
    if layer_save_path:
        return layer_save_path
    if not anonymous:
        return layer_identifier
    return rop_output or None
