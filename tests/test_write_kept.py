"""What a tile keeps of its source's header: an OpenEXR file's primaries and colour space (an ACEScg map stays
ACEScg; it was relabelled Rec.709, and a reader of the header shifted its hues), unless the name says another
encoding than the tile's values are in."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio

from seamless_usd.imaging.io import read_info
from seamless_usd.imaging.write import write_pixels
from seamless_usd.textures import ColorSpace

AP1 = (0.713, 0.293, 0.165, 0.830, 0.128, 0.044, 0.32168, 0.33767)


def _exr(path, name: str):
    spec = oiio.ImageSpec(8, 8, 3, oiio.FLOAT)
    spec.attribute("chromaticities", oiio.TypeDesc("float[8]"), AP1)
    spec.attribute("colorInteropID", name)
    spec.attribute("oiio:ColorSpace", name)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec)
    out.write_image(np.full((8, 8, 3), 0.5, np.float32))
    out.close()
    return path


def _header(path):
    spec = oiio.ImageInput.open(str(path)).spec()
    return spec.getattribute("chromaticities"), spec.getattribute("colorInteropID"), spec.get_string_attribute(
        "oiio:ColorSpace")


def test_an_acescg_tile_keeps_its_primaries_and_colour_space(tmp_path):
    source = _exr(tmp_path / "albedo.exr", "lin_ap1_scene")
    tile = write_pixels(tmp_path / "tile.exr", np.full((8, 8, 3), 0.25), read_info(source), ColorSpace.RAW,
                        keep_from=source)
    chroma, interop, name = _header(tile)
    assert np.allclose(chroma, AP1) and interop == "lin_ap1_scene" and name == "lin_ap1_scene"


def test_a_colour_space_name_for_another_encoding_is_not_kept(tmp_path):
    source = _exr(tmp_path / "albedo.exr", "srgb_rec709_scene")  # a linear map whose header says sRGB
    tile = write_pixels(tmp_path / "tile.exr", np.full((8, 8, 3), 0.25), read_info(source), ColorSpace.RAW,
                        keep_from=source)
    chroma, interop, name = _header(tile)
    assert np.allclose(chroma, AP1) and interop in (None, "lin_rec709_scene") and name == "lin_rec709_scene"
