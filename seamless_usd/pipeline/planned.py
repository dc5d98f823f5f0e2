"""Authoring inputs for stacks that are not trained: an already-tileable stack kept as it is, and what a
dry run would write."""
from __future__ import annotations

from pathlib import Path

from seamless_usd.version import __version__
from seamless_usd.textures import TextureStack
from seamless_usd.naming import stack_tile_filenames
from seamless_usd.pipeline.options import Options

__all__ = ["planned_result", "wrap_only_result"]


def wrap_only_result(stack: TextureStack):
    """Authoring input for an already-tileable stack: its own maps, wrap = repeat, no UV change."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult

    prov = Provenance(source_asset="", crop_size=(0, 0), uv_scale=(1.0, 1.0), q_passed=None, q_tau=0.0,
                      q_band_min=(0.0, 0.0), model_hash="", tool_version=__version__, passed=True,
                      verdict=f"already seamless, judged against itself ({stack.intent_reason})")
    maps = [MapResult(map=m, output_path=Path(m.resolved)) for m in stack.maps if m.resolved]
    return StackResult(stack=stack, maps=maps, uv_scale=(1.0, 1.0), provenance=prov, wrap_only=True)


def planned_result(stack: TextureStack, out_dir: Path, options: Options, tiles_of: str | None = None):
    """What a dry run shows authoring: the tile paths that would be written, and the UV scale if the
    first candidate passes Q: a source-sized refined tile keeps the UVs (scale 1); the paper's tile
    of the whole texture (c = working size) halves them. A dry run reads no pixels, so it cannot
    tell a repeating stack whose written tile will be a lattice cut (smaller, with a larger scale).
    ``tiles_of``: the id of an identical stack planned earlier into the same folder, whose tiles this one reuses
    (as the run does)."""
    from seamless_usd.authoring import MapResult, Provenance, StackResult, uv_scale_for
    from seamless_usd.imaging import WorkingResolution, output_extension

    sizes = [(m.image.width, m.image.height) for m in stack.maps if m.image is not None]
    working = WorkingResolution(max_size=options.max_size).working_size(sizes) if sizes else (1, 1)
    if options.tile_size == "source" and options.refine != "off":
        uv, crop = (1.0, 1.0), (working[0] // 2, working[1] // 2)
    else:
        uv, crop = uv_scale_for(working, working), working
    read = [m for m in stack.maps if m.image is not None]
    names = stack_tile_filenames(read, tiles_of or stack.id, [output_extension(m.image) for m in read])
    maps = [MapResult(map=m, output_path=out_dir / name) for m, name in zip(read, names)]
    prov = Provenance(
        source_asset=", ".join(m.asset for m in stack.maps), crop_size=crop, uv_scale=uv, q_passed=None,
        q_tau=0.0, q_band_min=(0.0, 0.0), model_hash="", tool_version=__version__,
    )
    return StackResult(stack=stack, maps=maps, uv_scale=uv, provenance=prov)
