"""Test helper: a one-material scene built as a real one is (usdkit's plane and UsdPreviewSurface), reading one
colour picture written beside it as an 8-bit sRGB PNG."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

ROOT = Path(__file__).resolve().parents[1]


def ground_scene(folder: Path, picture: np.ndarray, file_name: str, material: str) -> Path:
    """``folder/scene.usda``: a ground plane bound to ``/World/Looks/<material>``, whose diffuse colour reads
    ``picture`` ((H, W, 3) in [0, 1]) from ``./<file_name>``."""
    sys.path.insert(0, str(ROOT / "sample_assets"))
    from usdkit import bind, new_layer, plane, preview_material

    out = oiio.ImageBuf(np.ascontiguousarray(np.clip(picture, 0.0, 1.0), dtype=np.float32))
    out.set_write_format(oiio.UINT8)
    assert out.write(str(folder / file_name)), out.geterror()
    stage = new_layer(folder / "scene.usda", "World")
    stage.DefinePrim("/World", "Xform")
    bind(plane(stage, "/World/Ground", 4.0, 1.0, cells=1).GetPrim(), f"/World/Looks/{material}")
    preview_material(stage, f"/World/Looks/{material}", {"diffuseColor": (f"./{file_name}", "rgb", "sRGB")})
    stage.Save()
    return folder / "scene.usda"
