"""Names used by discovery, written once: shader ids, input and output names, roles, finding codes.

USD tokens follow the UsdPreviewSurface specification and the MaterialX standard library as seen
inside USD (``ND_<category>_<type>`` shader ids); MaterialX names follow the MaterialX specification.
"""
from __future__ import annotations

__all__ = [
    "ShaderIds",
    "Inputs",
    "Outputs",
    "MtlxCategories",
    "MtlxInputs",
    "Terminals",
    "Roles",
    "Codes",
    "Wrap",
    "TransformKinds",
    "OUTPUT_CHANNELS",
    "SEPARATE_OUTPUTS",
    "TYPE_CHANNELS",
    "MIN_CROP",
    "MIN_IMAGE_SIZE",
    "UDIM_TOKEN",
    "TILE_TOKENS",
    "tile_token",
    "MTLX_SUFFIX",
]


class ShaderIds:
    """``info:id`` values of shader prims."""

    PREVIEW_SURFACE = "UsdPreviewSurface"
    UV_TEXTURE = "UsdUVTexture"
    TRANSFORM_2D = "UsdTransform2d"
    PRIMVAR_READER_FLOAT2 = "UsdPrimvarReader_float2"
    # MaterialX standard-library nodes inside USD: "ND_<category>_<type>" prefixes.
    ND_IMAGE = "ND_image_"
    ND_TILEDIMAGE = "ND_tiledimage_"
    ND_GLTF = "ND_gltf_"
    ND_PLACE2D = "ND_place2d_"
    ND_TEXCOORD = "ND_texcoord_"
    ND_GEOMPROPVALUE = "ND_geompropvalue_"
    ND_SEPARATE = "ND_separate"
    ND_EXTRACT = "ND_extract_"
    ND_NORMALMAP = "ND_normalmap"


class Inputs:
    """UsdPreviewSurface-family input names (without the ``inputs:`` namespace)."""

    FILE = "file"
    ST = "st"
    IN = "in"
    SCALE = "scale"
    BIAS = "bias"
    WRAP_S = "wrapS"
    WRAP_T = "wrapT"
    SOURCE_COLOR_SPACE = "sourceColorSpace"
    VARNAME = "varname"
    ROTATION = "rotation"
    TRANSLATION = "translation"


class Outputs:
    """Material terminal output names (last component: ``outputs:mtlx:surface`` -> ``surface``)."""

    SURFACE = "surface"
    DISPLACEMENT = "displacement"


class Terminals:
    NAMES = frozenset({Outputs.SURFACE, Outputs.DISPLACEMENT})
    MTLX_SHADER_TYPES = ("surfaceshader", "displacementshader")


class MtlxCategories:
    """MaterialX node categories discovery knows about."""

    IMAGE = "image"
    TILEDIMAGE = "tiledimage"
    GLTF_IMAGE = "gltf_image"
    GLTF_COLORIMAGE = "gltf_colorimage"
    GLTF_NORMALMAP = "gltf_normalmap"
    PLACE2D = "place2d"
    TEXCOORD = "texcoord"
    GEOMPROPVALUE = "geompropvalue"
    SEPARATE = ("separate2", "separate3", "separate4")
    EXTRACT = "extract"
    NORMALMAP = "normalmap"
    TEXTURES = frozenset({IMAGE, TILEDIMAGE, GLTF_IMAGE, GLTF_COLORIMAGE, GLTF_NORMALMAP})
    GLTF_TEXTURES = frozenset({GLTF_IMAGE, GLTF_COLORIMAGE, GLTF_NORMALMAP})


class MtlxInputs:
    """MaterialX input names."""

    FILE = "file"
    FILENAME_TYPE = "filename"  # the type of an input holding a file path
    TEXCOORD = "texcoord"
    UADDRESSMODE = "uaddressmode"
    VADDRESSMODE = "vaddressmode"
    UVTILING = "uvtiling"
    UVOFFSET = "uvoffset"
    PIVOT = "pivot"
    SCALE = "scale"
    ROTATE = "rotate"
    OFFSET = "offset"
    OPERATIONORDER = "operationorder"
    INDEX = "index"
    IN = "in"
    GEOMPROP = "geomprop"


class Wrap:
    USD_DEFAULT = "useMetadata"  # UsdUVTexture wrapS/wrapT fallback
    MTLX_DEFAULT = "periodic"  # MaterialX uaddressmode/vaddressmode fallback; tiledimage always tiles


class TransformKinds:
    USD_TRANSFORM_2D = "UsdTransform2d"
    PLACE2D = "place2d"
    UVTILING = "uvtiling"


class Roles:
    """Surface inputs whose maps hold colour (encoded for display); every other role is data."""

    COLOR = frozenset(
        {
            # UsdPreviewSurface
            "diffuseColor", "emissiveColor", "specularColor",
            # MaterialX standard_surface
            "base_color", "specular_color", "transmission_color", "transmission_scatter",
            "subsurface_color", "subsurface_radius", "sheen_color", "coat_color", "thin_film_color",
            "emission_color",
            # open_pbr_surface
            "specular_color", "fuzz_color", "coat_color", "transmission_color",
            "subsurface_color", "subsurface_radius_scale", "emission_color",
            # gltf_pbr
            "emissive", "sheen_color", "attenuation_color", "specular_color",
        }
    )


# Channels a texture node's output reads, by output name (UsdUVTexture and multi-output MaterialX).
OUTPUT_CHANNELS = {
    "r": "r", "g": "g", "b": "b", "a": "a", "rgb": "rgb", "rgba": "rgba",
    "outcolor": "rgb", "outa": "a",
}
# Channels by value type (single-output MaterialX nodes: output "out").
TYPE_CHANNELS = {
    "float": "r", "color3": "rgb", "color4": "rgba", "vector2": "rg", "vector3": "rgb",
    "vector4": "rgba", "color3f": "rgb", "color4f": "rgba", "float2": "rg", "float3": "rgb",
    "float4": "rgba", "vector3f": "rgb", "normal3f": "rgb", "point3f": "rgb",
}
# Separate-node output name -> channel index.
SEPARATE_OUTPUTS = {"outr": 0, "outg": 1, "outb": 2, "outa": 3, "outx": 0, "outy": 1, "outz": 2, "outw": 3}


class Codes:
    """Stable ``Finding.code`` values."""

    NO_FILE = "no-file"
    MISSING_FILE = "missing-file"
    UNREADABLE_FILE = "unreadable-file"
    UDIM = "udim"
    ANIMATED_FILE = "animated-file"
    NO_UV = "no-uv"
    TOO_SMALL = "too-small"
    COLORSPACE_MISMATCH = "colorspace-mismatch"
    UNKNOWN_COLORSPACE = "unknown-colorspace"
    NORMAL_SCALE_BIAS = "normal-scale-bias"
    COMPOSITION_ERROR = "composition-error"
    MTLX_UNREADABLE = "mtlx-unreadable"
    DISCOVERY_ERROR = "discovery-error"
    MTLX_INVALID = "mtlx-invalid"  # a document MaterialX does not validate (a connection to nothing)
    SOURCE_NOT_FOUND = "source-not-found"  # a tile this tool wrote whose recorded source is gone
    UNLOADED_PAYLOAD = "unloaded-payload"  # an open stage's payload that is not loaded: not scanned
    VARIANT_IN_INSTANCE = "variant-in-instance"  # a variant set inside an instance: its other choices not scanned
    TILE_MISSING = "tile-missing"  # a tile this tool wrote, deleted since: made again from its recorded source
    FILE_NODE_NOT_READ = "file-node-not-read"  # a node that takes a file but is no texture node read (USD, MaterialX)


MIN_CROP = 100  # px: the smallest crop SeamlessGAN samples (DESIGN: c_min); a smaller stack gets a cut tile only
MIN_IMAGE_SIZE = 16  # px: below this no tile can be cut from a map either: skipped as too-small
UDIM_TOKEN = "<UDIM>"
#: Tokens that name a set of texture tiles (UDIM numbers, or Mari's u/v tiles), with what each stands for on disk.
TILE_TOKENS = {"<UDIM>": r"1\d{3}", "<UDIMSET>": r"1\d{3}", "<UVTILE>": r"u\d+_v\d+", "<UVTILE0>": r"u\d+_v\d+",
               "<UVTILE1>": r"u\d+_v\d+"}


def tile_token(path: str) -> str | None:
    """The texture-tile token in ``path`` (``<UDIM>``, ``<UDIMSET>``, ``<UVTILE>``...), or None."""
    return next((t for t in TILE_TOKENS if t in path), None)
MTLX_SUFFIX = ".mtlx"


class Recorded:
    """The provenance a tile this tool wrote carries, as the scan reads it (the names the authoring writes:
    ``seamless_usd.authoring.schema.Schema`` for USD, ``MtlxNames`` for MaterialX; a test keeps them equal)."""

    USD_SOURCE = "seamless:sourceAsset"
    USD_PASSED = "seamless:passed"
    MTLX_SOURCE = "seamless_sourceasset"
    MTLX_PASSED = "seamless_passed"
    MTLX_UV_NODE = "seamless_uv"  # the place2d the authoring inserts: one per nodegraph scope, the same values
    USD_UV_API = "SeamlessUVTransformAPI"  # on the UsdTransform2d / place2d nodes (UV scale, turn) the authoring inserts
    USD_UV_READER = "SeamlessUVReader"  # the texcoord node (UV0) a MaterialX image with no texcoord gets in USD
    MTLX_UV_MARK = "seamless_uvtransform"  # on the place2d nodes (UV scale, turn) the authoring inserts
    MTLX_UV_READER = "seamless_uv_texcoord"  # the texcoord node (UV0) it reads where the image read its default


#: The image types a MaterialX colorspace applies to (a float, vector2/3/4 image's values are never transformed), in
#: a .mtlx document and in a MaterialX node authored in USD (``ND_image_vector3``) alike.
COLOUR_TYPES = ("color3", "color4")


def mtlx_image_type(shader_id: str) -> str | None:
    """The output type of a MaterialX image node id (``ND_image_vector3`` -> ``vector3``); None for other ids."""
    for prefix in (ShaderIds.ND_IMAGE, ShaderIds.ND_TILEDIMAGE):
        if shader_id.startswith(prefix):
            return shader_id[len(prefix):].split("_")[0] or None
    return None
