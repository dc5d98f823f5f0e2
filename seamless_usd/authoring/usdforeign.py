"""Opinions in a new layer this tool wrote that it did not write itself: a prim, a property or layer metadata a TD
added since (a light, a note, an override of another input). A layer made again over a changed stage does not
carry them over, so they are found first, kept in a backup and named (:func:`.usd._author_new_layer`)."""
from __future__ import annotations

from pxr import Sdf

from seamless_usd.authoring.usdnodes import Names
from seamless_usd.findings import prim_ref
from seamless_usd.naming import is_tile_name

__all__ = ["not_ours", "not_ours_words"]

#: Properties this tool authors in a new layer: a texture's file, wrap and UV input, a UV node's own, its record.
_OUR_PROPERTIES = frozenset({"inputs:file", "inputs:wrapS", "inputs:wrapT", "inputs:uaddressmode", "inputs:vaddressmode",
                             "inputs:st", "inputs:texcoord", "inputs:in", "inputs:scale", "inputs:rotation",
                             "inputs:translation", "inputs:pivot", "inputs:rotate", "inputs:offset",
                             "inputs:operationorder", "inputs:uvtiling", "inputs:uvoffset", "info:id",
                             "outputs:result", "outputs:out"})


def not_ours(layer: Sdf.Layer) -> list[str]:
    """The opinions in a new layer this tool wrote that it did not write itself (a prim, a property or layer
    metadata a TD added since: a light, a note, an override of another input), by where they are."""
    found: list[str] = []
    if set(layer.customLayerData) - {Names.MADE_FROM} or len(layer.subLayerPaths) != 1 or layer.defaultPrim:
        found.append("its layer metadata")

    def ours(spec: Sdf.PrimSpec) -> bool:
        return (spec.name.startswith((Names.UV_NODE, Names.UV_READER))
                or any(str(a).startswith("Seamless") for a in spec.GetInfo("apiSchemas").GetAddedOrExplicitItems()))

    def visit(spec: Sdf.PrimSpec) -> None:
        if not ours(spec):
            extra = [p.name for p in spec.properties if p.name not in _OUR_PROPERTIES
                     and not p.name.startswith("seamless:") and not _a_tile(p)]
            if spec.specifier != Sdf.SpecifierOver or extra:
                found.append(prim_ref(spec.path.StripAllVariantSelections()) + (f" ({', '.join(extra[:3])})"
                                                                                 if extra else ""))
                return
        for child in spec.nameChildren:
            visit(child)
        for variant_set in spec.variantSets:
            for variant in variant_set.variants:
                visit(variant.primSpec)

    for root in layer.rootPrims:
        visit(root)
    return found


def _a_tile(prop: Sdf.PropertySpec) -> bool:
    """An asset-valued input (a material's interface input that holds a texture's file) set to one of this tool's
    tiles."""
    value = getattr(prop, "default", None)
    return isinstance(value, Sdf.AssetPath) and is_tile_name(value.path)


def not_ours_words(not_ours: list[str], what: str) -> str:
    """A warning's words for the opinions :func:`not_ours` found, and ``what`` becomes of them."""
    more = f" and {len(not_ours) - 4} more" if len(not_ours) > 4 else ""
    return (f"holds opinions this tool did not write ({', '.join(not_ours[:4])}{more}); {what}; keep your own "
            "opinions in a layer of your own (this one is made again whenever the stage below it changes)")
