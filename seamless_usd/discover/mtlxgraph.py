"""Small helpers over MaterialX documents: connections, interface values and node type names."""
from __future__ import annotations

import os

from functools import lru_cache

import MaterialX as mx

from seamless_usd.discover.tokens import OUTPUT_CHANNELS, TYPE_CHANNELS
from seamless_usd.textures import AuthoredAt

__all__ = ["standard_library", "node_type_name", "upstream", "value_source", "authored_at", "input_value", "channels_of"]


@lru_cache(maxsize=1)
def standard_library() -> mx.Document:
    """The MaterialX standard libraries shipped with the package (loaded once, ~0.2 s)."""
    lib = mx.createDocument()
    mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
    return lib


def node_type_name(node: mx.Node) -> str:
    """The node's nodedef name (``ND_image_color3``, ``ND_gltf_image_color3_color3_1_0``).

    From the document's data library when it has one, else by standard-library naming.
    """
    declared = node.getNodeDefString()
    if declared:
        return declared
    nodedef = node.getNodeDef()
    if nodedef is not None:
        return nodedef.getName()
    return f"ND_{node.getCategory()}_{node.getType()}"


def _scope(elem: mx.Element) -> mx.Element:
    """The graph (document or nodegraph) whose nodes ``elem``'s connections name."""
    return elem.getParent().getParent()


def _from_output(out: mx.Output | None) -> tuple[mx.Node, str] | None:
    if out is None:
        return None
    graph = out.getParent()
    if out.getNodeName():
        node = graph.getNode(out.getNodeName())
        return (node, out.getOutputString() or "out") if node is not None else None
    if out.getNodeGraphString():
        inner = _nodegraph(graph, out.getNodeGraphString())
        if inner is not None:
            return _from_output(inner.getOutput(out.getOutputString()) if out.getOutputString() else _first_output(inner))
    if out.getInterfaceName() and graph.isA(mx.NodeGraph):
        ginp = graph.getInput(out.getInterfaceName())
        return upstream(ginp) if ginp is not None else None
    return None


def _first_output(graph: mx.Element) -> mx.Output | None:
    outs = graph.getOutputs()
    return outs[0] if outs else None


def _nodegraph(scope: mx.Element, name: str) -> mx.NodeGraph | None:
    graph = scope.getChild(name) if hasattr(scope, "getChild") else None
    if graph is None or not graph.isA(mx.NodeGraph):
        graph = scope.getDocument().getNodeGraph(name)
    return graph


def upstream(inp: mx.Input | None, _depth: int = 0) -> tuple[mx.Node, str] | None:
    """The node and output name feeding ``inp`` (through nodegraphs and interface inputs)."""
    if inp is None or _depth > 64:
        return None
    scope = _scope(inp)
    if inp.getNodeGraphString():
        graph = _nodegraph(scope, inp.getNodeGraphString())
        if graph is None:
            return None
        out = graph.getOutput(inp.getOutputString()) if inp.getOutputString() else _first_output(graph)
        return _from_output(out)
    if inp.getNodeName():
        node = scope.getNode(inp.getNodeName()) if hasattr(scope, "getNode") else None
        return (node, inp.getOutputString() or "out") if node is not None else None
    if inp.getOutputString():
        return _from_output(scope.getOutput(inp.getOutputString()))
    if inp.getInterfaceName() and scope.isA(mx.NodeGraph):
        return upstream(scope.getInput(inp.getInterfaceName()), _depth + 1)
    return None


def value_source(inp: mx.Input | None) -> mx.Input | None:
    """The input holding ``inp``'s value: itself, or the nodegraph interface input it names."""
    seen = 0
    while inp is not None and seen < 64:
        seen += 1
        if inp.getInterfaceName():
            scope = _scope(inp)
            if scope.isA(mx.NodeGraph) and scope.getInput(inp.getInterfaceName()) is not None:
                inp = scope.getInput(inp.getInterfaceName())
                continue
        return inp if inp.hasValueString() else None
    return None


def authored_at(inp: mx.Input, document: str) -> AuthoredAt:
    """Where ``inp`` is authored: its element's path and the document that holds it (an ``xi:include``'s document,
    whose href is relative to the including ``document``'s folder, or ``document`` itself)."""
    layer = inp.getActiveSourceUri() or document
    if not os.path.isabs(layer):
        layer = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(document)), layer))
    return AuthoredAt(prim=inp.getParent().getNamePath(), attribute=inp.getName(), layer=layer)


def input_value(node: mx.Node, name: str, default, document: str):
    """``(value, AuthoredAt | None)``: None when authored on the node itself or defaulted."""
    src = value_source(node.getInput(name))
    if src is None:
        return default, None
    value = src.getValue()
    if value is None:
        return default, None
    where = None if src.getParent() == node else authored_at(src, document)
    return value, where


def channels_of(type_name: str, output: str) -> str | None:
    """Channels an output reads: by name for multi-output nodes, else by value type."""
    if output in OUTPUT_CHANNELS:
        return OUTPUT_CHANNELS[output]
    return TYPE_CHANNELS.get(type_name)
