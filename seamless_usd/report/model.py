"""The run report: what was processed, how well, what was written, and the exit code it implies."""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import Any

import numpy as np

from seamless_usd.findings import Finding, Severity

__all__ = ["StackStatus", "MapReport", "Previews", "StackReport", "Report"]


class StackStatus(str, Enum):
    PASSED = "passed"  # trained, sampled, Q passed, maps written
    NOT_PASSED = "not-passed"  # maps written from the best candidate, but Q did not pass
    FAILED = "failed"  # an error stopped this stack; nothing of it was written
    REUSED = "reused"  # identical to a stack processed earlier in the run (or cached)
    LEFT_ALONE = "left-alone"  # not meant to tile (uv-atlas, already-tileable, other): untouched, with the reason
    PLANNED = "planned"  # dry run: would be processed


@dataclass
class MapReport:
    node: str  # texture node prim path / mtlx node path
    asset: str  # source asset as authored
    output: str | None  # written tileable file (absolute), None in a dry run or on failure
    roles: list[str]
    channels: str
    color_space: str
    metrics: dict[str, float] = field(default_factory=dict)  # seam/detail metrics of the new tile
    source_metrics: dict[str, float] = field(default_factory=dict)  # the same for the source tiled as is

    @classmethod
    def for_map(cls, m, output=None, metrics=None, source_metrics=None) -> "MapReport":
        """The report row of a discovered ``TextureMap`` and the tile written for it (if any)."""
        return cls(
            node=m.node, asset=m.asset, output=str(output) if output else None,
            roles=[r.role for r in m.roles], channels=m.channels_used, color_space=m.color_space.value,
            metrics=dict(metrics or {}), source_metrics=dict(source_metrics or {}),
        )


@dataclass
class Previews:
    """Display images for the HTML report (uint8 arrays); never in the JSON.

    Built by :func:`seamless_usd.report.previews.stack_previews`. The ``*_view`` pictures and the
    lit pictures all show one UV window (``view``), so source and tile are at the same texel scale.
    """

    source_view: dict[str, np.ndarray] = field(default_factory=dict)  # map node -> source repeated over the window
    tile_view: dict[str, np.ndarray] = field(default_factory=dict)  # map node -> new tile repeated over the window
    lit_source: np.ndarray | None = None  # the material lit from a grazing angle, source repeated
    lit_tile: np.ndarray | None = None  # the same with the new tiles
    lit_note: str = ""  # what the lit pictures are made of, or why there are none
    view: dict[str, Any] = field(default_factory=dict)  # ViewGeometry.to_dict(): window, tile_extent, size
    thumbnail: np.ndarray | None = None  # small picture of the result for the library index
    discriminator: np.ndarray | None = None  # D map with the seam bands drawn
    levels: list[tuple[str, np.ndarray]] = field(default_factory=list)  # (caption, uint8 RGB): the layout and
    #                                                                       each refinement level (run details)
    asset_source: np.ndarray | None = None  # a tile turned back in the UVs: the first map's source as authored
    asset_tile: np.ndarray | None = None  # ... and its tile as the asset shows it, through the UV turn and scale
    #: the pictures kept in a file instead (:mod:`.stored`: a run's cache keeps every stack's): read only while the
    #: report draws that stack (:func:`.stored.loaded`), so a library run holds none of them (``view`` and
    #: ``lit_note`` are set)
    stored: str = ""
    stored_info: dict[str, Any] = field(default_factory=dict)


@dataclass
class StackReport:
    id: str
    material: str
    source: str  # the stage or document the stack was found in
    status: StackStatus
    message: str = ""
    maps: list[MapReport] = field(default_factory=list)
    duplicate_of: str | None = None
    origin: str = ""  # "trained" (GAN trained), "cut" (from the source alone), "cache" (finished entry reused),
    # "duplicate" (same stack earlier in the run)
    peak_rss_mb: float = 0.0  # peak memory of the process that ran the stack
    crop_size: tuple[int, int] | None = None  # (c_h, c_w) input crop of the chosen candidate
    tile_size: tuple[int, int] | None = None  # (H, W) pixels of the written tile
    working_size: tuple[int, int] | None = None  # (W, H) working resolution of the stack
    resampled: dict[str, Any] = field(default_factory=dict)  # working-resolution policy applied
    uv_scale: tuple[float, float] | None = None
    q: dict[str, Any] = field(default_factory=dict)  # passed, tau, band minima
    candidates: int = 0
    timings: dict[str, float] = field(default_factory=dict)
    model_hash: str = ""
    device: str = ""
    precision: str = ""
    intent: str = ""  # tiling intent class: "tiling", "uv-atlas", "already-tileable", "other"
    intent_reason: str = ""  # the measured reason for the class, e.g. "UVs 0.11-0.89, 37 islands"
    variant: str = ""  # the variant selection the stack was found under ("shadingVariant=Black"; "": the stage's own)
    failing: list[str] = field(default_factory=list)  # fidelity figures outside their tolerances ("map: figure")
    verdict: dict[str, Any] = field(default_factory=dict)  # seamless_usd.verdict.Verdict.as_dict() of the written tiles
    previews: Previews = field(default_factory=Previews, repr=False)

    def to_dict(self) -> dict:
        return {
            "id": self.id,
            "material": self.material,
            "source": self.source,
            "status": self.status.value,
            "message": self.message,
            "duplicate_of": self.duplicate_of,
            "origin": self.origin,
            "peak_rss_mb": self.peak_rss_mb,
            "crop_size": list(self.crop_size) if self.crop_size else None,
            "tile_size": list(self.tile_size) if self.tile_size else None,
            "working_size": list(self.working_size) if self.working_size else None,
            "resampled": self.resampled,
            "uv_scale": list(self.uv_scale) if self.uv_scale else None,
            "q": self.q,
            "candidates": self.candidates,
            "timings": self.timings,
            "model_hash": self.model_hash,
            "device": self.device,
            "precision": self.precision,
            "intent": self.intent,
            "intent_reason": self.intent_reason,
            "variant": self.variant,
            "failing": list(self.failing),
            "verdict": dict(self.verdict),
            "maps": [dict(vars(m)) for m in self.maps],
        }


@dataclass
class Report:
    """One run of ``process``. The report owns the exit code."""

    sources: list[str] = field(default_factory=list)
    stacks: list[StackReport] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    layers_written: list[str] = field(default_factory=list)
    backups: list[str] = field(default_factory=list)
    plan: list[str] = field(default_factory=list)  # human-readable edits (dry run)
    unreadable: list[str] = field(default_factory=list)  # inputs that could not be opened
    variants: list[dict] = field(default_factory=list)  # variant spaces explored (VariantExploration.to_dict)
    options: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, float] = field(default_factory=dict)
    tool_version: str = ""
    interrupted: bool = False  # stopped by Ctrl-C while tiles were made: nothing of the stage edited

    @property
    def ok(self) -> bool:
        """True when every stack was done and passed the verdict (seamless and faithful), nothing failed and every
        texture could be read; in a dry run, when no stack planned from the cache is known not to pass (so its exit
        code says what the run's will)."""
        from seamless_usd.discover.select import UNREAD_SKIPS

        bad = {StackStatus.FAILED, StackStatus.NOT_PASSED}
        known_bad = [s for s in self.stacks if s.status is StackStatus.PLANNED and s.verdict.get("passed") is False]
        # a texture that cannot be read, even where the material's other maps are left alone (already tileable)
        unread = [f for f in self.findings if f.code in UNREAD_SKIPS]
        return not known_bad and not unread and not any(s.status in bad for s in self.stacks) and not any(
            f.severity is Severity.ERROR for f in self.findings
        )

    @property
    def exit_code(self) -> int:
        """0 all stacks passed; 1 some failed or did not pass (the rest were written); 2 unreadable input; 130
        stopped by Ctrl-C (:attr:`interrupted`)."""
        if self.interrupted:
            return 130
        if self.unreadable:
            return 2
        return 0 if self.ok else 1

    def counts(self) -> dict[str, int]:
        out = {s.value: 0 for s in StackStatus}
        for s in self.stacks:
            out[s.status.value] += 1
        out["trained"] = sum(1 for s in self.stacks if s.origin == "trained")
        out["from_cache"] = sum(1 for s in self.stacks if s.origin == "cache")
        return out

    def merge(self, other: "Report") -> None:
        """Add another run's results (one report per library run)."""
        self.sources += other.sources
        self.stacks += other.stacks
        self.findings += other.findings
        self.layers_written += other.layers_written
        self.backups += other.backups
        self.plan += other.plan
        self.unreadable += other.unreadable
        self.variants += other.variants
        for k, v in other.timings.items():
            self.timings[k] = self.timings.get(k, 0.0) + v

    def to_dict(self) -> dict:
        return {
            "tool_version": self.tool_version,
            "exit_code": self.exit_code,
            "counts": self.counts(),
            "sources": self.sources,
            "options": self.options,
            "stacks": [s.to_dict() for s in self.stacks],
            "findings": [f.to_dict() for f in self.findings],
            "layers_written": self.layers_written,
            "backups": self.backups,
            "plan": self.plan,
            "unreadable": self.unreadable,
            "variants": self.variants,
            "timings": self.timings,
            "interrupted": self.interrupted,
        }
