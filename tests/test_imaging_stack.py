"""Working-resolution policy, load_stack_pixels and write_map on real files."""
from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from imagefiles import write_raw_image

from seamless_usd.textures import AuthoredAt, ColorSpace, ImageInfo, Origin, RoleUse, TextureMap
from seamless_usd.errors import InputError, UsageError
from seamless_usd.imaging import (
    MapEncoding,
    WorkingResolution,
    decode_map,
    load_stack_pixels,
    output_extension,
    output_path,
    read_image,
    read_info,
    resample,
    write_map,
)


SAMPLE_ROLES = {
    "brick_albedo.png": ((("diffuseColor", "rgb"),), ColorSpace.SRGB),
    "brick_albedo_linear.exr": ((("diffuseColor", "rgb"),), ColorSpace.RAW),
    "brick_normal.png": ((("normal", "rgb"),), ColorSpace.RAW),
    "brick_orm.png": ((("occlusion", "r"), ("roughness", "g"), ("metallic", "b")), ColorSpace.RAW),
    "brick_roughness.png": ((("roughness", "r"),), ColorSpace.RAW),
    "brick_roughness16.png": ((("roughness", "r"),), ColorSpace.RAW),
    "cloth.png": ((("diffuseColor", "rgb"),), ColorSpace.SRGB),
    "wood_color.png": ((("diffuseColor", "rgb"),), ColorSpace.SRGB),
    "wood_roughness.png": ((("roughness", "r"),), ColorSpace.RAW),
}


def texture_map(path: Path, roles=(("diffuseColor", "rgb"),), color_space=ColorSpace.SRGB, normal=False) -> TextureMap:
    scale, bias = ((2.0, 2.0, 2.0, 1.0), (-1.0, -1.0, -1.0, 0.0)) if normal else ((1.0,) * 4, (0.0,) * 4)
    return TextureMap(
        material="/M",
        node=f"/M/{path.stem}",
        node_type="UsdUVTexture",
        origin=Origin.USD,
        asset=f"textures/{path.name}",
        resolved=str(path),
        file_at=AuthoredAt(f"/M/{path.stem}", "inputs:file", "scene.usda"),
        roles=tuple(RoleUse(r, c, f"</M/Surface.inputs:{r}>") for r, c in roles),
        color_space=color_space,
        color_space_reason="test",
        scale=scale,
        bias=bias,
    )


def sample_map(samples_dir: Path, name: str) -> TextureMap:
    roles, cs = SAMPLE_ROLES[name]
    return texture_map(samples_dir / "textures" / name, roles, cs, normal=name == "brick_normal.png")


# the policy --------------------------------------------------------------------------------------


def test_working_size_rules() -> None:
    sizes = [(256, 256), (512, 128), (100, 300)]
    assert WorkingResolution.native().working_size(sizes) == (512, 300)
    assert WorkingResolution(common="smallest").working_size(sizes) == (100, 128)
    assert WorkingResolution(max_size=256).working_size(sizes) == (256, 150)
    assert WorkingResolution(max_size=1024).working_size(sizes) == (512, 300)  # cap only shrinks
    assert WorkingResolution(max_size=1).working_size([(4000, 10)]) == (1, 1)


def test_policy_validation_lists_valid_names() -> None:
    with pytest.raises(UsageError, match="valid: auto, box"):
        WorkingResolution(filter="nearestish")
    with pytest.raises(UsageError, match="largest, smallest"):
        WorkingResolution(common="median")
    with pytest.raises(UsageError, match="positive"):
        WorkingResolution(max_size=0)
    assert json.loads(json.dumps(WorkingResolution(max_size=64).to_dict()))["max_size"] == 64


def test_resample_values_and_shapes() -> None:
    constant = np.full((8, 8, 3), 0.25, np.float32)
    assert np.allclose(resample(constant, (16, 4)), 0.25, atol=1e-6)  # filters preserve constants
    assert resample(constant, (16, 4)).shape == (4, 16, 3)
    assert resample(constant[..., 0], (2, 2)).shape == (2, 2)
    assert resample(constant, (8, 8)) is not None and resample(constant, (8, 8)).shape == (8, 8, 3)
    ramp = np.tile(np.linspace(0, 1, 64, dtype=np.float32), (4, 1))[..., None]
    half = resample(ramp, (32, 4), "box")
    assert np.allclose(half[0, :, 0], ramp[0, ::2, 0] + (ramp[0, 1, 0] - ramp[0, 0, 0]) / 2, atol=1e-5)


# load_stack_pixels -------------------------------------------------------------------------------


def test_sample_brick_stack_native(samples_dir: Path) -> None:
    names = ["brick_albedo.png", "brick_normal.png", "brick_orm.png", "brick_roughness16.png", "brick_albedo_linear.exr"]
    stack = load_stack_pixels([sample_map(samples_dir, n) for n in names])
    assert stack.working_size == (256, 256)
    assert stack.channel_counts == (3, 3, 3, 1, 3)
    assert stack.scale_factors == ((1.0, 1.0),) * 5 and stack.resampled == (False,) * 5
    for v in stack.values:
        assert v.dtype == np.float32 and v.shape[:2] == (256, 256)
        assert v.min() >= -1.0 and v.max() <= 1.0
    # unit to the precision of the 8-bit file: each component within half a code (sqrt(3) / 255 at most)
    assert np.abs(np.linalg.norm(stack.values[1], axis=-1) - 1.0).max() <= np.sqrt(3) / 255
    assert stack.stacked().shape == (256, 256, 13)
    assert [a.shape[2] for a in stack.split(np.zeros((64, 32, 13)))] == [3, 3, 3, 1, 3]
    assert stack.findings == []
    record = json.loads(json.dumps(stack.to_dict()))
    assert record["working_size"] == [256, 256] and record["policy"]["max_size"] is None
    assert len(record["encodings"]) == 5


def test_stack_of_different_sizes_goes_to_the_largest_and_records_it(samples_dir: Path) -> None:
    # cloth.png is 200 px, brick_roughness.png 256 px: both end on the 256 px grid
    maps = [sample_map(samples_dir, "cloth.png"), sample_map(samples_dir, "brick_roughness.png")]
    stack = load_stack_pixels(maps, WorkingResolution())
    assert stack.original_sizes == ((200, 200), (256, 256))
    assert stack.working_size == (256, 256)
    assert stack.scale_factors == ((1.28, 1.28), (1.0, 1.0))
    assert stack.resampled == (True, False)
    assert all(v.shape[:2] == (256, 256) for v in stack.values)
    assert stack.values[0].min() >= -1.0 and stack.values[0].max() <= 1.0
    record = stack.policy_record
    assert record["maps"][0] == {"asset": "textures/cloth.png", "original_size": [200, 200], "scale": [1.28, 1.28], "resampled": True}


def test_stack_smallest_common_size(samples_dir: Path) -> None:
    maps = [sample_map(samples_dir, "cloth.png"), sample_map(samples_dir, "brick_roughness.png")]
    stack = load_stack_pixels(maps, WorkingResolution(common="smallest"))
    assert stack.working_size == (200, 200)
    assert stack.resampled == (False, True)
    assert stack.scale_factors[1] == (200 / 256, 200 / 256)


def test_stack_cap_downsamples_and_renormalises_normals(samples_dir: Path) -> None:
    maps = [sample_map(samples_dir, "brick_normal.png"), sample_map(samples_dir, "brick_albedo.png")]
    stack = load_stack_pixels(maps, WorkingResolution(max_size=100, filter="lanczos3"))
    assert stack.working_size == (100, 100)
    assert stack.scale_factors[0] == pytest.approx((100 / 256, 100 / 256))
    assert np.allclose(np.linalg.norm(stack.values[0], axis=-1), 1.0, atol=1e-5)
    assert stack.values[1].min() >= -1.0 and stack.values[1].max() <= 1.0
    # the mean colour survives downsampling (linear-light averaging)
    full = load_stack_pixels(maps[1:]).values[0]
    assert np.allclose(stack.values[1].mean(axis=(0, 1)), full.mean(axis=(0, 1)), atol=0.01)


def test_stack_nonfinite_pixels_are_replaced_and_reported(tmp_path: Path) -> None:
    data = np.full((8, 8, 3), 0.5, np.float32)
    data[0, 0, 0], data[1, 1, 1], data[2, 2, 2] = np.nan, np.inf, -np.inf
    data[3, 3] = 4.0
    path = write_raw_image(tmp_path / "emit.exr", data)
    stack = load_stack_pixels([texture_map(path, (("emissiveColor", "rgb"),), ColorSpace.RAW)])
    assert np.isfinite(stack.values[0]).all()
    [finding] = stack.findings
    assert finding.code == "non-finite-pixels" and finding.where == "@textures/emit.exr@"
    assert "1 NaN, 1 +inf, 1 -inf" in finding.message


def test_stack_channel_warnings_become_findings(tmp_path: Path) -> None:
    path = write_raw_image(tmp_path / "rgb.png", np.zeros((4, 4, 3), np.uint8))
    stack = load_stack_pixels([texture_map(path, (("diffuseColor", "rgb"), ("opacity", "a")))])
    [finding] = stack.findings
    assert (finding.code, finding.where) == ("map-channels", "</M/rgb> @textures/rgb.png@")


def test_a_normal_map_in_the_wrong_encoding_is_named(samples_dir: Path, tmp_path: Path) -> None:
    """The bundled brick normal map reads clean; the same vectors stored signed in a float EXR but read with the
    0-1 scale and bias, or a colour texture wired as a normal map, are named with what to check."""
    good = load_stack_pixels([sample_map(samples_dir, "brick_normal.png")])
    assert not good.findings
    vectors = read_image(str(samples_dir / "textures" / "brick_normal.png"))[0][..., :3] * 2.0 - 1.0
    signed = write_raw_image(tmp_path / "normal_signed.exr", vectors.astype(np.float32))
    wood = samples_dir / "textures" / "wood_color.png"
    for path, length in ((signed, "1.6"), (wood, "")):
        stack = load_stack_pixels([texture_map(path, (("normal", "rgb"),), ColorSpace.RAW, normal=True)])
        [finding] = [f for f in stack.findings if "tangent-space normal map" in f.message]
        assert finding.code == "map-channels" and path.name in finding.where
        assert "median length is " + length in finding.message and "scale and bias" in finding.message
    # with nothing authored (scale 1, bias 0), a float file holding signed vectors is read as stored: right
    plain = load_stack_pixels([dataclasses.replace(texture_map(signed, (("normal", "rgb"),), ColorSpace.RAW),
                                                   scale=(1.0,) * 4, bias=(0.0,) * 4)])
    assert not plain.findings and plain.encodings[0].normal_scale == (1.0, 1.0, 1.0)
    assert np.allclose(plain.values[0], good.values[0], atol=0.02)


@pytest.mark.parametrize("name", ["a.tga", "a.tif", "a.jpg"])
def test_8bit_sources_of_other_formats_are_written_as_png(tmp_path: Path, name: str) -> None:
    data = np.random.default_rng(7).integers(0, 256, (6, 6, 3), dtype=np.uint8)
    stack = load_stack_pixels([texture_map(write_raw_image(tmp_path / name, data))])
    out = write_map(tmp_path / "tile", stack.values[0], stack.encodings[0], like=stack.infos[0])
    assert out.name == "tile.png"
    assert np.array_equal(np.rint(read_image(out)[0] * 255), np.rint(read_image(tmp_path / name)[0] * 255))


def test_cmyk_jpeg_is_written_as_rgb_png(tmp_path: Path) -> None:
    image = pytest.importorskip("PIL.Image")
    cmyk = np.random.default_rng(8).integers(0, 256, (8, 8, 4), dtype=np.uint8)
    image.fromarray(cmyk, mode="CMYK").save(tmp_path / "print.jpg", quality=95)
    stack = load_stack_pixels([texture_map(tmp_path / "print.jpg")])
    out = write_map(tmp_path / "tile", stack.values[0], stack.encodings[0], like=stack.infos[0])
    back, info = read_image(out)
    assert (out.suffix, info.channels, info.dtype) == (".png", 3, "uint8")
    assert np.array_equal(np.rint(back * 255), np.rint(read_image(tmp_path / "print.jpg")[0] * 255))


def test_stack_errors_are_input_errors(tmp_path: Path) -> None:
    missing = texture_map(tmp_path / "gone.png")
    with pytest.raises(InputError, match=r"@.*gone\.png@"):
        load_stack_pixels([missing])
    unresolved = TextureMap(**{**missing.__dict__, "resolved": ""})
    with pytest.raises(InputError, match=r"unresolved texture of </M/gone>"):
        load_stack_pixels([unresolved])
    path = write_raw_image(tmp_path / "n.png", np.zeros((4, 4, 3), np.uint8))
    bad = TextureMap(**{**texture_map(path, (("normal", "rgb"),), ColorSpace.RAW).__dict__, "scale": (2.0, 0.0, 2.0, 1.0), "bias": (-1.0, 0.0, -1.0, 0.0)})
    with pytest.raises(InputError, match=r"</M/n>.*zero component"):
        load_stack_pixels([bad])
    with pytest.raises(InputError, match="limit of 15"):
        load_stack_pixels([texture_map(path)], max_pixels=15)


# write_map -----------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(SAMPLE_ROLES))
def test_sample_maps_round_trip_through_the_network_domain(samples_dir: Path, tmp_path: Path, name: str) -> None:
    m = sample_map(samples_dir, name)
    stack = load_stack_pixels([m])
    info, enc = stack.infos[0], stack.encodings[0]
    out = write_map(tmp_path / f"tile{output_extension(info)}", stack.values[0], enc, like=info)
    back, back_info = read_image(out)
    source, _ = read_image(m.resolved)
    assert (back_info.dtype, back_info.channels, back_info.width) == (info.dtype, info.channels, info.width)
    if info.dtype == "half":
        assert np.array_equal(back.astype(np.float16), source.astype(np.float16))
    elif m.is_normal:
        # The sample's vectors are mostly not unit length (resized from a JPEG; 1 % are): the output
        # stores the same directions, those unit as stored in their own codes and the others made
        # unit, and a second pass moves no value by more than 1/255.
        directions = decode_map(source, enc), decode_map(back, enc)
        cos = np.sum(directions[0] * directions[1], axis=-1) / (
            np.linalg.norm(directions[0], axis=-1) * np.linalg.norm(directions[1], axis=-1))
        assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 1.0
        as_stored = np.abs(np.linalg.norm(source * 2.0 - 1.0, axis=-1) - 1.0) <= np.sqrt(3) / 255
        assert as_stored.sum() > 100 and np.array_equal(np.rint(back * 255)[as_stored], np.rint(source * 255)[as_stored])
        assert np.abs(np.linalg.norm(directions[1], axis=-1) - 1.0).max() <= np.sqrt(3) / 255
        again = write_map(tmp_path / "again.png", decode_map(back, enc), enc, like=info)
        assert np.abs(np.rint(read_image(again)[0] * 255) - np.rint(back * 255)).max() <= 1
    else:
        top = 255 if info.dtype == "uint8" else 65535
        assert np.array_equal(np.rint(back * top), np.rint(source * top))
    expected_cs = "srgb_rec709_scene" if m.color_space is ColorSpace.SRGB else "lin_rec709_scene"
    if info.dtype.startswith("uint"):
        assert back_info.color_space == expected_cs


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float16, np.float32])
def test_write_map_keeps_depth_channels_and_alpha(tmp_path: Path, channels: int, dtype) -> None:
    rng = np.random.default_rng(channels)
    if np.issubdtype(dtype, np.integer):
        data = rng.integers(0, np.iinfo(dtype).max + 1, (6, 9, channels), dtype=dtype)
    else:
        data = (rng.random((6, 9, channels)) * 3).astype(dtype)  # values above 1
    if channels in (2, 4):
        data[0, :, -1] = 0  # transparent texels keep their colour
    src = write_raw_image(tmp_path / f"src.{'png' if np.issubdtype(dtype, np.integer) else 'exr'}", data)
    stack = load_stack_pixels([texture_map(src, (("diffuseColor", "rgb"),), ColorSpace.SRGB)])
    info, enc = stack.infos[0], stack.encodings[0]
    assert enc.network_channels == channels
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = write_map(out_dir / "tile", stack.values[0], enc, like=info)  # extension added
    assert out.suffix == output_extension(info)
    back, back_info = read_image(out)
    assert (back_info.dtype, back_info.channels) == (info.dtype, channels)
    source = read_image(src)[0]
    if np.issubdtype(dtype, np.integer):
        top = np.iinfo(dtype).max
        assert np.array_equal(np.rint(back * top), np.rint(source * top))
    elif dtype is np.float16:
        assert np.array_equal(back.astype(np.float16), data)
    else:
        assert np.allclose(back, data, rtol=1e-5, atol=1e-6)


def test_write_map_16bit_tiff_stays_tiff(tmp_path: Path) -> None:
    data = np.random.default_rng(2).integers(0, 65536, (5, 5, 1), dtype=np.uint16)
    src = write_raw_image(tmp_path / "height.tif", data)
    stack = load_stack_pixels([texture_map(src, (("displacement", "r"),), ColorSpace.RAW)])
    out = write_map(tmp_path / "tile.tif", stack.values[0], stack.encodings[0], like=stack.infos[0])
    back, info = read_image(out)
    assert (info.file_format, info.dtype) == ("tiff", "uint16")
    assert np.array_equal(np.rint(back * 65535), data.astype(np.float64))


def test_write_map_packed_file_fills_unused_channels(samples_dir: Path, tmp_path: Path) -> None:
    m = texture_map(samples_dir / "textures" / "brick_orm.png", (("roughness", "g"),), ColorSpace.RAW)
    stack = load_stack_pixels([m])
    enc, info = stack.encodings[0], stack.infos[0]
    assert enc.channels == (1,)
    tile = np.zeros((32, 48, 1), np.float32)  # a synthesised tile of another size
    out = write_map(tmp_path / "orm_tile.png", tile, enc, like=info)
    back, back_info = read_image(out)
    assert back.shape == (32, 48, 3)
    assert np.allclose(back[..., 1], 128 / 255)
    source = read_image(m.resolved)[0]
    assert np.allclose(back[..., 0], np.rint(source[..., 0].mean() * 255) / 255)


def test_write_map_extension_and_checks(tmp_path: Path) -> None:
    like = ImageInfo(4, 4, 3, "half", "openexr", ("R", "G", "B"))
    enc = MapEncoding.for_image(like, "raw")
    assert output_path(tmp_path / "a", like).name == "a.exr"
    assert output_path(tmp_path / "a.EXR", like).name == "a.EXR"
    with pytest.raises(ValueError, match=r"written as \.exr, not \.png"):
        write_map(tmp_path / "a.png", np.zeros((4, 4, 3)), enc, like)
    with pytest.raises(ValueError, match="the source has 4"):
        write_map(tmp_path / "a.exr", np.zeros((4, 4, 3)), enc, ImageInfo(4, 4, 4, "half", "openexr"))
    bad = np.zeros((4, 4, 3), np.float32)
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN or inf"):
        write_map(tmp_path / "a.exr", bad, enc, like)
    assert list(tmp_path.iterdir()) == []


def test_write_map_replaces_atomically(samples_dir: Path, tmp_path: Path) -> None:
    src = tmp_path / "rough.png"
    shutil.copy(samples_dir / "textures" / "brick_roughness.png", src)
    stack = load_stack_pixels([texture_map(src, (("roughness", "r"),), ColorSpace.RAW)])
    target = tmp_path / "out.png"
    target.write_bytes(b"old")
    write_map(target, stack.values[0], stack.encodings[0], like=stack.infos[0])
    assert read_info(target).width == 256
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.png", "rough.png"]
