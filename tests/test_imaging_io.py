"""Reading and writing image files with real OpenImageIO on files written into tmp_path."""
from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from imagefiles import write_raw_image

from seamless_usd.textures import ColorSpace, ImageInfo
from seamless_usd.errors import InputError
from seamless_usd.imaging import output_extension, read_image, read_info, write_pixels

TEXTURES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"
def codes(rng: np.random.Generator, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
    return rng.integers(0, np.iinfo(dtype).max + 1, size=shape, dtype=dtype)


# values: every format and sample type comes back as float file values --------------------------


@pytest.mark.parametrize("channels", [1, 2, 3, 4])
def test_png_8bit_reads_exact_codes(tmp_path: Path, channels: int) -> None:
    data = codes(np.random.default_rng(channels), (5, 7, channels))
    data[0, 0, -1] = 0  # a fully transparent texel keeps its colour (straight alpha)
    path = write_raw_image(tmp_path / "a.png", data)
    pixels, info = read_image(path)
    assert pixels.dtype == np.float32 and pixels.shape == (5, 7, channels)
    assert np.array_equal(np.rint(pixels * 255).astype(np.uint8), data)
    assert (info.width, info.height, info.channels, info.dtype, info.file_format) == (7, 5, channels, "uint8", "png")


def test_png_16bit_reads_exact_codes(tmp_path: Path) -> None:
    data = codes(np.random.default_rng(1), (4, 6, 3), np.uint16)
    pixels, info = read_image(write_raw_image(tmp_path / "a.png", data))
    assert info.dtype == "uint16"
    assert np.array_equal(np.rint(pixels * 65535).astype(np.uint16), data)


@pytest.mark.parametrize("dtype", [np.float16, np.float32])
def test_exr_half_and_float_read_as_stored(tmp_path: Path, dtype) -> None:
    data = (np.random.default_rng(2).normal(size=(4, 5, 4)) * 10).astype(dtype)
    pixels, info = read_image(write_raw_image(tmp_path / "a.exr", data, ("R", "G", "B", "A")))
    assert info.dtype == {np.float16: "half", np.float32: "float"}[dtype]
    assert info.file_format == "openexr" and info.channel_names == ("R", "G", "B", "A")
    assert np.array_equal(pixels, data.astype(np.float32))


@pytest.mark.parametrize(
    "name, dtype, channels",
    [("a.tif", np.uint16, 2), ("a.tif", np.float32, 1), ("a.tga", np.uint8, 4), ("a.jpg", np.uint8, 3)],
)
def test_tiff_tga_jpeg(tmp_path: Path, name: str, dtype, channels: int) -> None:
    rng = np.random.default_rng(3)
    data = rng.random((6, 6, channels)).astype(dtype) if dtype is np.float32 else codes(rng, (6, 6, channels), dtype)
    pixels, info = read_image(write_raw_image(tmp_path / name, data))
    assert pixels.shape == (6, 6, channels) and info.channels == channels
    if name.endswith(".jpg"):
        return  # lossy
    top = 1.0 if dtype is np.float32 else np.iinfo(dtype).max
    assert np.allclose(pixels * top, data, atol=0 if top == 1.0 else 0.01)


def test_radiance_hdr_reads_values_above_one(tmp_path: Path) -> None:
    data = np.full((4, 4, 3), 6.0, np.float32)
    pixels, info = read_image(write_raw_image(tmp_path / "sky.hdr", data))
    assert info.file_format == "hdr" and info.dtype == "float"
    assert np.allclose(pixels, 6.0, rtol=0.01)


def test_cmyk_jpeg_reads_as_rgb(tmp_path: Path) -> None:
    image = pytest.importorskip("PIL.Image")
    cmyk = np.zeros((8, 8, 4), np.uint8)
    cmyk[..., 0] = 255  # full cyan, no black: red channel near 0, green and blue near 1
    path = tmp_path / "print.jpg"
    image.fromarray(cmyk, mode="CMYK").save(path, quality=100)
    pixels, info = read_image(path)
    assert info.channels == 3 and pixels.shape == (8, 8, 3)
    assert pixels[..., 0].max() < 0.1 and pixels[..., 1:].min() > 0.9


def test_sample_assets_read() -> None:
    for path in sorted(TEXTURES.glob("*")):
        if path.suffix not in (".png", ".exr"):
            continue
        pixels, info = read_image(path)
        assert pixels.shape == (info.height, info.width, info.channels)
        assert np.isfinite(pixels).all()
    assert read_info(TEXTURES / "brick_roughness16.png").dtype == "uint16"
    exr = read_info(TEXTURES / "brick_albedo_linear.exr")
    assert (exr.dtype, exr.channels) == ("half", 3)


def test_png_colour_space_only_when_declared(tmp_path: Path) -> None:
    # OpenImageIO calls every PNG sRGB; read_info reports it only when a chunk says so.
    tagged = write_raw_image(tmp_path / "tagged.png", np.zeros((2, 2, 3), np.uint8))
    assert read_info(tagged).color_space == "srgb_rec709_scene"
    data = bytearray(tagged.read_bytes())
    plain = tmp_path / "plain.png"
    plain.write_bytes(_drop_png_chunks(bytes(data), {b"sRGB", b"gAMA", b"cHRM", b"iCCP"}))
    assert read_info(plain).color_space is None
    assert read_image(plain)[0].shape == (2, 2, 3)


# shapes: sizes and channel counts are the header's -----------------------------------------------


def test_read_info_does_not_decode(tmp_path: Path) -> None:
    path = write_raw_image(tmp_path / "big.png", np.zeros((300, 200, 1), np.uint8))
    info = read_info(path)
    assert (info.width, info.height, info.channels, info.channel_names) == (200, 300, 1, ("Y",))


# NaN / inf: read as stored (the stack loader replaces and reports them) -----------------------------


def test_nonfinite_float_values_are_read_as_stored(tmp_path: Path) -> None:
    data = np.array([[[np.nan, np.inf, -np.inf, 1.0]]], np.float16)
    pixels, _ = read_image(write_raw_image(tmp_path / "bad.exr", data, ("R", "G", "B", "A")))
    assert np.isnan(pixels[0, 0, 0]) and np.isposinf(pixels[0, 0, 1]) and np.isneginf(pixels[0, 0, 2])


# errors: missing, corrupt, truncated, huge -------------------------------------------------------


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"@.*nope\.png@.*not found"):
        read_info(tmp_path / "nope.png")


@pytest.mark.parametrize("content", [b"", b"not an image at all" * 20, b"\x89PNG\r\n\x1a\n" + b"\x00" * 40])
def test_corrupt_files_are_input_errors(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "broken.png"
    path.write_bytes(content)
    with pytest.raises(InputError, match=r"@.*broken\.png@.*re-export"):
        read_image(path)


@pytest.mark.parametrize("name", ["brick_albedo.png", "brick_albedo_linear.exr"])
def test_truncated_files_are_input_errors(tmp_path: Path, name: str) -> None:
    data = (TEXTURES / name).read_bytes()
    path = tmp_path / name
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=rf"@.*{name.replace('.', '.')}@.*(truncated|corrupt)"):
        read_image(path)


def test_huge_png_header_refused_before_decoding(tmp_path: Path) -> None:
    path = tmp_path / "huge.png"
    path.write_bytes(_png_with_size(write_raw_image(tmp_path / "s.png", np.zeros((8, 8, 3), np.uint8)), 60_000, 40_000))
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB, the process's peak so far
    for read in (read_info, read_image):
        with pytest.raises(InputError, match=r"@.*huge\.png@.*(60000x40000|claims a \d+ MB image)"):
            read(path)
    # 2.4 Gpx were never allocated nor decoded (7 GB as RGB bytes): the peak barely moved
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - peak < 200 * 1024


def test_huge_exr_data_window_refused_before_decoding(tmp_path: Path) -> None:
    small = write_raw_image(tmp_path / "s.exr", np.zeros((8, 8, 3), np.float16))
    path = tmp_path / "huge.exr"
    path.write_bytes(_exr_with_data_window(small.read_bytes(), 29_999, 29_999))
    with pytest.raises(InputError, match=r"@.*huge\.exr@.*(30000x30000|claims a \d+ MB image)"):
        read_image(path)


def test_pixel_limit_is_checked_on_the_header_before_decoding(tmp_path: Path) -> None:
    # A valid 300x200 header over image data that cannot be decoded: with a limit below 60000
    # pixels the limit error comes first, so no decoding was attempted.
    good = write_raw_image(tmp_path / "g.png", codes(np.random.default_rng(5), (200, 300, 3)))
    data = good.read_bytes()
    path = tmp_path / "limited.png"
    path.write_bytes(b"".join([data[:8]] + [raw[:8] + bytes(len(raw) - 12) + raw[-4:] if kind == b"IDAT" else raw for kind, raw in _png_chunks(data)]))
    assert read_info(path).width == 300
    with pytest.raises(InputError, match=r"@.*limited\.png@.*300x200 = 60000 pixels.*limit of 59999"):
        read_image(path, max_pixels=59_999)
    with pytest.raises(InputError, match=r"@.*limited\.png@.*(truncated|corrupt)"):
        read_image(path, max_pixels=60_000)
    with pytest.raises(InputError, match="limit of 63"):
        read_info(TEXTURES / "cloth.png", max_pixels=63)


# writing --------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "info, ext",
    [
        (ImageInfo(4, 4, 3, "uint8", "jpeg"), ".png"),
        (ImageInfo(4, 4, 4, "uint8", "targa"), ".png"),
        (ImageInfo(4, 4, 3, "uint8", "tiff"), ".png"),
        (ImageInfo(4, 4, 1, "uint16", "png"), ".png"),
        (ImageInfo(4, 4, 1, "uint16", "tiff"), ".tif"),
        (ImageInfo(4, 4, 3, "half", "openexr"), ".exr"),
        (ImageInfo(4, 4, 3, "float", "hdr"), ".exr"),
        (ImageInfo(4, 4, 5, "uint8", "tiff"), ".tif"),
    ],
)
def test_output_extension(info: ImageInfo, ext: str) -> None:
    assert output_extension(info) == ext


@pytest.mark.parametrize(
    "like, dtype",
    [
        (ImageInfo(3, 2, 4, "uint8", "png", ("R", "G", "B", "A")), np.uint8),
        (ImageInfo(3, 2, 1, "uint16", "png", ("Y",)), np.uint16),
        (ImageInfo(3, 2, 2, "uint16", "tiff", ("Y", "A")), np.uint16),
        (ImageInfo(3, 2, 3, "half", "openexr", ("R", "G", "B")), np.float16),
        (ImageInfo(3, 2, 4, "float", "openexr", ("R", "G", "B", "A")), np.float32),
    ],
)
def test_write_pixels_keeps_family_depth_and_layout(tmp_path: Path, like: ImageInfo, dtype) -> None:
    rng = np.random.default_rng(4)
    if np.issubdtype(dtype, np.integer):
        data = codes(rng, (2, 3, like.channels), dtype)
        values = data / np.iinfo(dtype).max
    else:
        data = (rng.random((2, 3, like.channels)) * 4).astype(dtype)
        values = data.astype(np.float32)
    path = write_pixels(tmp_path / f"out{output_extension(like)}", values, like, ColorSpace.RAW)
    pixels, info = read_image(path)
    assert (info.dtype, info.channels, info.channel_names) == (like.dtype, like.channels, like.channel_names)
    top = np.iinfo(dtype).max if np.issubdtype(dtype, np.integer) else 1
    assert np.array_equal(np.rint(pixels * top) if top != 1 else pixels, data.astype(np.float32))
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temp file left


def test_write_pixels_records_colour_encoding(tmp_path: Path) -> None:
    like = ImageInfo(2, 2, 3, "uint8", "png")
    srgb = write_pixels(tmp_path / "c.png", np.zeros((2, 2, 3)), like, ColorSpace.SRGB)
    raw = write_pixels(tmp_path / "d.png", np.zeros((2, 2, 3)), like, ColorSpace.RAW)
    assert read_info(srgb).color_space == "srgb_rec709_scene"
    assert read_info(raw).color_space is None  # a data map's source said nothing: neither does its tile (no gAMA)
    stated = ImageInfo(2, 2, 3, "uint8", "png", color_space="lin_rec709_scene")
    assert read_info(write_pixels(tmp_path / "e.png", np.zeros((2, 2, 3)), stated, ColorSpace.RAW)).color_space == (
        "lin_rec709_scene")  # ... where it said linear, the tile says so too
    for ext, fmt, dtype in ((".exr", "openexr", "half"), (".tif", "tiff", "uint16")):
        path = write_pixels(tmp_path / f"f{ext}", np.zeros((2, 2, 3)), ImageInfo(2, 2, 3, dtype, fmt), ColorSpace.RAW)
        assert read_info(path).color_space is None, ext


def test_write_pixels_clips_and_rounds(tmp_path: Path) -> None:
    like = ImageInfo(3, 1, 1, "uint8", "png")
    path = write_pixels(tmp_path / "a.png", np.array([[-0.5, 0.5 / 255 + 1e-6, 2.0]]), like, ColorSpace.RAW)
    assert np.rint(read_image(path)[0][..., 0] * 255).tolist() == [[0, 1, 255]]
    half = ImageInfo(1, 1, 1, "half", "openexr")
    path = write_pixels(tmp_path / "h.exr", np.array([[1e6]]), half, ColorSpace.RAW)
    assert read_image(path)[0].item() == 65504.0


def test_write_pixels_rejects_wrong_extension_and_channels(tmp_path: Path) -> None:
    like = ImageInfo(2, 2, 3, "half", "openexr")
    with pytest.raises(ValueError, match=r"written as \.exr"):
        write_pixels(tmp_path / "a.png", np.zeros((2, 2, 3)), like, ColorSpace.RAW)
    with pytest.raises(ValueError, match=r"\(H, W, 3\)"):
        write_pixels(tmp_path / "a.exr", np.zeros((2, 2, 4)), like, ColorSpace.RAW)
    assert list(tmp_path.iterdir()) == []


def test_write_pixels_into_missing_folder(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="does not exist"):
        write_pixels(tmp_path / "no" / "a.png", np.zeros((2, 2, 1)), ImageInfo(2, 2, 1, "uint8", "png"), "raw")


# helpers that craft files --------------------------------------------------------------------------


def _png_chunks(data: bytes):
    i = 8
    while i < len(data):
        (length,) = struct.unpack(">I", data[i : i + 4])
        yield data[i + 4 : i + 8], data[i : i + 12 + length]
        i += 12 + length


def _drop_png_chunks(data: bytes, kinds: set[bytes]) -> bytes:
    return data[:8] + b"".join(raw for kind, raw in _png_chunks(data) if kind not in kinds)


def _png_with_size(path: Path, width: int, height: int) -> bytes:
    """The PNG at ``path`` with its IHDR claiming ``width x height`` (valid CRC, same data)."""
    data = path.read_bytes()
    out = [data[:8]]
    for kind, raw in _png_chunks(data):
        if kind == b"IHDR":
            body = struct.pack(">II", width, height) + raw[16:21]
            raw = struct.pack(">I", 13) + b"IHDR" + body + struct.pack(">I", zlib.crc32(b"IHDR" + body))
        out.append(raw)
    return b"".join(out)


def _exr_with_data_window(data: bytes, xmax: int, ymax: int) -> bytes:
    """An OpenEXR file whose header's data and display windows claim ``(xmax+1) x (ymax+1)``."""
    for name in (b"dataWindow", b"displayWindow"):
        key = name + b"\x00box2i\x00" + struct.pack("<i", 16)
        at = data.index(key) + len(key)
        data = data[:at] + struct.pack("<iiii", 0, 0, xmax, ymax) + data[at + 16 :]
    return data
