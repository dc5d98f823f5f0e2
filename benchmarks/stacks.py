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

__all__ = ["MapFile", "StackSpec", "STACKS", "QUALITY_STACKS", "FULLRES_STACKS", "SAMPLES_DIR", "SHARED_DIR", "load_stack"]

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
    rotated: tuple[float, int] | None = None  # (degrees clockwise, side): see :func:`_rotated`


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
    **{f"rot{angle}_{what}_{side}": StackSpec("shared", maps, rotated=(angle, side), note=(
        f"{side} px window of the MaterialX {what} maps repeated and turned {angle} degrees: long structure "
        f"at the images' own texel scale, no lattice along the axes"))
       for what, maps in (("wood", (MapFile("color", "wood_color.jpg", 3), MapFile("roughness", "wood_roughness.jpg", 1))),
                          ("brick", (MapFile("base_gray", "brick_base_gray.jpg", 1),
                                     MapFile("normal", "brick_normal.jpg", 3, True),
                                     MapFile("roughness", "brick_roughness.jpg", 1))))
       for angle in (23, 61) for side in (512, 2048, 4096)},
    **{f"{kind}_{side}": StackSpec("synthetic", (), note=(
        f"synthetic {side} px {'stone cells with dark joints' if kind == 'cells' else 'long curved stripes'} "
        f"(benchmarks/synthetic.py), non-periodic crop: colour and height maps"))
       for kind in ("cells", "stripes") for side in (512, 2048)},
    "mx_cloth": StackSpec(
        "shared",
        (MapFile("color", "cloth.jpg", 3),),
        window=(197, 163, 400, 200),
        note="400 px window at (197, 163) of the 640 px MaterialX cloth photo, 200 px",
    ),
}


#: The quality benchmark's stacks (the default of ``benchmarks/quality.py``).
QUALITY_STACKS = ("brick", "wood", "cloth", "mx_brick", "mx_wood", "mx_cloth")
#: The full-resolution quality benchmark (``benchmarks/quality.py --stacks fullres``): six stacks at 2048 px and
#: two at 4096 px, all structured and none periodic along the axes.
FULLRES_STACKS = ("rot23_wood_2048", "rot61_wood_2048", "rot23_brick_2048", "rot61_brick_2048", "cells_2048",
                  "stripes_2048", "rot23_wood_4096", "rot23_brick_4096")


def _rotated(pixels: np.ndarray, degrees: float, side: int) -> np.ndarray:
    """A ``side`` px window of a periodic image (H, W, C) turned by ``degrees`` clockwise about its centre.

    The image tiles, so its repeat has no seam: every output texel samples the repeated image (bicubic,
    coordinates taken modulo the image), however large the window. Structured, non-periodic along the
    axes, at the image's own texel scale.
    """
    import torch
    import torch.nn.functional as F

    h, w = pixels.shape[:2]
    a = np.radians(degrees)
    c = (np.arange(side) - (side - 1) / 2.0).astype(np.float64)
    yy, xx = np.meshgrid(c, c, indexing="ij")
    sx = (np.cos(a) * xx + np.sin(a) * yy + w / 2.0) % w  # source position of each output texel
    sy = (-np.sin(a) * xx + np.cos(a) * yy + h / 2.0) % h
    pad = 3
    img = torch.from_numpy(np.ascontiguousarray(pixels.transpose(2, 0, 1)))[None]
    img = F.pad(img, (pad,) * 4, mode="circular")
    gx = (sx + pad + 0.5) / img.shape[3] * 2 - 1  # align_corners=False texel centres
    gy = (sy + pad + 0.5) / img.shape[2] * 2 - 1
    grid = torch.from_numpy(np.stack([gx, gy], -1).astype(np.float32))[None]
    out = F.grid_sample(img, grid, mode="bicubic", padding_mode="border", align_corners=False)[0]
    return np.clip(out.permute(1, 2, 0).numpy(), 0.0, 1.0)


def _read(path: Path, window: tuple[int, int, int, int] | None, max_size: int | None,
          rotated: tuple[float, int] | None = None) -> np.ndarray:
    """File values as float32 ``(H, W, C)`` in [0, 1], turned, windowed and resized with OpenImageIO."""
    buf = oiio.ImageBuf(str(path))
    if buf.has_error:
        raise RuntimeError(f"cannot read @{path}@: {buf.geterror()}")
    nch = buf.nchannels
    if rotated is not None:
        turned = _rotated(np.asarray(buf.get_pixels(oiio.FLOAT), dtype=np.float32), *rotated)
        buf = oiio.ImageBuf(np.ascontiguousarray(turned))
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
    if spec.folder == "synthetic":
        import synthetic

        kind, side = name.rsplit("_", 1)
        side = int(side)
        made = getattr(synthetic, kind)(side, (64 if kind == "cells" else 48) * side / 512, seed=0)
        if max_size is not None and max_size < side:
            f = side // max_size
            made = {k: (v.reshape(side // f, f, side // f, f, -1).mean(axis=(1, 3)), n) for k, (v, n) in made.items()}
        return made
    folder = SAMPLES_DIR if spec.folder == "samples" else textures_dir
    if not folder.is_dir():
        raise FileNotFoundError(
            f"stack {name!r} needs the MaterialX images in @{folder}@ (see its README); "
            f"pass --textures-dir, or leave {name!r} out of --stacks"
        )
    out = {}
    for m in spec.maps:
        v = _read(folder / m.file, spec.window, max_size, spec.rotated)[..., : m.channels] * 2.0 - 1.0
        if m.is_normal and spec.rotated is not None:  # the vectors turn with the picture (x right, y up)
            a = np.radians(spec.rotated[0])
            x, y = v[..., 0].copy(), v[..., 1].copy()
            v[..., 0], v[..., 1] = x * np.cos(a) + y * np.sin(a), -x * np.sin(a) + y * np.cos(a)
        out[m.name] = (v, m.is_normal)
    return out
