#!/usr/bin/env python3
"""Regenerate the sample textures from the MaterialX project's images (Apache-2.0).

The source maps are periodic; each sample cuts the same off-grid window from every map of a
stack (so the result is *not* tileable) and downscales it. Run from the repository root with the
source images folder as argument::

    python3 sample_assets/make_textures.py /path/to/MaterialX/resources/Images
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

OUT = Path(__file__).resolve().parent / "textures"


def window(src: Path, x: int, y: int, size: int, out_size: int) -> np.ndarray:
    buf = oiio.ImageBuf(str(src))
    roi = oiio.ROI(x, x + size, y, y + size, 0, 1, 0, buf.nchannels)
    cut = oiio.ImageBufAlgo.cut(buf, roi)
    small = oiio.ImageBufAlgo.resize(cut, roi=oiio.ROI(0, out_size, 0, out_size, 0, 1, 0, buf.nchannels))
    return small.get_pixels(oiio.FLOAT)


SRGB = {"oiio:ColorSpace": "srgb_rec709_scene"}  # PNG sRGB chunk: colour maps
RAW = {"oiio:ColorSpace": "lin_rec709_scene"}  # no sRGB chunk: data maps read as raw under auto


def write(name: str, pixels: np.ndarray, dtype=oiio.UINT8, extra: dict | None = None) -> None:
    if pixels.ndim == 2:
        pixels = pixels[..., None]
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, dtype)
    for k, v in (extra or {}).items():
        spec.attribute(k, v)
    out = oiio.ImageOutput.create(str(OUT / name))
    out.open(str(OUT / name), spec)
    out.write_image(np.clip(pixels, 0, 1) if dtype in (oiio.UINT8, oiio.UINT16) else pixels)
    out.close()


def main(src_dir: str) -> None:
    src = Path(src_dir)
    OUT.mkdir(exist_ok=True)
    # Brick wall: 700 px window at (137, 291), 256 px maps.
    at = dict(x=137, y=291, size=700, out_size=256)
    gray = window(src / "brick_base_gray.jpg", **at)[..., :1]
    # base_gray is meant to be multiplied by a brick colour; do it in linear light.
    lin = np.where(gray <= 0.04045, gray / 12.92, ((gray + 0.055) / 1.055) ** 2.4)
    tint = np.array([0.62, 0.36, 0.27], np.float32)
    albedo_lin = lin * tint
    albedo = np.where(albedo_lin <= 0.0031308, albedo_lin * 12.92, 1.055 * albedo_lin ** (1 / 2.4) - 0.055)
    write("brick_albedo.png", albedo, extra=SRGB)
    write("brick_normal.png", window(src / "brick_normal.jpg", **at), extra=RAW)
    rough = window(src / "brick_roughness.jpg", **at)[..., :1]
    write("brick_roughness.png", rough, extra=RAW)
    mask = window(src / "brick_mask.jpg", **at)[..., :1]
    # Packed ORM (glTF convention): R occlusion (mortar darker), G roughness, B metallic (none).
    occlusion = 1.0 - 0.45 * mask
    write("brick_orm.png", np.concatenate([occlusion, rough, np.zeros_like(rough)], axis=-1), extra=RAW)
    # 16-bit roughness and a half-float EXR albedo (linear) for bit-depth coverage.
    write("brick_roughness16.png", rough, oiio.UINT16, extra=RAW)
    write("brick_albedo_linear.exr", albedo_lin.astype(np.float32), oiio.HALF, extra=RAW)
    # Wood: 900 px window at (413, 97), 256 px maps.
    at = dict(x=413, y=97, size=900, out_size=256)
    write("wood_color.png", window(src / "wood_color.jpg", **at), extra=SRGB)
    write("wood_roughness.png", window(src / "wood_roughness.jpg", **at)[..., :1], extra=RAW)
    # Cloth: 400 px window at (61, 133) of the 640 px photo, 200 px map.
    write("cloth.png", window(src / "cloth.jpg", x=61, y=133, size=400, out_size=200), extra=SRGB)


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "../shared/textures")
