"""What a stack job returns (:func:`.stackjob.run_stack`): per-map outputs and measurements, the sampling facts
and the verdict on the written tiles, and how the client turns them into the stack's report and authoring input.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from seamless_usd.findings import Finding
from seamless_usd.pipeline.madefrom import made_fields, source_uv_scale, uv_turn_of
from seamless_usd.report.model import MapReport, Previews, StackReport, StackStatus
from seamless_usd.textures import TextureMap, TextureStack

__all__ = ["MapOutcome", "StackOutcome", "map_identity", "outcome_from_record", "reused_message"]


def map_identity(m: TextureMap) -> tuple[str, str]:
    """Maps of identical stacks are matched by file and channels used."""
    return (m.resolved, m.channels_used)


@dataclass
class MapOutcome:
    output: Path
    metrics: dict[str, float]
    source_metrics: dict[str, float]


@dataclass
class StackOutcome:
    """What a job returns: per-map outputs and measurements, and the sampling facts."""

    stack_id: str
    maps: dict[tuple[str, str], MapOutcome]  # map_identity -> outcome
    crop_size: tuple[int, int]
    tile_size: tuple[int, int]
    working_size: tuple[int, int]
    resampled: dict[str, Any]
    uv_scale: tuple[float, float]
    q: dict[str, Any]
    candidates: int
    timings: dict[str, float]
    model_hash: str
    device: str
    precision: str
    cached: bool = False
    output_dir: Path | None = None  # where the tiles were written
    peak_rss_mb: float = 0.0  # peak resident memory of the process that ran the job
    previews: Previews = field(default_factory=Previews, repr=False)
    findings: list[Finding] = field(default_factory=list)  # warnings while loading (e.g. non-finite pixels)
    failing: list[str] = field(default_factory=list)  # "asset: figure value (tolerance)" outside the tolerances
    verdict: dict = field(default_factory=dict)  # seamless_usd.verdict.Verdict.as_dict() of the written tiles
    cache_key: str = ""  # the cache entry the tiles came from (``pipeline.cache``)

    @property
    def passed(self) -> bool:
        """The verdict on the written tiles: no seam in any map, every fidelity figure inside its tolerance."""
        return bool(self.verdict.get("passed"))

    def reasons(self) -> list[str]:
        """Why the stack did not pass (empty when it passed), and for a stack whose joins cannot hide, what to do."""
        from seamless_usd.synthesis import structure_advice
        from seamless_usd.verdict import Verdict

        if not self.verdict:
            return ["not judged"]
        out = Verdict.from_dict(self.verdict).reasons()
        gan = self.resampled.get("gan") or {}
        advice = None if self.passed else structure_advice(gan.get("lattice") or {}, gan.get("layout"))
        return out + ([advice] if advice else [])

    def fill_report(self, report: StackReport, stack: TextureStack, reused: bool) -> None:
        # a copy of a tile that did not pass is not passed either: 'reused' is kept for a passed one
        report.status = (
            StackStatus.REUSED if reused and self.passed else StackStatus.PASSED if self.passed
            else StackStatus.NOT_PASSED
        )
        report.origin = ("duplicate" if reused else "cache" if self.cached else
                         "trained" if self.model_hash else "cut")  # no model: cut from the source, no GAN trained
        report.peak_rss_mb = round(self.peak_rss_mb, 1)
        if reused:
            report.duplicate_of = self.stack_id
            report.message = reused_message(self.stack_id, self)
        elif not self.passed:
            report.message = "; ".join(self.reasons())
        elif self.cached:
            report.message = "result taken from the cache"
        report.failing = list(self.failing)
        report.verdict = dict(self.verdict)
        for name in ("crop_size", "tile_size", "working_size", "resampled", "uv_scale", "q", "candidates",
                     "timings", "model_hash", "device", "precision"):
            setattr(report, name, getattr(self, name))
        report.previews = self.previews
        report.maps = [
            MapReport.for_map(m, out.output, out.metrics, out.source_metrics)
            for m, out in ((m, self.maps[map_identity(m)]) for m in stack.maps)
        ]

    def stack_result(self, stack: TextureStack):
        """The authoring input for ``stack`` (possibly an identical stack of another material)."""
        from seamless_usd.version import __version__
        from seamless_usd.authoring import MapResult, Provenance, StackResult

        prov = Provenance(
            source_asset=", ".join(m.asset for m in stack.maps),
            crop_size=(self.crop_size[1], self.crop_size[0]),  # authoring records (c_w, c_h)
            uv_scale=self.uv_scale,
            q_passed=None if not self.q else bool(self.q.get("passed")),
            q_tau=float(self.q.get("tau", 0.0)),
            q_band_min=tuple(self.q.get("band_min", (0.0, 0.0))),
            model_hash=self.model_hash,
            tool_version=__version__,
            passed=self.passed,
            verdict="seamless and faithful" if self.passed else "; ".join(self.reasons()),
            **made_fields(*(self.resampled.get(k) for k in ("straightened", "levelled", "evened"))),
        )
        maps = [MapResult(map=m, output_path=self.maps[map_identity(m)].output) for m in stack.maps]
        return StackResult(stack=stack, maps=maps, uv_scale=self.uv_scale, provenance=prov, uv_turn=self.uv_turn())

    def uv_turn(self):
        """The turn the asset's UVs give the tile back (``process --straighten``): the source's, in texel units;
        None when the tile was not straightened or is written straight (``--write-straight``)."""
        from seamless_usd.authoring import UVTurn

        turn = uv_turn_of(self.resampled.get("straightened"))
        return None if turn is None else UVTurn(*turn)


def outcome_from_record(stack: TextureStack, meta: dict, pixels, record: dict, previews: Previews, cached: bool,
                        out_dir: Path, cache_key: str = "") -> StackOutcome:
    """The job's result from the cache entry's ``meta`` and the judged ``record`` (see :mod:`.rerun`); ``pixels``: the
    stack as loaded, whose reading policy and warnings the result carries (None: a dry run, which reads no pixels).

    ``meta["straightened"]``: the tile was made from the straightened maps, and its UV scale, read against them,
    is brought back to the source's texel density; ``meta["levelled"]`` / ``meta["evened"]``: from the maps with
    their light levelled or their lattice evened (:mod:`.madefrom`)."""
    straightened = meta.get("straightened")
    maps = {tuple(json.loads(k)): MapOutcome(Path(o["path"]), dict(o["metrics"]), dict(o["source_metrics"]))
            for k, o in record["outputs"].items()}
    verdict = dict(record["verdict"])
    return StackOutcome(
        stack_id=stack.id,
        maps=maps,
        crop_size=tuple(int(v) for v in meta["crop_size"]),
        tile_size=tuple(int(v) for v in record["tile_size"]),
        working_size=tuple(int(v) for v in meta["scale"]["gan_working_size"]),
        resampled={**(pixels.policy_record if pixels is not None else {}), "gan": dict(meta["scale"]),
                   **({"straightened": straightened} if straightened else {}),
                   **{k: meta[k] for k in ("levelled", "evened") if meta.get(k)}},
        failing=list(verdict.get("failing", [])),
        verdict=verdict,
        uv_scale=source_uv_scale(meta["uv_scale"], straightened),
        q=dict(meta["q"]),
        candidates=int(meta["candidates"]),
        timings=dict(record["timings"]),
        model_hash=str(meta["model_hash"]),
        device=str(meta["device"]),
        precision=str(meta["precision"]),
        cached=cached,
        output_dir=out_dir,
        cache_key=cache_key,
        peak_rss_mb=_peak_rss_mb(),
        previews=previews,
        findings=[] if pixels is None else list(pixels.findings) + _turn_refused(straightened)
        + _coarser(stack, record["tile_size"], source_uv_scale(meta["uv_scale"], straightened), pixels.original_sizes)
        + _unread_channels(stack, pixels) + _dropped_parts(pixels),
    )


def _unread_channels(stack: TextureStack, pixels) -> list[Finding]:
    """A warning for each map whose file holds channels no input of the material reads (a packed mask wired by its
    red channel alone): the tile holds each such channel as the source's mean, not its values."""
    from seamless_usd.findings import Severity, asset_ref, prim_ref

    out = []
    for m, info, encoding in zip(pixels.maps, pixels.infos, pixels.encodings):
        unread = [i for i in range(encoding.file_channels) if i not in encoding.channels and i != encoding.alpha]
        if unread:
            names = [info.channel_names[i] if i < len(info.channel_names) else str(i) for i in unread]
            out.append(Finding(Severity.WARNING, "unread-channels", f"{prim_ref(m.node.strip('<>'))} {asset_ref(m.asset)}",
                               f"{'channels' if len(names) > 1 else 'channel'} {', '.join(names)} of the file "
                               f"{'are' if len(names) > 1 else 'is'} read by no input of the material, so the tile "
                               f"holds {'each' if len(names) > 1 else 'it'} as the source's mean, not its values "
                               "(connect it, or keep the source for whatever else reads it)", stack.material))
    return out


def _dropped_parts(pixels) -> list[Finding]:
    """A warning for each map whose file holds several parts (an OpenEXR's subimages, a TIFF's pages): the tile
    holds the first only, which is the one the material reads."""
    from seamless_usd.findings import Severity, asset_ref, prim_ref

    return [Finding(Severity.WARNING, "parts-not-kept", f"{prim_ref(m.node.strip('<>'))} {asset_ref(m.asset)}",
                    f"the file holds {info.parts} parts (subimages); the tile holds the first only, the one the "
                    "material reads: keep the source for whatever reads the others", m.material)
            for m, info in zip(pixels.maps, pixels.infos) if info.parts > 1]


#: A tile holding less than this share of its source's texels per UV unit is named coarser than the source.
COARSER = 0.95


def _coarser(stack: TextureStack, tile_hw, uv_scale, sizes) -> list[Finding]:
    """A warning when the tile holds fewer texels per UV unit than the stack's largest source map: read at a capped
    size (``--max-size``) or the SeamlessGAN tile at its working resolution (``--refine off``), it is blurrier on
    the asset than the source was."""
    width, height = max(w for w, _ in sizes), max(h for _, h in sizes)
    share = min(tile_hw[1] * uv_scale[0] / width, tile_hw[0] * uv_scale[1] / height)
    if share >= COARSER:
        return []
    from seamless_usd.findings import Severity, prim_ref

    return [Finding(Severity.WARNING, "coarser-tile", prim_ref(stack.material.strip("<>")),
                    f"the tile holds {share:.0%} of the source's texels per UV unit ({tile_hw[1]}x{tile_hw[0]} px "
                    f"where the source has {width}x{height}), so it is blurrier on the asset: a stack read at a capped "
                    "size (--max-size) or the SeamlessGAN tile kept at its working resolution (--refine off)",
                    stack.material)]


def _turn_refused(straightened: dict | None) -> list[Finding]:
    """A warning for each texture node whose UVs could not turn a straightened tile back (it is written straight)."""
    nodes = (straightened or {}).get("uv_turn_refused") or []
    if not nodes:
        return []
    from seamless_usd.authoring.types import Codes
    from seamless_usd.findings import Severity, prim_ref
    from seamless_usd.report.facts import UV_TURN_REFUSED

    return [Finding(Severity.WARNING, Codes.UNSUPPORTED_UV, prim_ref(node.strip("<>")),
                    f"the straightened tile is written straight, so the pattern on the asset turns by "
                    f"{straightened['degrees']:g} degrees: {UV_TURN_REFUSED}") for node in nodes]


def _peak_rss_mb() -> float:
    try:
        import resource
    except ImportError:  # pragma: no cover - Windows
        return 0.0
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # KiB on Linux


def reused_message(first: str, outcome: "StackOutcome") -> str:
    """The row message of a stack identical to ``first`` whose result (``outcome``) it reuses: why that did not
    pass, when it did not."""
    said = f"identical to stack {first}: its result is reused"
    return said if outcome.passed else f"{said}, not passed: {'; '.join(outcome.reasons())}"
