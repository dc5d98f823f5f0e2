"""Materials of MaterialX documents, read with the MaterialX package.

Documents come from the command line or from USD prims that reference them (usd-core has no
MaterialX file-format plugin). Paths get the active ``fileprefix`` (document, nodegraph or node,
the nearest wins, as in MaterialX) and resolve against the document's folder.
"""
from __future__ import annotations

from pathlib import Path

import MaterialX as mx

from seamless_usd.discover import mtlxgraph
from seamless_usd.discover.colorspace import Label
from seamless_usd.discover.maps import TextureUse
from seamless_usd.discover.tokens import (
    COLOUR_TYPES,
    SEPARATE_OUTPUTS,
    tile_token,
    Codes,
    MtlxCategories,
    MtlxInputs,
    Recorded,
    Terminals,
    Wrap,
)
from seamless_usd.textures import NORMAL_ROLES, Origin, RecordedSource, RoleUse
from seamless_usd.discover.uv import mtlx_uv_chain
from seamless_usd.errors import InputError
from seamless_usd.findings import Finding, Severity, asset_ref

__all__ = ["read_document", "walk_document"]

_MAX_DEPTH = 64


def read_document(path: str | Path) -> mx.Document:
    """Read a ``.mtlx`` file (with its XIncludes); InputError naming the file when it cannot be read."""
    path = Path(path).resolve()
    if not path.is_file():
        raise InputError(f"{asset_ref(path)}: no such MaterialX document")
    doc = mx.createDocument()
    try:
        mx.readFromXmlFile(doc, str(path), mx.FileSearchPath(str(path.parent)))
    except Exception as exc:  # noqa: BLE001 - MaterialX raises several unrelated exception types
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{asset_ref(path)}: cannot read the MaterialX document: {first}") from None
    doc.setDataLibrary(mtlxgraph.standard_library())  # node definitions, for nodedef names
    return doc


def walk_document(
    doc: mx.Document, path: str | Path, *, under: str = "", only: str = "", flat: bool = False
) -> tuple[list[str], list[TextureUse], list[Finding]]:
    """Materials and texture uses of a document.

    ``under`` is the USD prim a referenced document is attached to: its materials are named
    where usdMtlx composes them: ``<under/Materials/name>`` for a reference to the document (its
    default prim ``/MaterialX``), ``<under/name>`` (``flat``) for one to ``</MaterialX/Materials>``,
    or ``<under>`` itself when the reference targets one material (``only``). Materials of a
    document read directly are ``<name>``.
    """
    document = str(Path(path).resolve())
    materials: list[str] = []
    uses: list[TextureUse] = []
    errors: list[Finding] = []
    for material in doc.getMaterialNodes():
        if only and material.getName() != only:
            continue
        if under:
            name = f"<{under}>" if only else (
                f"<{under}/{material.getName()}>" if flat else f"<{under}/Materials/{material.getName()}>")
        else:
            name = f"<{material.getNamePath()}>"
        materials.append(name)
        try:
            found, custom = _material_uses(material, name, document)
            uses.extend(found)
            errors.extend(_file_node_finding(node, consumer, name, document) for node, consumer in custom)
        except Exception as exc:  # noqa: BLE001 - one bad material must not stop the scan
            errors.append(Finding(Severity.ERROR, Codes.DISCOVERY_ERROR, f"{name} {asset_ref(document)}",
                                  f"cannot follow the material network: {type(exc).__name__}: {exc}"))
    valid, said = doc.validate()
    if not valid:  # a connection to a node or graph that is not there reads as no texture at all: say why
        lines = [" ".join(line.split()) for line in said.strip().splitlines() if line.strip()]
        errors.append(Finding(Severity.WARNING, Codes.MTLX_INVALID, asset_ref(document),
                              f"the document does not validate ({'; '.join(lines[:3])}"
                              f"{f'; and {len(lines) - 3} more' if len(lines) > 3 else ''}): a material may read nothing "
                              "where it connects to what is not there, and a renderer may not read it; fix the "
                              "document"))
    return materials, uses, errors


def _material_uses(material: mx.Node, name: str, document: str) -> tuple[list[TextureUse], list[tuple[mx.Node, str]]]:
    """The material's texture uses, and the nodes of custom definitions with a file input its shaders read
    (:func:`_trace`), each with the shader input reading it."""
    uses: list[TextureUse] = []
    custom: dict[str, tuple[mx.Node, str]] = {}
    shaders = []
    for shader_type in Terminals.MTLX_SHADER_TYPES:
        shaders.extend(mx.getShaderNodes(material, shader_type))
    for shader in shaders:
        for inp in shader.getInputs():
            consumer = f"<{shader.getNamePath()}.{inp.getName()}>"
            for tex, channels, flip in _trace(inp, None, 0, False):
                if channels is None:
                    custom.setdefault(tex.getNamePath(), (tex, consumer))
                else:
                    uses.append(_texture_use(name, tex, RoleUse(inp.getName(), channels, consumer), flip, document))
    return uses, list(custom.values())


def _file_node_finding(node: mx.Node, consumer: str, material: str, document: str) -> Finding:
    """A skipped finding for a node that takes a file but is no image node this tool reads: a node of a definition
    the document makes itself (a studio's wrapper round ``image``), whose texture is inside the definition and shared
    by every node of it, or a standard one such as ``triplanarprojection``."""
    files = [i.getValueString() for i in node.getInputs() if i.getType() == MtlxInputs.FILENAME_TYPE]
    shown = f" {asset_ref(files[0])}" if files and files[0] else ""
    definition = mtlxgraph.node_type_name(node)
    custom = node.getDocument().getChild(definition) is not None  # defined in the document, not a standard library
    what = (f"a node of the document's own definition {definition}, whose image is inside the definition (shared "
            "by every node of it): flatten the document's custom nodes into their graphs (MaterialX "
            "flattenSubgraphs) to process it" if custom else
            f"{'an' if node.getCategory()[:1].lower() in 'aeiou' else 'a'} {node.getCategory()} node ({definition}), "
            "which this tool does not make tileable")
    return Finding(Severity.SKIPPED, Codes.FILE_NODE_NOT_READ, f"<{node.getNamePath()}>{shown}",
                   f"{consumer} reads a file through {what} (material {material} in {asset_ref(document)})",
                   material=material)


def _compose(inner: tuple[int, ...], outer: tuple[int, ...] | None) -> tuple[int, ...]:
    return inner if outer is None else tuple(inner[i] for i in outer if i < len(inner))


def _trace(inp: mx.Input, pick, depth: int, flip: bool, seen: set | None = None):
    """Yield ``(texture node, channels, normal_y_flip)`` for every texture node feeding ``inp``.

    ``seen`` holds the (node, output, channel pick, flip) visits of this trace, so cycles end and
    shared upstream nodes are walked once, not once per path.
    """
    if depth > _MAX_DEPTH:
        return
    up = mtlxgraph.upstream(inp)
    if up is None:
        return
    node, out_name = up
    seen = set() if seen is None else seen
    visit = (node.getNamePath(), out_name, pick, flip)
    if visit in seen:
        return
    seen.add(visit)
    category = node.getCategory()
    if category not in MtlxCategories.TEXTURES and any(i.getType() == MtlxInputs.FILENAME_TYPE
                                                       for i in node.getInputs()):
        yield node, None, flip  # a node reading a file that is no image node read: named (see _file_node_finding)
        return
    if category in MtlxCategories.TEXTURES:
        channels = mtlxgraph.channels_of(node.getType(), out_name) or "rgb"
        if pick is not None:
            channels = "".join(channels[i] for i in pick if i < len(channels)) or channels
        yield node, channels, flip
        return
    if category in (MtlxCategories.PLACE2D, MtlxCategories.TEXCOORD, MtlxCategories.GEOMPROPVALUE):
        return
    if category in MtlxCategories.SEPARATE and out_name in SEPARATE_OUTPUTS:
        yield from _trace(node.getInput(MtlxInputs.IN), _compose((SEPARATE_OUTPUTS[out_name],), pick), depth + 1, flip, seen)
        return
    if category == MtlxCategories.EXTRACT:
        index, _ = mtlxgraph.input_value(node, MtlxInputs.INDEX, 0, "")
        yield from _trace(node.getInput(MtlxInputs.IN), _compose((int(index),), pick), depth + 1, flip, seen)
        return
    if category == MtlxCategories.NORMALMAP:
        scale, _ = mtlxgraph.input_value(node, MtlxInputs.SCALE, 1.0, "")
        flip = flip or (not isinstance(scale, (int, float)) and float(scale[1]) < 0)
    for upstream in node.getInputs():
        yield from _trace(upstream, pick, depth + 1, flip, seen)


def _texture_use(material: str, tex: mx.Node, role: RoleUse, flip: bool, document: str) -> TextureUse:
    file_inp = tex.getInput(MtlxInputs.FILE)
    src = mtlxgraph.value_source(file_inp)
    asset = resolved = udim = expected = ""
    file_at = None
    labels: list[Label] = []
    if src is not None and src.getValueString():
        asset = src.getValueString()
        prefixed = src.getResolvedValueString()  # applies the active fileprefix
        file_at = mtlxgraph.authored_at(src, document)
        base = Path(file_at.layer).parent
        candidate = Path(prefixed) if Path(prefixed).is_absolute() else base / prefixed
        expected = str(candidate)
        if tile_token(prefixed):
            udim = expected
        elif candidate.is_file():
            resolved = str(candidate.resolve())
    # the colour space stated on the file input, else on the interface input its value comes from, else the one
    # they inherit (node graph, document)
    holders = [h for h in (file_inp, src) if h is not None]
    stated = [h.getColorSpace() for h in holders if h.hasColorSpace()] + [h.getActiveColorSpace() for h in holders]
    if tex.getType() not in COLOUR_TYPES:  # MaterialX transforms colour images only: the others read as stored
        labels.append(Label("raw", f"MaterialX {tex.getType()} image, never colour-transformed"))
    elif any(stated):
        labels.append(Label(next(c for c in stated if c), "MaterialX colorspace"))
    tiled = tex.getCategory() == MtlxCategories.TILEDIMAGE
    wrap_s = Wrap.MTLX_DEFAULT if tiled else mtlxgraph.input_value(tex, MtlxInputs.UADDRESSMODE, Wrap.MTLX_DEFAULT, document)[0]
    wrap_t = Wrap.MTLX_DEFAULT if tiled else mtlxgraph.input_value(tex, MtlxInputs.VADDRESSMODE, Wrap.MTLX_DEFAULT, document)[0]
    return TextureUse(
        material=material,
        node=tex.getNamePath(),
        node_type=mtlxgraph.node_type_name(tex),
        origin=Origin.MTLX,
        asset=asset,
        resolved=resolved,
        udim_pattern=udim,
        expected=expected,
        file_at=file_at,
        role=role,
        labels=labels,
        wrap_s=str(wrap_s),
        wrap_t=str(wrap_t),
        uv=mtlx_uv_chain(tex, document),
        document=document,
        normal_y_flip=flip and role.role in NORMAL_ROLES,
        recorded_passed=(tex.getAttribute(Recorded.MTLX_PASSED) == "true"
                         if tex.hasAttribute(Recorded.MTLX_SOURCE) and tex.hasAttribute(Recorded.MTLX_PASSED) else None),
        recorded_source=_recorded_source(tex, document),
    )


def _recorded_source(tex: mx.Node, document: str) -> RecordedSource | None:
    """The source the tile of ``tex`` records (relative to its document), or None when it is not this tool's tile."""
    asset = tex.getAttribute(Recorded.MTLX_SOURCE) if tex.hasAttribute(Recorded.MTLX_SOURCE) else ""
    if not asset:
        return None
    path = Path(document).parent / asset
    return RecordedSource(asset, str(path.resolve()) if path.is_file() else "")
