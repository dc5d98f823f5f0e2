"""The lit preview: inputs taken from the right roles and channels, normals with their scale/bias and
Y convention, GGX roughness, a grazing light that shows normal and roughness seams."""
from __future__ import annotations

from types import SimpleNamespace as NS

import numpy as np
import pytest

from seamless_usd.textures import ColorSpace
from seamless_usd.imaging.normals import decode_normals, normal_scale_bias
from seamless_usd.report.lit import GRAZING_LIGHT, ShadingInputs, shade, shading_inputs, to_display
from seamless_usd.report.previews import stack_previews


def _map(node, roles, channels, color_space="raw", is_normal=False):
    return NS(node=node, roles=tuple(NS(role=r, channels=c) for r, c in roles), channels_used=channels,
              color_space=ColorSpace(color_space), is_normal=is_normal)


def _flat(shape=(4, 4), roughness=0.5):
    return ShadingInputs(albedo=np.full(shape + (3,), 0.5), normal=np.broadcast_to([0.0, 0.0, 1.0], shape + (3,)).copy(),
                         roughness=np.full(shape, roughness), metallic=np.zeros(shape), occlusion=np.ones(shape))


def test_packed_orm_roles_read_their_own_channels():
    orm = _map("/M/Orm", [("occlusion", "r"), ("roughness", "g"), ("metallic", "b")], "rgb")
    values = np.empty((2, 2, 3))
    values[..., 0], values[..., 1], values[..., 2] = 2 * 0.25 - 1, 2 * 0.5 - 1, 2 * 1.0 - 1
    s = shading_inputs([orm], [values])
    assert s.occlusion[0, 0] == pytest.approx(0.25) and s.roughness[0, 0] == pytest.approx(0.5)
    assert s.metallic[0, 0] == pytest.approx(1.0) and sorted(s.used) == ["metallic", "occlusion", "roughness"]


def test_albedo_is_linear_light():
    srgb = _map("/M/C", [("diffuseColor", "rgb")], "rgb", "sRGB")
    raw = _map("/M/C", [("base_color", "rgb")], "rgb", "raw")
    v = np.full((1, 1, 3), 2 * 0.5 - 1)
    assert shading_inputs([srgb], [v]).albedo[0, 0, 0] == pytest.approx(0.2140, abs=1e-3)  # sRGB 0.5
    assert shading_inputs([raw], [v]).albedo[0, 0, 0] == pytest.approx(0.5)


def test_a_normal_facing_the_grazing_light_is_brighter_than_one_facing_away():
    s = _flat((1, 3))
    toward = GRAZING_LIGHT.direction * [1, 1, 0] + [0, 0, 2.0]
    away = GRAZING_LIGHT.direction * [-1, -1, 0] + [0, 0, 2.0]
    s.normal[0, 0], s.normal[0, 2] = toward / np.linalg.norm(toward), away / np.linalg.norm(away)
    lum = shade(s).mean(axis=2)[0]
    assert lum[0] > 1.3 * lum[1] > 1.3 * lum[2]


def test_roughness_changes_the_specular_response():
    medium, smooth = _flat((1, 1), 0.5), _flat((1, 1), 0.1)
    # The viewer is off the mirror direction of a flat surface: the wider lobe of roughness 0.5 reaches it.
    assert shade(medium)[0, 0, 0] > 1.2 * shade(smooth)[0, 0, 0]


def test_a_directx_normal_map_lights_like_its_opengl_twin():
    rng = np.random.default_rng(0)
    n = rng.normal(0, 0.3, (8, 8, 3))
    n[..., 2] = 1.0
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    gl_file = (n + 1) / 2
    dx_file = gl_file.copy()
    dx_file[..., 1] = 1 - dx_file[..., 1]  # DirectX stores -Y
    gl = decode_normals(gl_file, *normal_scale_bias((2, 2, 2, 1), (-1, -1, -1, 0)))
    dx = decode_normals(dx_file, *normal_scale_bias((2, -2, 2, 1), (-1, 1, -1, 0)))  # as discovery declares it
    m = _map("/M/N", [("normal", "rgb")], "rgb", is_normal=True)
    np.testing.assert_allclose(shade(shading_inputs([m], [gl])), shade(shading_inputs([m], [dx])), atol=1e-6)


def test_a_roughness_seam_shows_in_the_lit_tile_not_in_the_flat_source():
    """Under the grazing light a roughness jump at the tile border is a visible line."""
    rough = _map("/M/R", [("roughness", "r")], "r")
    normal = _map("/M/N", [("normal", "rgb")], "rgb", is_normal=True)
    nmap = np.broadcast_to([0.0, 0.0, 1.0], (32, 32, 3)).copy()
    source_r = np.full((32, 32, 1), 0.0)
    tile_r = source_r.copy()
    tile_r[:, :16] = -0.8  # left half roughness 0.1, right half 0.5: a jump at the centre and the border
    p = stack_previews([normal, rough], [nmap, source_r], [nmap, tile_r], (1.0, 1.0), max_px=96)
    assert np.ptp(p.lit_source.astype(int)) <= 1
    column = p.lit_tile.astype(int).mean(axis=(0, 2))
    assert np.abs(np.diff(column)).max() > 10


def test_display_is_srgb_with_a_soft_shoulder():
    out = to_display(np.array([[[0.0, 0.18, 10.0]]]))
    assert out[0, 0, 0] == 0 and out[0, 0, 1] == 118 and out[0, 0, 2] >= 250
    assert to_display(np.array([[[0.18, 0.18, 0.18]]]), exposure=2.0)[0, 0, 0] > out[0, 0, 1]
