"""Values the authoring step takes and returns: write modes, per-map results, provenance."""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path

from seamless_usd.textures import TextureMap, TextureStack
from seamless_usd.findings import Finding, Severity

__all__ = [
    "Codes",
    "WriteMode",
    "MapResult",
    "Provenance",
    "StackResult",
    "UVTurn",
    "AuthoringResult",
    "uv_scale_for",
    "shared_with",
]


class Codes:
    """Finding codes of the authoring step."""

    MISSING_PRIM = "authoring-missing-prim"
    MISSING_OUTPUT = "missing-output"
    IN_PACKAGE = "in-package"
    READ_ONLY = "read-only-layer"
    INSTANCE_PROXY = "instance-proxy"
    NO_UV = "no-uv-input"
    SHARED_CONFLICT = "shared-texture-conflict"
    ANONYMOUS_ANCHOR = "absolute-asset-path"
    NOTHING_TO_DO = "already-up-to-date"
    UNSUPPORTED_UV = "uv-not-composed"
    MTLX_INCLUDES_MOVED = "mtlx-includes-moved"
    MTLX_INCLUDE_INLINED = "mtlx-include-inlined"
    SCHEMA_NOT_REGISTERED = "schema-not-registered"
    VARIANT_NOT_EDITABLE = "variant-not-editable"
    EDIT_NOT_COMPOSED = "edit-not-composed"  # an edit a stronger opinion hides
    MTLX_EDITS_REPLACED = "mtlx-edits-replaced"  # a new document made again from a changed source
    EDITS_REPLACED = "edits-replaced"  # a new layer made again over a changed stage
    MTLX_VERSION_UPGRADED = "mtlx-version-upgraded"  # an older document written at the library's version
    SHARED_LAYER_EDITED = "shared-layer-edited"  # in place: a referenced or payload layer other stages may use


class WriteMode(str, Enum):
    """Where the edits go."""

    NEW_LAYER = "new-layer"  # default: a new layer beside the input that sublayers its root layer
    IN_PLACE = "in-place"  # edit the layers holding the opinions, after `.bak` copies
    DRY_RUN = "dry-run"  # compute the edits, write nothing


@dataclass(frozen=True)
class MapResult:
    """A tileable file, already written, that replaces ``map``'s image."""

    map: TextureMap
    output_path: Path


@dataclass(frozen=True)
class Provenance:
    """What is recorded on each edited texture node (``SeamlessTileAPI``)."""

    source_asset: str  # the texture file the tile was made from, as authored
    crop_size: tuple[int, int]  # (c_w, c_h) working pixels; the tile is 2c x 2c
    uv_scale: tuple[float, float]  # (W / 2c_w, H / 2c_h)
    q_passed: bool | None  # the discriminator's Q on the written tile (min(D) on each band >= tau); None: Q never ran
    q_tau: float
    q_band_min: tuple[float, float]  # (vertical band, horizontal band)
    model_hash: str
    tool_version: str
    passed: bool = False  # the verdict: seamless at the wrap and inside, and faithful to the source
    verdict: str = ""  # the verdict in words: "seamless and faithful", or why not
    straightened: float = 0.0  # degrees the source was turned clockwise before tiling (0: not straightened)
    levelled: float = 0.0  # the most a texel value was scaled by (share) to level the source's light (0: not levelled)
    evened: float = 0.0  # the most a texel moved (texels) to even the source's drifting lattice (0: not evened)
    uv_turn: float = 0.0  # degrees the authored UVs turn the straightened tile back, counter-clockwise (0: none)
    rectified: tuple[float, float, float] = (0.0, 0.0, 0.0)  # (vx, vy, spread): where the source's lines met, as
    #   shares of its width and height, and their leans' spread in degrees, when it was rectified (spread 0: not)


#: Said of a texture node whose UVs were to turn a straightened tile back and could not.
TURN_NOT_AUTHORED = ("its UVs cannot turn (a tiledimage, or no UV transform authored): the straightened tile is written "
                     "straight and the pattern on the asset turns by the angle recorded as straightened (an image node "
                     "fed by a UV transform keeps the asset's look)")


@dataclass(frozen=True)
class UVTurn:
    """The turn a straightened tile is given back in the asset's UVs, so the asset looks as before: the source
    was turned clockwise by ``degrees`` (as the picture is seen) before it was tiled; ``aspect`` is its height over
    its width in texels (the turn is made in texel units, not in the UV square's)."""

    degrees: float
    aspect: float = 1.0


@dataclass(frozen=True)
class StackResult:
    """The new maps of one stack, sharing one UV scale."""

    stack: TextureStack
    maps: list[MapResult]
    uv_scale: tuple[float, float]
    provenance: Provenance
    wrap_only: bool = False  # an already-tileable stack: only set wrap = repeat (maps are the sources)
    uv_turn: UVTurn | None = None  # a straightened tile turned back in the UVs (None: the UVs do not turn it)
    scale_known: bool = True  # False: a dry run's guess, the tile not made yet (its UV scale is known once it is)


@dataclass
class AuthoringResult:
    """What authoring did (or, in a dry run, would do)."""

    layers_written: list[Path] = field(default_factory=list)  # layers / documents saved
    backups: list[Path] = field(default_factory=list)  # `.bak` copies (in place only)
    edited_prims: list[str] = field(default_factory=list)  # "<path>" of texture nodes / mtlx nodes
    findings: list[Finding] = field(default_factory=list)
    plan: list[str] = field(default_factory=list)  # one human-readable line per edit
    dry_run: bool = False
    output: Path | None = None  # the new layer / document (NEW_LAYER mode), if written or planned
    not_written: list[tuple[str, str]] = field(default_factory=list)  # ("<texture node>", why) left unedited
    # (material, "<texture node>", why): a node another material shares, which keeps that material's tile
    not_written_for: list[tuple[str, str, str]] = field(default_factory=list)

    def refusals(self) -> list[Finding]:
        """The findings that say an edit was not made (errors and skips; a warning, such as the schema registry
        built before the schema was registered, is not one)."""
        return [f for f in self.findings if f.severity in (Severity.ERROR, Severity.SKIPPED)]

    def unwritten_nodes(self, material: str | None = None) -> dict[str, str]:
        """``"<node>"`` -> why, for every texture node whose edits were not made (for ``material``: also those
        that show another material's tile)."""
        return {**{n: why for m, n, why in self.not_written_for if m == material}, **dict(self.not_written)}

    def to_dict(self) -> dict:
        return {
            "layers_written": [str(p) for p in self.layers_written],
            "backups": [str(p) for p in self.backups],
            "edited_prims": list(self.edited_prims),
            "findings": [f.to_dict() for f in self.findings],
            "plan": list(self.plan),
            "dry_run": self.dry_run,
            "output": str(self.output) if self.output else None,
            "not_written": [list(item) for item in self.not_written],
        }


def uv_scale_for(working_size: tuple[int, int], crop: tuple[int, int]) -> tuple[float, float]:
    """UV scale that keeps the pattern's real-world size for a 2c x 2c tile.

    The working image is W x H pixels for the UV unit square, so the tile spans 2c/W x 2c/H of
    UV space; multiplying UVs by (W / 2c_w, H / 2c_h) makes one UV unit one tile.

    >>> uv_scale_for((1024, 512), (128, 128))
    (4.0, 2.0)
    """
    (w, h), (cw, ch) = working_size, crop
    if min(w, h, cw, ch) <= 0:
        raise ValueError(f"working size {working_size} and crop {crop} must be positive")
    return (w / (2.0 * cw), h / (2.0 * ch))


def shared_with(material: str) -> str:
    """Why a texture node's edits for one material were not made: another material shares it and keeps its tile."""
    return (f"the texture node is shared with {material}, which keeps its own tile there (this material's tile is "
            "written but not used); give each material its own texture node")


def node_key(tex_map) -> str:
    """How a texture node's edits are named where they are not written: the node, and the variant selection its
    stack was found under (one node under two selections has two sets of edits, and one refused must not fail
    the other)."""
    from seamless_usd.findings import prim_ref
    from seamless_usd.textures import describe_selection

    node = prim_ref(tex_map.node.strip("<>"))
    return f"{node} in {describe_selection(tex_map.selection)}" if tex_map.selection else node
