"""The end-to-end benchmark's scene: one material whose three brick maps are found as one tiling stack
with the colour spaces and the normal map's scale and bias the scene states."""
from __future__ import annotations

from pathlib import Path

import OpenImageIO as oiio

from benchscripts import load_benchmark

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def test_the_scene_holds_one_tiling_stack_of_three_maps_at_the_size_asked(tmp_path):
    import seamless_usd

    bench = load_benchmark("endtoend")
    textures = tmp_path / "textures"
    textures.mkdir()
    for name, source in (("brick_base_gray", "brick_albedo.png"), ("brick_normal", "brick_normal.png"),
                         ("brick_roughness", "brick_roughness.png")):  # the bundled brick stands in for shared/
        buf = oiio.ImageBuf(str(TEXTURES / source))
        assert buf.write(str(textures / f"{name}.jpg"))
    scene = bench.build_scene(tmp_path / "scene", 160, textures)
    result = seamless_usd.scan(scene)
    [stack] = result.stacks
    assert stack.intent == "tiling", stack.intent_reason
    spaces = {m.asset: (m.color_space.value, m.is_normal) for m in stack.maps}
    assert spaces == {"./brick_base_gray_160.png": ("sRGB", False), "./brick_normal_160.png": ("raw", True),
                      "./brick_roughness_160.png": ("raw", False)}
    for m in stack.maps:
        spec = oiio.ImageInput.open(str(tmp_path / "scene" / m.asset[2:])).spec()
        assert (spec.width, spec.height) == (160, 160)
    [normal] = [m for m in stack.maps if m.is_normal]
    assert tuple(normal.scale[:3]) == (2, 2, 2) and tuple(normal.bias[:3]) == (-1, -1, -1)
