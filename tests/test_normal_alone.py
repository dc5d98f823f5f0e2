"""A normal map judged on its own (``check``, the scan's triage) is read as the vectors it holds, with its scale and
bias as ``process`` decodes it: the same vectors stored as 8-bit codes, 16-bit codes or signed floats get the same
answer, and a map that does not read as a normal map at all (a colour photo wired as one) is said to, by ``check``
and the scan alike."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Sdf, Usd, UsdShade

from seamless_usd.discover import scan_paths
from seamless_usd.pipeline.check import check_paths

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def _write(path: Path, values: np.ndarray, fmt) -> None:
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(values.shape[1], values.shape[0], 3, fmt))
    assert out.write_image(np.ascontiguousarray(values, np.float32))
    out.close()


def _scene(root: Path, files: dict[str, tuple[str, tuple | None]]) -> Path:
    """One material per file, its normal input reading it (with the scale and bias given, else none authored)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "sample_assets"))
    from usdkit import preview_material

    stage = Usd.Stage.CreateNew(str(root / "normals.usda"))
    for name, (file, scale_bias) in files.items():
        preview_material(stage, f"/Looks/{name}", {"normal": (f"./{file}", "rgb", "raw")}, wrap=None)
        if scale_bias:
            tex = UsdShade.Shader.Get(stage, f"/Looks/{name}/normalTex")
            tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set(scale_bias[0])
            tex.CreateInput("bias", Sdf.ValueTypeNames.Float4).Set(scale_bias[1])
    stage.GetRootLayer().Save()
    return root / "normals.usda"


def test_one_normal_map_stored_three_ways_gets_one_answer_and_a_photo_is_named(tmp_path):
    codes = oiio.ImageBuf(str(TEXTURES / "brick_normal.png")).get_pixels(oiio.FLOAT)[..., :3]
    vectors = 2.0 * codes - 1.0
    vectors /= np.linalg.norm(vectors, axis=2, keepdims=True)
    conventional = ((2, 2, 2, 1), (-1, -1, -1, 0))
    _write(tmp_path / "n8.png", (vectors + 1) / 2, oiio.UINT8)
    _write(tmp_path / "n16.png", (vectors + 1) / 2, oiio.UINT16)
    _write(tmp_path / "nf.exr", vectors, oiio.FLOAT)  # signed, nothing authored: read as stored
    _write(tmp_path / "photo.png", oiio.ImageBuf(str(TEXTURES / "brick_albedo.png")).get_pixels(oiio.FLOAT)[..., :3],
           oiio.UINT8)
    scene = _scene(tmp_path, {"N8": ("n8.png", conventional), "N16": ("n16.png", conventional), "NF": ("nf.exr", None),
                              "Photo": ("photo.png", conventional)})
    checked = {Path(i.name.strip("<>")).name: i for i in check_paths([scene]).items}
    scanned = {Path(s.material.strip("<>")).name: s for s in scan_paths([scene]).stacks}
    # 16-bit codes and signed floats hold the same vectors (8-bit codes round them): the same figures
    assert abs(checked["N16"].verdict["strongest"] - checked["NF"].verdict["strongest"]) < 0.02
    assert len({checked[n].passed for n in ("N8", "N16", "NF")}) == 1
    for name in ("N8", "N16", "NF"):
        assert not checked[name].note and "does not read as" not in scanned[name].intent_reason
    assert "does not read as a tangent-space normal map" in checked["Photo"].note
    assert "does not read as a tangent-space normal map" in scanned["Photo"].intent_reason


def test_a_one_channel_picture_wired_as_a_normal_map_is_judged_as_values_and_named(tmp_path):
    """One channel cannot hold vectors: it was made unit length, every texel +1 or -1, so a grey picture read a seam
    a billion times over the margin on the stage and passed on its own, and nothing said why."""
    grey = oiio.ImageBuf(str(TEXTURES / "brick_roughness.png")).get_pixels(oiio.FLOAT)[..., :1]
    out = oiio.ImageOutput.create(str(tmp_path / "grey.png"))
    assert out.open(str(tmp_path / "grey.png"), oiio.ImageSpec(grey.shape[1], grey.shape[0], 1, oiio.UINT8))
    assert out.write_image(np.ascontiguousarray(grey, np.float32))
    out.close()
    scene = _scene(tmp_path, {"Grey": ("grey.png", None)})
    [on_stage] = check_paths([scene]).items
    [alone] = check_paths([tmp_path / "grey.png"]).items
    [scanned] = scan_paths([scene]).stacks
    assert on_stage.verdict["strongest"] < 100 and on_stage.passed == alone.passed
    assert "does not read as a normal map: it has 1 channel(s)" in on_stage.note
    assert "does not read as a normal map: it has 1 channel(s)" in scanned.intent_reason
