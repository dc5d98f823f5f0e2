"""How an OpenEXR source stores its texels is how its tile stores them: a tiled, MIP-mapped texture (what maketx
makes, what a renderer's texture cache reads) stays one, each channel keeps its own sample type (half colour beside
a float alpha), and the source's compression is kept (a studio's lossy DWA stays DWA, PIZ stays PIZ). Before,
every OpenEXR tile was written as one scanline level of one sample type with zip compression."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd.discover.images import read_image_info
from seamless_usd.imaging.io import read_info
from seamless_usd.imaging.write import write_pixels
from seamless_usd.textures import ColorSpace

SIZE = 64


def _values(channels: int) -> np.ndarray:
    y, x = np.mgrid[0:SIZE, 0:SIZE] / SIZE
    planes = [0.2 + 0.6 * np.sin(2 * np.pi * (k + 1) * x) ** 2 * np.cos(2 * np.pi * y) ** 2 for k in range(channels)]
    return np.stack(planes, -1).astype(np.float32)


def _texture(path: Path) -> None:
    """A one-channel half texture as maketx makes it: tiled, MIP-mapped, PIZ-compressed."""
    buf = oiio.ImageBuf(oiio.ImageSpec(SIZE, SIZE, 1, oiio.HALF))
    assert buf.set_pixels(oiio.ROI(0, SIZE, 0, SIZE, 0, 1, 0, 1), _values(1))
    config = oiio.ImageSpec()
    config.attribute("compression", "piz")
    assert oiio.ImageBufAlgo.make_texture(oiio.MakeTxTexture, buf, str(path), config), oiio.geterror()


def _mixed(path: Path) -> None:
    """Half colour and a float alpha, DWAA-compressed, scanline."""
    spec = oiio.ImageSpec(SIZE, SIZE, 4, oiio.HALF)
    spec.channelformats = (oiio.HALF, oiio.HALF, oiio.HALF, oiio.FLOAT)
    spec.attribute("compression", "dwaa")
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(_values(4)), out.geterror()
    out.close()


def _header(path: Path) -> tuple[oiio.ImageSpec, int]:
    """The first level's header and how many MIP levels the file holds."""
    inp = oiio.ImageInput.open(str(path))
    spec = inp.spec()
    levels = 1
    while inp.seek_subimage(0, levels):
        levels += 1
    inp.close()
    return spec, levels


def test_both_readers_see_the_layout(tmp_path):
    _texture(tmp_path / "rough.exr")
    _mixed(tmp_path / "albedo.exr")
    texture, mixed = read_info(tmp_path / "rough.exr"), read_info(tmp_path / "albedo.exr")
    assert texture.texture and texture.compression == "piz" and texture.channel_types == ()
    assert not mixed.texture and mixed.compression == "dwaa"
    assert mixed.channel_types == ("half", "half", "half", "float")
    # the scan reads headers its own way (through the asset resolver too): the same facts
    for name, info in (("rough.exr", texture), ("albedo.exr", mixed)):
        assert read_image_info(str(tmp_path / name)) == info


def test_a_tiled_mip_mapped_texture_stays_one_with_its_compression(tmp_path):
    _texture(tmp_path / "rough.exr")
    like = read_info(tmp_path / "rough.exr")
    written = write_pixels(tmp_path / "tile.exr", _values(1)[::-1].copy(), like, ColorSpace.RAW)
    spec, levels = _header(written)
    assert spec.tile_width > 0 and levels == 7, (spec.tile_width, levels)  # 64 px down to 1 px
    assert spec.get_string_attribute("compression") == "piz" and str(spec.format) == "half"
    assert spec.get_string_attribute("wrapmodes") == "periodic,periodic"
    back = np.asarray(oiio.ImageBuf(str(written)).get_pixels(oiio.FLOAT)).reshape(SIZE, SIZE, 1)
    assert np.abs(back - _values(1)[::-1]).max() < 1e-3  # the first level holds the tile itself


def test_each_channel_keeps_its_sample_type_and_the_compression_is_kept(tmp_path):
    _mixed(tmp_path / "albedo.exr")
    like = read_info(tmp_path / "albedo.exr")
    values = _values(4)
    values[0, 0, 0], values[0, 0, 3] = 1e6, 1e6  # beyond what a half holds: clipped there only
    written = write_pixels(tmp_path / "tile.exr", values, like, ColorSpace.RAW)
    spec, levels = _header(written)
    assert [str(t) for t in spec.channelformats] == ["half", "half", "half", "float"] and levels == 1
    assert spec.get_string_attribute("compression") == "dwaa" and spec.tile_width == 0
    back = np.asarray(oiio.ImageBuf(str(written)).get_pixels(oiio.FLOAT)).reshape(SIZE, SIZE, 4)
    # the half channel held to the half range (DWA is lossy: near it), not written as infinity; the float one whole
    assert 60000 < back[0, 0, 0] <= 65504.0 and back[0, 0, 3] == 1e6


def test_a_source_of_another_family_gets_lossless_zip(tmp_path):
    """A float TIFF's tile is an OpenEXR: a TIFF compression name means nothing there."""
    spec = oiio.ImageSpec(SIZE, SIZE, 3, oiio.FLOAT)
    spec.attribute("compression", "lzw")
    out = oiio.ImageOutput.create(str(tmp_path / "albedo.tif"))
    assert out.open(str(tmp_path / "albedo.tif"), spec) and out.write_image(_values(3))
    out.close()
    like = read_info(tmp_path / "albedo.tif")
    assert like.compression == "lzw"
    written = write_pixels(tmp_path / "tile.exr", _values(3), like, ColorSpace.RAW)
    assert _header(written)[0].get_string_attribute("compression") == "zip"
