"""The real texture stacks of the quality benchmark, read in the network domain.

``brick``, ``wood``, ``cloth``
    The bundled sample maps (``sample_assets/textures``), already off-grid windows of periodic
    textures, so not tileable.
``mx_brick``, ``mx_wood``, ``mx_cloth``
    Other off-grid windows cut from the MaterialX images in ``../shared/textures`` (relative to
    the repository root), the same window from every map of a stack, downscaled like the samples.

Maps enter the network domain as ``2 v - 1`` of their file values ``v`` in ``[0, 1]`` (colour stays
display-encoded; normal maps become vectors), which is the domain the metrics read.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

__all__ = ["MapFile", "StackSpec", "STACKS", "SAMPLES_DIR", "SHARED_DIR", "load_stack"]

ROOT = Path(__file__).resolve().parent.parent
SAMPLES_DIR = ROOT / "sample_assets" / "textures"
SHARED_DIR = ROOT.parent / "shared" / "textures"  # ../shared/textures from the repository root


@dataclass(frozen=True)
class MapFile:
    """One map of a stack: a name, the file, its channels and whether it holds normals."""

    name: str
    file: str
    channels: int  # channels kept (the first ones): 1 for grey/roughness maps stored as RGB
    is_normal: bool = False


@dataclass(frozen=True)
class StackSpec:
    """A stack of maps read from ``folder`` (``samples`` or ``shared``), optionally windowed.

    ``window`` is ``(x, y, size, out_size)``: a ``size`` px square at ``(x, y)`` resized to
    ``out_size`` px, cut the same from every map.
    """

    folder: str
    maps: tuple[MapFile, ...]
    window: tuple[int, int, int, int] | None = None
    note: str = ""


#: Stacks by name.
STACKS: dict[str, StackSpec] = {
    "brick": StackSpec(
        "samples",
        (
            MapFile("albedo", "brick_albedo.png", 3),
            MapFile("normal", "brick_normal.png", 3, True),
            MapFile("roughness", "brick_roughness.png", 1),
        ),
        note="sample: 700 px window at (137, 291) of the MaterialX brick, 256 px",
    ),
    "wood": StackSpec(
        "samples",
        (MapFile("color", "wood_color.png", 3), MapFile("roughness", "wood_roughness.png", 1)),
        note="sample: 900 px window at (413, 97) of the MaterialX wood, 256 px",
    ),
    "cloth": StackSpec(
        "samples",
        (MapFile("color", "cloth.png", 3),),
        note="sample: 400 px window at (61, 133) of the MaterialX cloth, 200 px",
    ),
    "mx_brick": StackSpec(
        "shared",
        (
            MapFile("base_gray", "brick_base_gray.jpg", 1),
            MapFile("normal", "brick_normal.jpg", 3, True),
            MapFile("roughness", "brick_roughness.jpg", 1),
        ),
        window=(1013, 389, 700, 256),
        note="700 px window at (1013, 389) of the 2048 px MaterialX brick maps, 256 px",
    ),
    "mx_wood": StackSpec(
        "shared",
        (MapFile("color", "wood_color.jpg", 3), MapFile("roughness", "wood_roughness.jpg", 1)),
        window=(1091, 733, 900, 256),
        note="900 px window at (1091, 733) of the 2048 px MaterialX wood maps, 256 px",
    ),
    "mx_cloth": StackSpec(
        "shared",
        (MapFile("color", "cloth.jpg", 3),),
        window=(197, 163, 400, 200),
        note="400 px window at (197, 163) of the 640 px MaterialX cloth photo, 200 px",
    ),
}


def _read(path: Path, window: tuple[int, int, int, int] | None, max_size: int | None) -> np.ndarray:
    """File values as float32 ``(H, W, C)`` in [0, 1], windowed and resized with OpenImageIO."""
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise RuntimeError(f"cannot read @{path}@: {buf.geterror()}")
    nch = buf.nchannels
    if window is not None:
        x, y, size, out_size = window
        spec = buf.spec()
        if x + size > spec.width or y + size > spec.height:
            raise RuntimeError(f"window {window} does not fit @{path}@ ({spec.width}x{spec.height})")
        buf = oiio.ImageBufAlgo.cut(buf, oiio.ROI(x, x + size, y, y + size, 0, 1, 0, nch))
        buf = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, out_size, 0, out_size, 0, 1, 0, nch))
    if max_size is not None:
        spec = buf.spec()
        scale = max_size / max(spec.width, spec.height)
        if scale < 1:
            w, h = max(8, round(spec.width * scale)), max(8, round(spec.height * scale))
            buf = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, w, 0, h, 0, 1, 0, nch))
    return np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32)


def load_stack(
    name: str, textures_dir: Path = SHARED_DIR, max_size: int | None = None
) -> dict[str, tuple[np.ndarray, bool]]:
    """The maps of stack ``name`` in the network domain: ``{map: (pixels (H, W, C), is_normal)}``.

    Parameters
    ----------
    name : str
        A key of :data:`STACKS`.
    textures_dir : pathlib.Path
        Folder of the MaterialX images for the ``mx_*`` stacks.
    max_size : int, optional
        Downscale so that the longest side is at most this (quick runs).
    """
    spec = STACKS[name]
    folder = SAMPLES_DIR if spec.folder == "samples" else textures_dir
    if not folder.is_dir():
        raise FileNotFoundError(
            f"stack {name!r} needs the MaterialX images in @{folder}@ (see its README); "
            f"pass --textures-dir, or leave {name!r} out of --stacks"
        )
    out = {}
    for m in spec.maps:
        v = _read(folder / m.file, spec.window, max_size)[..., : m.channels]
        out[m.name] = (v * 2.0 - 1.0, m.is_normal)
    return out
