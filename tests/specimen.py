"""Test helper: a specimen report from a real stack without training, for the report's tests and for layout work.

The tile is made from the source itself, so the page has real pixels and real figures in seconds:

* ``"periodic"``: the periodic component of the source (Moisan's periodic-plus-smooth
  decomposition), tileable by construction, at the source's scale (a passing result);
* ``"rolled"``: the source shifted by half its size, so its own border seam lands on the tile's
  centre lines (a result with a visible centre seam);
* ``"magnified"``: the periodic component's top-left quarter enlarged 2x (a result whose features
  are twice too large: a scale ratio near 0.5).

Run ``python tests/specimen.py SCENE OUT.html`` to write one page.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from seamless_usd.report.model import MapReport, Report, StackReport, StackStatus
from seamless_usd.report.previews import stack_previews

__all__ = ["KINDS", "specimen_tile", "specimen_stack", "specimen_report"]

KINDS = ("periodic", "rolled", "magnified")


def _periodic(values: np.ndarray, is_normal: bool) -> np.ndarray:
    from seamless_usd.metrics import periodic_smooth_decomposition

    out = np.stack([periodic_smooth_decomposition(values[..., c])[0] for c in range(values.shape[2])], axis=2)
    out = np.clip(out, -1.0, 1.0)
    if is_normal and out.shape[2] >= 3:
        n = out[..., :3]
        out[..., :3] = n / np.maximum(np.linalg.norm(n, axis=2, keepdims=True), 1e-8)
    return out.astype(np.float32)


def specimen_tile(values: np.ndarray, kind: str, is_normal: bool = False) -> np.ndarray:
    """A tile of ``kind`` (see the module docstring) made from one map's network-domain values."""
    v = np.asarray(values, dtype=np.float32)
    if kind == "rolled":
        return np.roll(v, (v.shape[0] // 2, v.shape[1] // 2), axis=(0, 1))
    if kind == "periodic":
        return _periodic(v, is_normal)
    if kind == "magnified":
        p = _periodic(v, is_normal)
        h, w = v.shape[:2]
        return np.ascontiguousarray(p[: h // 2, : w // 2].repeat(2, axis=0).repeat(2, axis=1)[:h, :w])
    raise ValueError(f"unknown specimen kind {kind!r}; valid: {', '.join(KINDS)}")


def specimen_stack(scene: str | Path, kind: str = "periodic", size: int | None = None, stack_index: int = 0,
                   noise: float = 0.0, seed: int = 0) -> StackReport:
    """The report of one stack of ``scene`` with a :func:`specimen_tile` per map.

    Parameters
    ----------
    scene : a USD stage or ``.mtlx`` document with at least one texture stack.
    kind : how the tiles are made (:data:`KINDS`).
    size : resample the maps to ``size x size`` first (None: as they are).
    stack_index : which stack of the scan.
    noise : standard deviation of fine grain added to the sources (network domain), to make the
        pictures hard to compress (a worst case for the page's weight).
    """
    from seamless_usd import metrics
    from seamless_usd.discover import scan_paths
    from seamless_usd.imaging.normals import renormalise
    from seamless_usd.imaging.resample import resample
    from seamless_usd.imaging.stack import load_stack_pixels

    stack = scan_paths([str(scene)]).stacks[stack_index]
    pixels = load_stack_pixels(stack.maps)
    rng = np.random.default_rng(seed)
    sources, tiles, rows = [], [], []
    for m, v in zip(stack.maps, pixels.values):
        if size:
            v = np.clip(resample(v, (size, size)), -1.0, 1.0)
        if noise:
            v = np.clip(v + rng.normal(0.0, noise, v.shape).astype(np.float32), -1.0, 1.0)
        if m.is_normal and v.shape[2] >= 3:
            v[..., :3] = renormalise(v[..., :3])
        t = specimen_tile(v, kind, m.is_normal)
        sources.append(v)
        tiles.append(t)
        rows.append(MapReport.for_map(
            m, output=f"tileable/{Path(m.asset).stem}.{kind}.png",
            metrics=metrics.map_metrics(t, v, is_normal=m.is_normal),
            source_metrics=metrics.map_metrics(v, None, is_normal=m.is_normal),
        ))
    failing = [f"{', '.join(r.roles)}: {f}" for r in rows
               for f in metrics.failing_figures(r.metrics, tuple(metrics.TARGETS))]
    h, w = tiles[0].shape[:2]
    return StackReport(
        id=stack.id, material=stack.material, source=str(scene),
        status=StackStatus.NOT_PASSED if failing else StackStatus.PASSED,
        maps=rows, origin="trained", crop_size=(h // 2, w // 2), tile_size=(h, w),
        working_size=(sources[0].shape[1], sources[0].shape[0]), uv_scale=(1.0, 1.0),
        q={"passed": not failing}, intent="tiling", intent_reason="specimen: tiles made without training",
        failing=failing, previews=stack_previews(stack.maps, sources, tiles, (1.0, 1.0)),
    )


def specimen_report(scenes: list[str | Path], kind: str = "periodic", **kwargs) -> Report:
    """A :class:`Report` with the first stack of each scene (see :func:`specimen_stack`)."""
    report = Report(sources=[str(s) for s in scenes], tool_version="specimen")
    report.stacks = [specimen_stack(s, kind, **kwargs) for s in scenes]
    return report


if __name__ == "__main__":  # pragma: no cover - a layout aid
    from seamless_usd.report.html import write_html

    scene, out = sys.argv[1], Path(sys.argv[2])
    write_html(specimen_report([scene], sys.argv[3] if len(sys.argv) > 3 else "periodic"), out)
    print(out)
