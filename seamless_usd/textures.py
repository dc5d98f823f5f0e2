"""The values that cross between the steps: a texture map, where it is authored, how it is used and
how the maps of a material group into a stack.

Discovery makes them; every later step (imaging, synthesis, authoring, pipeline, report) takes them.
No pixels here, and nothing above this module is imported: these are frozen dataclasses with a JSON
form (``to_dict``).
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from enum import Enum

from seamless_usd.findings import Finding

__all__ = [
    "ColorSpace",
    "Origin",
    "AuthoredAt",
    "RecordedSource",
    "RoleUse",
    "UVTransform",
    "UVChain",
    "ImageInfo",
    "TextureMap",
    "TextureStack",
    "ScanResult",
    "VariantChoice",
    "describe_selection",
    "Selection",
    "ExploredSelection",
    "VariantExploration",
]


class ColorSpace(str, Enum):
    """How a map's stored values encode what the shader reads."""

    SRGB = "sRGB"  # sRGB transfer function: colour maps (albedo, emission)
    RAW = "raw"  # linear / data: normals, roughness, metallic, occlusion, displacement, float EXR


class Origin(str, Enum):
    USD = "usd"  # a shader prim in a composed USD stage
    MTLX = "mtlx"  # a node in a MaterialX document read with the MaterialX package


@dataclass(frozen=True)
class RecordedSource:
    """The source a tile this tool wrote records (``seamless:sourceAsset``, MaterialX ``seamless_sourceasset``):
    ``asset`` as authored, ``resolved`` its absolute path ("" when it is not there). A tile is made again from its
    source, never from itself (a tile of a tile judged against the tile it was made from)."""

    asset: str
    resolved: str


@dataclass(frozen=True)
class AuthoredAt:
    """Where a value is actually authored (after following connections and interface inputs).

    For USD: ``prim`` is the prim path of the attribute's owner, ``attribute`` its full name
    (``inputs:file``) and ``layer`` the identifier of the strongest layer holding the opinion
    (relative asset paths resolve against it). For MaterialX: ``prim`` is the element's path
    inside the document (``NG_brick/image_color``), ``attribute`` the input name (``file``) and
    ``layer`` the ``.mtlx`` file.
    """

    prim: str
    attribute: str
    layer: str


@dataclass(frozen=True)
class RoleUse:
    """One use of a map by a surface shader input."""

    role: str  # surface input name without namespace: "diffuseColor", "normal", "roughness", "base_color"
    channels: str  # which channels of the file this role reads: "rgb", "r", "g", "b", "a", "rgba", "rg"
    shader_input: str  # "</Mat/Surface.inputs:roughness>" style full property path of the consumer


@dataclass(frozen=True)
class UVTransform:
    """An existing 2D texture-coordinate transform in a map's UV chain.

    ``kind`` is ``UsdTransform2d`` (in * scale, rotate by ``rotation`` degrees, + translation),
    ``place2d`` (MaterialX: pivot, scale, rotate, offset, operationorder) or ``uvtiling``
    (MaterialX ``tiledimage`` uvtiling / uvoffset inputs on the image node itself).
    ``authored`` lists, per input name, where the value is authored when it is not on the node
    itself (a Material interface input, say), so authoring edits it there.
    """

    node: str
    kind: str
    scale: tuple[float, float] = (1.0, 1.0)
    rotation: float = 0.0
    translation: tuple[float, float] = (0.0, 0.0)
    pivot: tuple[float, float] = (0.0, 0.0)
    operation_order: int = 0
    authored: tuple[tuple[str, AuthoredAt], ...] = ()
    ours: bool = False  # the UV scale or turn node this tool inserted


@dataclass(frozen=True)
class UVChain:
    """What feeds a texture node's texture coordinates, nearest-to-the-texture last.

    ``reader`` is the primvar reader prim (or MaterialX texcoord node) and ``primvar`` the name it
    reads (``st``); ``transforms`` the transform nodes between the reader and the texture, in
    evaluation order (first applied first). ``connected_from`` is the attribute the texture's
    ``st``/``texcoord`` input is connected to: maps with the same ``key`` share a UV chain.
    """

    primvar: str | None
    reader: str | None
    transforms: tuple[UVTransform, ...] = ()
    connected_from: str | None = None
    #: (primvar, reader, connected_from) as the chain was before the nodes this tool inserted (its UV scale and
    #: turn, the UV0 reader of an image that read its default UVs); None when it holds none of them
    before_ours: tuple[str | None, str | None, str | None] | None = None

    @property
    def key(self) -> str:
        return json.dumps(
            [self.primvar, self.reader, [t.node for t in self.transforms], self.connected_from]
        )

    @property
    def origin_key(self) -> str:
        """``key`` of the chain as it was before this tool's own nodes: the same before and after a run's edits,
        so a stack keeps its id (and its tiles their names) when it is run again over those edits."""
        if self.before_ours is None:
            return self.key
        primvar, reader, connected = self.before_ours
        return json.dumps([primvar, reader, [t.node for t in self.transforms if not t.ours], connected])


@dataclass(frozen=True)
class VariantChoice:
    """One variant set's selection on one prim."""

    prim: str  # prim path holding the variant set ("/King")
    set: str  # variant set name ("shadingVariant")
    variant: str  # the selected variant ("White")


Selection = tuple  # of VariantChoice: the choices that differ from the stage's own, parents first


def describe_selection(selection: Selection) -> str:
    """``modelVariant=Fancy, shadingVariant=White``; "" for the stage's own selection. A set whose name recurs on
    several prims (three crates, each with its ``shadingVariant``) names its prim: ``shadingVariant=damaged on
    </World/Crate1>, shadingVariant=clean on </World/Crate2>``.

    >>> from seamless_usd.textures import VariantChoice
    >>> describe_selection((VariantChoice("/A", "look", "worn"), VariantChoice("/B", "look", "new")))
    'look=worn on </A>, look=new on </B>'
    """
    names = [c.set for c in selection]
    return ", ".join(f"{c.set}={c.variant}" + (f" on <{c.prim}>" if names.count(c.set) > 1 else "")
                     for c in selection)


@dataclass(frozen=True)
class ExploredSelection:
    """One composition of a stage's variant space and the materials found under it."""

    selection: Selection
    materials: tuple[str, ...]

    def to_dict(self) -> dict:
        return {"selection": _jsonable(asdict(self)["selection"]), "label": describe_selection(self.selection),
                "materials": list(self.materials)}


@dataclass(frozen=True)
class VariantExploration:
    """How one stage's variant space was explored."""

    source: str
    mode: str  # "all": every combination; "each-set": one set at a time (the space was too large)
    combinations: int  # compositions explored
    limit: int  # the most combinations explored in "all" mode
    selections: tuple[ExploredSelection, ...]

    @property
    def note(self) -> str:
        if self.mode == "all":
            return f"every combination explored ({self.combinations})"
        return (f"more than {self.limit} combinations: explored one variant set at a time from the stage's "
                f"own selection ({self.combinations} selections); combinations of sets were not composed")

    def to_dict(self) -> dict:
        return {"source": self.source, "mode": self.mode, "combinations": self.combinations, "limit": self.limit,
                "note": self.note, "selections": [s.to_dict() for s in self.selections]}


@dataclass(frozen=True)
class ImageInfo:
    """What the file header says (read with OpenImageIO, no pixels decoded)."""

    width: int
    height: int
    channels: int
    dtype: str  # "uint8", "int8", "uint16", "int16", "uint32", "int32", "half", "float" (:func:`.imaging.io.sample_type`)
    file_format: str  # OpenImageIO format name: "png", "jpeg", "openexr", "tiff", ...
    channel_names: tuple[str, ...] = ()
    color_space: str | None = None  # "oiio:ColorSpace" or equivalent header metadata, if any
    texture: bool = False  # a tiled, MIP-mapped texture file (maketx's .tx: "textureformat" in its header)
    associated_alpha: bool = False  # colour stored multiplied by alpha (a TIFF's ExtraSamples = 1): written so again
    parts: int = 1  # subimages (OpenEXR parts, TIFF pages): a tile holds the first only
    channel_types: tuple[str, ...] = ()  # each channel's sample type where they differ (half RGB, float A), else ()
    compression: str | None = None  # an OpenEXR's or TIFF's compression ("zip", "piz", "dwaa", "lzw"): kept


@dataclass(frozen=True)
class TextureMap:
    """One image file as used by one material (a packed ORM file is one map with three roles)."""

    material: str  # "</World/Looks/Brick>" material prim path (or mtlx material name)
    node: str  # texture node: prim path of the UsdUVTexture, or mtlx node path
    node_type: str  # "UsdUVTexture", "ND_image_color3", "ND_tiledimage_vector3", ...
    origin: Origin
    asset: str  # asset path exactly as authored ("textures/brick_albedo.png")
    resolved: str  # absolute path on disk ("" when unresolved; then the map is skipped instead)
    file_at: AuthoredAt  # where the asset value is authored
    roles: tuple[RoleUse, ...]
    color_space: ColorSpace
    color_space_reason: str  # why: "inputs:sourceColorSpace", "colorSpace metadata", "auto: 8-bit RGB"...
    scale: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    bias: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    wrap_s: str = "useMetadata"
    wrap_t: str = "useMetadata"
    uv: UVChain = field(default_factory=lambda: UVChain(None, None))
    image: ImageInfo | None = None
    document: str | None = None  # the .mtlx file for Origin.MTLX maps
    in_package: bool = False  # inside a .usdz (readable through Ar, not editable in place)
    normal_y_flip: bool = False  # the file's green channel stores -Y (DirectX convention):
    # UsdUVTexture scale.y < 0, or a MaterialX normalmap with a negative y scale
    selection: Selection = ()  # variant selection it was found under (() : the stage's own)
    recorded_passed: bool | None = None  # a tile this tool wrote: whether it passed when written (else None)
    recorded_source: RecordedSource | None = None  # a tile this tool wrote: the source it records
    tile_missing: bool = False  # a tile this tool wrote that is gone: ``resolved`` is its recorded source
    file_in_variant: bool = False  # the asset value comes from inside a variant under every selection it is read in

    @property
    def is_normal(self) -> bool:
        return any(r.role in NORMAL_ROLES for r in self.roles)

    @property
    def channels_used(self) -> str:
        """Union of the channels the roles read, in rgba order ("rgb", "r", "rgba", ...)."""
        used = set()
        for r in self.roles:
            used.update(r.channels)
        return "".join(c for c in "rgba" if c in used)

    @property
    def uv_turns(self) -> bool:
        """Whether the tool can turn this map's texture coordinates with a UV transform of its own (how
        ``process --straighten`` gives a straightened tile its turn back): an image node (``UsdUVTexture``,
        MaterialX ``image``) whose texture coordinates are connected in USD (a MaterialX document's image reads
        its default coordinates through a new ``place2d``); not a ``tiledimage`` (``uvtiling`` / ``uvoffset``
        only), a glTF image node (a transform of its own) or a node the tool does not know."""
        image = self.node_type == "UsdUVTexture" or self.node_type.startswith("ND_image_")
        return image and (self.origin is Origin.MTLX or bool(self.uv.connected_from))

    def to_dict(self) -> dict:
        return _jsonable(asdict(self))


NORMAL_ROLES = frozenset({"normal", "normalmap", "geometry_normal", "coat_normal"})


@dataclass(frozen=True)
class TextureStack:
    """The maps of one material that share a UV chain: trained and sampled together."""

    material: str
    uv: UVChain
    maps: tuple[TextureMap, ...]
    duplicate_of: str | None = None  # id of an identical stack found earlier (processed once)
    intent: str = ""  # tiling intent (discover.intent.Intent): tiling, uv-atlas, already-tileable, other
    intent_reason: str = ""  # the measured reason ("UVs 0.11-0.89 x 0.11-0.89, 37 islands on <...>")
    source: str = ""  # the stage or document scanned that it was found through

    @property
    def selection(self) -> Selection:
        """The variant selection the stack was found under (() : the stage's own)."""
        return self.maps[0].selection if self.maps else ()

    @property
    def id(self) -> str:
        """Stable id of this stack within a scan: material plus UV chain (plus the variant
        selection, when the stack was found under another than the stage's own)."""
        variant = f"|{describe_selection(self.selection)}" if self.selection else ""
        h = hashlib.sha1(f"{self.material}|{self.uv.origin_key}{variant}".encode()).hexdigest()[:10]
        return f"{self.material.strip('<>').strip('/').replace('/', '_') or 'material'}-{h}"

    @property
    def content_key(self) -> str:
        """Identity for de-duplication: same files, channels and colour spaces."""
        parts = sorted(
            json.dumps([m.resolved, m.channels_used, m.color_space.value, list(m.scale), list(m.bias)])
            for m in self.maps
        )
        return hashlib.sha1("\n".join(parts).encode()).hexdigest()

    def to_dict(self) -> dict:
        d = _jsonable(asdict(self))
        d["id"] = self.id
        d["content_key"] = self.content_key
        d["variant"] = describe_selection(self.selection)
        return d


@dataclass
class ScanResult:
    """Everything a scan found: stacks to process and findings to report."""

    sources: list[str] = field(default_factory=list)  # stages / documents scanned
    stacks: list[TextureStack] = field(default_factory=list)
    findings: list[Finding] = field(default_factory=list)
    materials: list[str] = field(default_factory=list)  # every material seen, even with no stack
    variants: list[VariantExploration] = field(default_factory=list)  # per stage with variant sets
    interrupted: bool = False  # stopped by Ctrl-C or SIGTERM: what was scanned by then

    def to_dict(self) -> dict:
        return {
            "sources": list(self.sources),
            "materials": list(self.materials),
            "variants": [v.to_dict() for v in self.variants],
            "stacks": [s.to_dict() for s in self.stacks],
            "findings": [f.to_dict() for f in self.findings],
            "interrupted": self.interrupted,
        }


def _jsonable(obj):
    if isinstance(obj, Enum):
        return obj.value
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    return obj
