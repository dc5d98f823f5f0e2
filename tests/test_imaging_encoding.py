"""File values <-> network domain: MapEncoding, decode_map, encode_map, transfer functions, normals."""
from __future__ import annotations

import numpy as np
import pytest

from seamless_usd.textures import AuthoredAt, ColorSpace, ImageInfo, Origin, RoleUse, TextureMap
from seamless_usd.imaging import (
    MapEncoding,
    Tone,
    ValueRange,
    decode_map,
    encode_map,
    from_linear,
    normal_scale_bias,
    replace_nonfinite,
    to_linear,
)

RGBA = ("R", "G", "B", "A")


def texture_map(
    roles: tuple[tuple[str, str], ...] = (("diffuseColor", "rgb"),),
    color_space: ColorSpace = ColorSpace.SRGB,
    scale=(1.0, 1.0, 1.0, 1.0),
    bias=(0.0, 0.0, 0.0, 0.0),
) -> TextureMap:
    return TextureMap(
        material="/M",
        node="/M/Tex",
        node_type="UsdUVTexture",
        origin=Origin.USD,
        asset="tex.png",
        resolved="",
        file_at=AuthoredAt("/M/Tex", "inputs:file", "scene.usda"),
        roles=tuple(RoleUse(r, c, f"</M/Surface.inputs:{r}>") for r, c in roles),
        color_space=color_space,
        color_space_reason="test",
        scale=scale,
        bias=bias,
    )


def info(channels: int, dtype: str = "uint8", names: tuple[str, ...] = ()) -> ImageInfo:
    return ImageInfo(8, 8, channels, dtype, "png" if dtype.startswith("uint") else "openexr", names)


def all_codes(channels: int, dtype=np.uint8, seed: int = 0) -> np.ndarray:
    """(16, 16*k, C) file values covering every code of ``dtype`` in every channel (8-bit)."""
    top = np.iinfo(dtype).max
    if dtype is np.uint8:
        base = np.arange(256, dtype=np.int64).reshape(16, 16)
        planes = [np.roll(base, 37 * c) for c in range(channels)]
    else:
        rng = np.random.default_rng(seed)
        planes = [rng.integers(0, top + 1, (16, 16)) for _ in range(channels)]
        planes[0].flat[:4] = [0, 1, top - 1, top]
    return (np.stack(planes, axis=-1) / top).astype(np.float32)


def quantise(values: np.ndarray, top: int) -> np.ndarray:
    return np.rint(np.asarray(values, np.float64) * top).astype(np.int64)


# values: transfer functions ----------------------------------------------------------------------


def test_srgb_transfer_values() -> None:
    v = np.array([0.0, 0.04045, 0.5, 1.0])
    expected = np.array([0.0, 0.04045 / 12.92, ((0.5 + 0.055) / 1.055) ** 2.4, 1.0])
    assert np.allclose(to_linear(v, "sRGB"), expected, atol=1e-7)
    assert np.allclose(to_linear(v, "sRGB", "uint8"), to_linear(np.rint(v * 255) / 255, "sRGB"), atol=1e-12)
    assert np.allclose(from_linear(to_linear(v, "sRGB"), "sRGB"), v, atol=1e-12)
    assert np.array_equal(to_linear(v, "raw"), v)


def test_srgb_transfer_matches_colour_science_everywhere() -> None:
    """The written-out IEC 61966-2-1 pair gives colour-science's numbers: every 16-bit code, values around
    both knees, below 0 and above 1."""
    import warnings

    with warnings.catch_warnings():  # colour-science warns about optional plotting packages
        warnings.simplefilter("ignore")
        from colour.models import eotf_inverse_sRGB, eotf_sRGB
    knees = np.array([0.04045, 0.0031308])
    around = (knees[:, None] + np.linspace(-1e-6, 1e-6, 41)).ravel()
    v = np.concatenate([np.arange(65536) / 65535, around, np.linspace(-0.5, 1.5, 2001)])
    assert np.allclose(to_linear(v, "sRGB"), eotf_sRGB(v), rtol=1e-15, atol=1e-17)
    assert np.allclose(from_linear(v, "sRGB"), eotf_inverse_sRGB(v), rtol=1e-15, atol=1e-17)
    codes = np.arange(65536) / 65535
    assert np.allclose(to_linear(codes, "sRGB", "uint16"), eotf_sRGB(codes), rtol=1e-15, atol=1e-17)
    assert np.array_equal(from_linear(eotf_sRGB(codes), "sRGB", "uint16"), codes)
    with pytest.raises(ValueError, match="unknown colour space"):
        to_linear(v, "ACEScg")


@pytest.mark.parametrize("dtype, top", [("uint8", 255), ("uint16", 65535)])
def test_integer_encoding_picks_the_rounded_code(dtype: str, top: int) -> None:
    x = np.random.default_rng(0).random(200_000) * 1.2 - 0.1  # includes values outside [0, 1]
    by_table = from_linear(x, "sRGB", dtype)
    by_rounding = np.rint(np.clip(from_linear(x, "sRGB"), 0, 1) * top) / top
    assert np.array_equal(by_table, by_rounding)
    assert np.array_equal(from_linear(x, "raw", dtype), x)  # raw: the writer rounds


# values: round trips file -> network -> file -------------------------------------------------------


@pytest.mark.parametrize("color_space", [ColorSpace.SRGB, ColorSpace.RAW])
@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_8bit_round_trip_is_exact(color_space: ColorSpace, channels: int) -> None:
    pixels = all_codes(channels)
    enc = MapEncoding.for_image(info(channels), color_space, pixels=pixels)
    net = decode_map(pixels, enc)
    assert net.dtype == np.float32 and net.min() >= -1.0 and net.max() <= 1.0
    assert np.array_equal(quantise(encode_map(net, enc), 255), quantise(pixels, 255))


@pytest.mark.parametrize("color_space", [ColorSpace.SRGB, ColorSpace.RAW])
def test_16bit_round_trip_is_exact(color_space: ColorSpace) -> None:
    pixels = all_codes(3, np.uint16)
    enc = MapEncoding.for_image(info(3, "uint16"), color_space)
    back = encode_map(decode_map(pixels, enc), enc)
    assert np.array_equal(quantise(back, 65535), quantise(pixels, 65535))


def test_srgb_network_values_stay_perceptual_by_default() -> None:
    enc = MapEncoding.for_image(info(3), "sRGB")
    mid = np.full((1, 1, 3), 128 / 255, np.float32)
    assert np.allclose(decode_map(mid, enc), 2 * (128 / 255) - 1, atol=1e-6)
    assert np.allclose(decode_map(np.ones((1, 1, 3)), enc), 1.0)
    assert np.allclose(decode_map(np.zeros((1, 1, 3)), enc), -1.0)


@pytest.mark.parametrize("dtype", ["uint8", "uint16", "half"])
def test_srgb_round_trip_is_exact_in_both_domains(dtype: str) -> None:
    codes = 255 if dtype == "uint8" else 65535
    pixels = np.linspace(0, 1, codes + 1, dtype=np.float32).reshape(1, -1, 1).repeat(3, axis=2)
    for perceptual in (True, False):
        enc = MapEncoding.for_image(info(3, dtype), "sRGB", perceptual=perceptual)
        back = encode_map(decode_map(pixels, enc), enc)
        assert np.abs(back - pixels).max() <= 0.5 / codes + 1e-6


def test_srgb_network_values_are_linear_when_not_perceptual() -> None:
    enc = MapEncoding.for_image(info(3), "sRGB", perceptual=False)
    mid = np.full((1, 1, 3), 128 / 255, np.float32)
    assert np.allclose(decode_map(mid, enc), 2 * to_linear(128 / 255, "sRGB") - 1, atol=1e-6)
    assert np.allclose(decode_map(np.ones((1, 1, 3)), enc), 1.0)
    assert np.allclose(decode_map(np.zeros((1, 1, 3)), enc), -1.0)


@pytest.mark.parametrize("dtype", ["half", "float"])
def test_float_ldr_round_trip(dtype: str) -> None:
    np_type = np.float16 if dtype == "half" else np.float32
    pixels = np.random.default_rng(0).random((8, 8, 3)).astype(np_type).astype(np.float32)
    enc = MapEncoding.for_image(info(3, dtype), "raw", pixels=pixels)
    assert enc.value_range == ValueRange(0.0, 1.0, Tone.LINEAR)
    back = encode_map(decode_map(pixels, enc), enc)
    if dtype == "half":
        assert np.array_equal(back.astype(np.float16), pixels.astype(np.float16))
    else:
        assert np.allclose(back, pixels, rtol=1e-6, atol=1e-7)


def test_hdr_values_above_one_round_trip_through_log() -> None:
    # An emissive EXR: most values in [0, 1], a few hot spots up to 5000.
    rng = np.random.default_rng(1)
    pixels = rng.random((16, 16, 3)).astype(np.float16)
    pixels[0, 0] = [5000, 40, 1.5]
    pixels = pixels.astype(np.float32)
    enc = MapEncoding.for_image(info(3, "half"), "raw", pixels=pixels)
    assert enc.value_range.tone is Tone.LOG and enc.value_range.hi == 5000
    net = decode_map(pixels, enc)
    assert net.min() >= -1.0 and net.max() == pytest.approx(1.0)
    assert np.array_equal(encode_map(net, enc).astype(np.float16), pixels.astype(np.float16))
    order = np.argsort(pixels, axis=None)
    assert np.all(np.diff(net.ravel()[order]) >= 0)  # monotonic: no two file values swap


def test_negative_float_values_round_trip() -> None:
    pixels = np.linspace(-3, 2, 64, dtype=np.float32).reshape(8, 8, 1)
    enc = MapEncoding.for_image(info(1, "float"), "raw", pixels=pixels)
    assert (enc.value_range.lo, enc.value_range.hi, enc.value_range.tone) == (-3.0, 2.0, Tone.LOG)
    net = decode_map(pixels, enc)
    assert net.min() == pytest.approx(-1) and net.max() == pytest.approx(1)
    assert np.allclose(encode_map(net, enc), pixels, rtol=1e-6, atol=1e-6)


def test_float_without_pixels_never_clips() -> None:
    enc = MapEncoding.for_image(info(1, "float"), "raw")
    pixels = np.array([[[3.0]]], np.float32)
    net = decode_map(pixels, enc)
    assert net.item() == pytest.approx(5.0)  # outside [-1, 1], but nothing lost
    assert encode_map(net, enc).item() == pytest.approx(3.0)


def test_value_range_validation() -> None:
    with pytest.raises(ValueError, match="hi > lo"):
        ValueRange(1.0, 1.0)


# values: channels used and kept ------------------------------------------------------------------


def test_packed_orm_keeps_only_used_channels_and_fills_the_rest() -> None:
    pixels = all_codes(3)
    pixels[..., 2] = 0.0  # metallic unused, all zero
    m = texture_map((("occlusion", "r"), ("roughness", "g")), ColorSpace.RAW)
    enc = MapEncoding.for_map(m, info(3), pixels)
    assert enc.channels == (0, 1) and enc.network_channels == 2
    net = decode_map(pixels, enc)
    assert net.shape == (16, 16, 2)
    back = encode_map(net, enc)
    assert back.shape == (16, 16, 3)
    assert np.array_equal(quantise(back[..., :2], 255), quantise(pixels[..., :2], 255))
    assert np.all(back[..., 2] == 0.0)


def test_single_channel_of_rgb_file() -> None:
    m = texture_map((("roughness", "b"),), ColorSpace.RAW)
    enc = MapEncoding.for_map(m, info(3), all_codes(3))
    assert enc.channels == (2,)


def test_alpha_is_kept_even_when_no_role_reads_it() -> None:
    pixels = all_codes(4)
    enc = MapEncoding.for_map(texture_map(), info(4, names=RGBA), pixels)
    assert enc.channels == (0, 1, 2, 3) and enc.alpha == 3
    assert any("alpha kept" in n for n in enc.notes)
    net = decode_map(pixels, enc)
    assert np.allclose(net[..., 3], 2 * pixels[..., 3] - 1, atol=1e-6)  # alpha is linear, not sRGB
    assert np.array_equal(quantise(encode_map(net, enc), 255), quantise(pixels, 255))


def test_grey_alpha_file_reads_rgb_from_grey() -> None:
    enc = MapEncoding.for_map(texture_map((("diffuseColor", "rgb"), ("opacity", "a"))), info(2, names=("Y", "A")))
    assert enc.channels == (0, 1) and enc.alpha == 1


def test_alpha_role_on_file_without_alpha() -> None:
    with_colour = texture_map((("diffuseColor", "rgb"), ("opacity", "a")))
    enc = MapEncoding.for_map(with_colour, info(3))
    assert enc.channels == (0, 1, 2)
    assert any("has none" in w for w in enc.warnings)
    with pytest.raises(ValueError, match="no alpha"):
        MapEncoding.for_map(texture_map((("opacity", "a"),), ColorSpace.RAW), info(3))


def test_map_without_roles_uses_all_channels() -> None:
    assert MapEncoding.for_map(texture_map(()), info(3), None).channels == (0, 1, 2)


def test_unknown_channel_letter() -> None:
    with pytest.raises(ValueError, match="unknown channel letters"):
        MapEncoding.for_image(info(3), "raw", channels_used="rx")


def test_to_dict_is_json_ready() -> None:
    import json

    enc = MapEncoding.for_map(texture_map(), info(4, names=RGBA), all_codes(4))
    d = json.loads(json.dumps(enc.to_dict()))
    assert d["color_space"] == "sRGB" and d["channels"] == [0, 1, 2, 3] and d["value_range"]["tone"] == "linear"


# values: normal maps -------------------------------------------------------------------------------


def unit_normals_8bit(n: int = 4096, seed: int = 0) -> np.ndarray:
    """Quantised file values of random unit normals in the upper hemisphere, (64, 64, 3)."""
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2]) + 0.2
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return (np.rint((v * 0.5 + 0.5) * 255) / 255).reshape(64, 64, 3).astype(np.float32)


def test_normal_scale_bias_defaults_and_validation() -> None:
    assert normal_scale_bias((1, 1, 1, 1), (0, 0, 0, 0)) == ((2.0, 2.0, 2.0), (-1.0, -1.0, -1.0))
    with pytest.raises(ValueError, match="zero component"):
        normal_scale_bias((2, 0, 2, 1), (-1, 0, -1, 0))


@pytest.mark.parametrize(
    "scale, bias",
    [((2.0, 2.0, 2.0, 1.0), (-1.0, -1.0, -1.0, 0.0)), ((2.0, -2.0, 2.0, 1.0), (-1.0, 1.0, -1.0, 0.0))],
    ids=["opengl", "directx-y-flip"],
)
def test_normals_decode_to_unit_vectors_and_round_trip(scale, bias) -> None:
    pixels = unit_normals_8bit()
    m = texture_map((("normal", "rgb"),), ColorSpace.RAW, scale, bias)
    enc = MapEncoding.for_map(m, info(3), pixels)
    assert enc.normal == (0, 1, 2) and enc.normal_scale == scale[:3]
    net = decode_map(pixels, enc)
    # unit to the precision of 8-bit codes (each component within half a code: sqrt(3) / 255 at most)
    assert np.abs(np.linalg.norm(net, axis=-1) - 1.0).max() <= np.sqrt(3) / 255
    expected_y = (2 * pixels[..., 1] - 1) * (1 if scale[1] > 0 else -1)
    assert np.allclose(net[..., 1], expected_y, atol=0.02)  # the Y convention is applied
    back = quantise(encode_map(net, enc), 255)
    assert np.array_equal(back, quantise(pixels, 255))  # stored unit normals come back to their own codes
    # the re-encoded file decodes to the same vectors: a second round trip changes nothing
    again = quantise(encode_map(decode_map(back / 255.0, enc), enc), 255)
    assert np.array_equal(again, back)


def test_y_flip_maps_the_same_direction_to_the_same_network_value() -> None:
    up = np.array([[[0.5, 1.0, 0.5]]], np.float32)  # +Y in OpenGL convention
    down = np.array([[[0.5, 0.0, 0.5]]], np.float32)  # the same direction stored DirectX style
    gl = MapEncoding.for_map(texture_map((("normal", "rgb"),), ColorSpace.RAW, (2, 2, 2, 1), (-1, -1, -1, 0)), info(3))
    dx = MapEncoding.for_map(texture_map((("normal", "rgb"),), ColorSpace.RAW, (2, -2, 2, 1), (-1, 1, -1, 0)), info(3))
    assert np.allclose(decode_map(up, gl), decode_map(down, dx))
    assert np.allclose(encode_map(decode_map(up, gl), dx), down)


def test_normals_are_renormalised_on_encode() -> None:
    enc = MapEncoding.for_map(texture_map((("normal", "rgb"),), ColorSpace.RAW), info(3))
    out = encode_map(np.array([[[0.0, 0.0, 0.3], [0.0, 0.0, 0.0]]], np.float32), enc)
    assert np.allclose(out, [[[0.5, 0.5, 1.0], [0.5, 0.5, 1.0]]])


@pytest.mark.parametrize("dtype, code", [("uint8", 255), ("uint16", 65535)])
def test_only_normals_off_unit_by_more_than_a_stored_code_are_renormalised(dtype, code) -> None:
    """A vector as unit as the file's codes allow is written as it is; one further off is made unit."""
    enc = MapEncoding.for_map(texture_map((("normal", "rgb"),), ColorSpace.RAW), info(3, dtype=dtype))
    lengths = 1.0 + np.array([0.4, 2.0]) / code  # off by less than a rounded code can make it, and by more
    v = np.array([0.6, 0.0, 0.8])[None, None] * lengths[None, :, None]
    out = encode_map(v.astype(np.float32), enc)
    assert np.allclose(out[0, 0], (v[0, 0] + 1) / 2, atol=1e-7)  # kept as it is
    assert np.allclose(out[0, 1], [0.8, 0.5, 0.9], atol=1e-7)  # made unit


def test_normal_map_with_alpha_keeps_alpha_separate() -> None:
    pixels = np.concatenate([unit_normals_8bit(), np.full((64, 64, 1), 0.25, np.float32)], axis=-1)
    enc = MapEncoding.for_map(texture_map((("normal", "rgb"),), ColorSpace.RAW), info(4, names=RGBA), pixels)
    net = decode_map(pixels, enc)
    assert np.allclose(net[..., 3], -0.5)
    assert np.allclose(encode_map(net, enc)[..., 3], 0.25)


def test_sample_normal_map_round_trip(samples_dir) -> None:
    from seamless_usd.imaging import read_image

    pixels, img = read_image(samples_dir / "textures" / "brick_normal.png")
    m = texture_map((("normal", "rgb"),), ColorSpace.RAW, (2, 2, 2, 1), (-1, -1, -1, 0))
    enc = MapEncoding.for_map(m, img, pixels)
    once = quantise(encode_map(decode_map(pixels, enc), enc), 255)
    twice = quantise(encode_map(decode_map(once / 255.0, enc), enc), 255)
    assert np.abs(twice - once).max() <= 1  # stable after renormalisation


# shapes ----------------------------------------------------------------------------------------------


def test_shapes_hw_and_hwc() -> None:
    enc = MapEncoding.for_image(info(1), "raw")
    flat = np.full((3, 5), 0.5, np.float32)
    assert decode_map(flat, enc).shape == (3, 5, 1)
    assert encode_map(np.zeros((3, 5)), enc).shape == (3, 5, 1)
    enc3 = MapEncoding.for_image(info(3), "sRGB")
    assert decode_map(np.zeros((2, 7, 3)), enc3).shape == (2, 7, 3)
    # a tile may be larger than the source
    assert encode_map(np.zeros((16, 4, 3)), enc3).shape == (16, 4, 3)
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        decode_map(np.zeros((2, 2, 4)), enc3)
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        encode_map(np.zeros((2, 2)), enc3)


# NaN / inf -----------------------------------------------------------------------------------------


def test_nonfinite_is_refused_by_decode_and_encode() -> None:
    enc = MapEncoding.for_image(info(3, "half"), "raw")
    bad = np.zeros((2, 2, 3), np.float32)
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN or inf"):
        decode_map(bad, enc)
    bad[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match="NaN or inf"):
        encode_map(bad, enc)


def test_replace_nonfinite_policy() -> None:
    p = np.array([[[1.0, 5.0], [np.nan, -2.0], [np.inf, -np.inf], [0.5, 3.0]]], np.float32)
    fixed, counts = replace_nonfinite(p)
    assert (counts.nan, counts.posinf, counts.neginf, counts.total) == (1, 1, 1, 3)
    assert fixed.tolist() == [[[1.0, 5.0], [0.0, -2.0], [1.0, -2.0], [0.5, 3.0]]]
    assert np.isnan(p).sum() == 1  # the input is not modified
    same, none = replace_nonfinite(fixed)
    assert same is fixed and none.total == 0
    flat, counts = replace_nonfinite(np.array([[np.inf, np.inf]]))
    assert flat.tolist() == [[0.0, 0.0]] and counts.posinf == 2  # no finite value: 0


def test_fitting_ignores_nonfinite() -> None:
    pixels = np.array([[[0.5], [np.inf]]], np.float32)
    assert ValueRange.fit(pixels) == ValueRange(0.0, 1.0, Tone.LINEAR)
