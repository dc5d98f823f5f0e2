"""Small helpers of :mod:`.mtlx` on MaterialX inputs: the names it uses, an input a node does not have yet, vector2
values written with full float precision, whether a gltf image node's own UV transform is the identity, and which
input a node's tile goes to."""
from __future__ import annotations

import MaterialX as mx

__all__ = ["MtlxNames", "UnauthoredInput", "set_vector2", "gltf_identity", "vector2", "fmt", "own_file_input"]


class MtlxNames:
    """Categories, input names, values and provenance attributes, named once."""

    OUTPUT_SUFFIX = ".seamless"
    IMAGE = "image"
    TILED_IMAGE = "tiledimage"
    GLTF_PREFIX = "gltf_"  # gltf_image, gltf_colorimage, ...: their own place2d inside
    PLACE_2D = "place2d"
    UV_NODE = "seamless_uv"
    UV_READER = "seamless_uv_texcoord"  # the texcoord node (UV0) a place2d reads where the image read its default UVs
    VECTOR2 = "vector2"
    STRING = "string"
    FILENAME = "filename"
    FILE = "file"
    TEXCOORD = "texcoord"
    SCALE = "scale"
    U_ADDRESS = "uaddressmode"
    V_ADDRESS = "vaddressmode"
    PERIODIC = "periodic"
    UV_TILING = "uvtiling"
    UV_OFFSET = "uvoffset"
    CONNECTION_ATTRS = ("nodename", "nodegraph", "output", "interfacename", "value")
    MARK_UV = "seamless_uvtransform"  # "true" on the scale place2d seamless-usd inserted, "turn" on its turn
    MARK_TURN = "turn"
    MARK_TILING = "tiling"  # on the multiply node that scales a tiledimage's connected uvtiling / uvoffset
    UV_TURN_NODE = "seamless_uv_turn"
    ROTATE = "rotate"
    FLOAT = "float"
    SOURCE_ASSET = "seamless_sourceasset"
    CROP_SIZE = "seamless_cropsize"
    UV_SCALE = "seamless_uvscale"
    PASSED = "seamless_passed"
    VERDICT = "seamless_verdict"
    Q_PASSED = "seamless_qpassed"
    Q_TAU = "seamless_qtau"
    Q_BAND_MIN = "seamless_qbandmin"
    MODEL_HASH = "seamless_modelhash"
    TOOL_VERSION = "seamless_toolversion"
    STRAIGHTENED = "seamless_straightened"
    LEVELLED = "seamless_levelled"
    EVENED = "seamless_evened"
    UV_TURN = "seamless_uvturn"
    RECTIFIED = "seamless_rectified"
    MADE_FROM = "seamless_madefrom"  # on a new document: the SHA-256 of the document it was made from


class UnauthoredInput:
    """An input a node does not have yet: reads as unset, added on the first write."""

    def __init__(self, node: mx.Node, name: str, type_name: str):
        self.node, self.name, self.type_name = node, name, type_name

    def getValueString(self) -> str:
        return ""

    def getNamePath(self) -> str:
        return f"{self.node.getNamePath()}/{self.name}"

    def _real(self) -> mx.Input:
        return self.node.getInput(self.name) or self.node.addInput(self.name, self.type_name)

    def setValueString(self, value: str) -> None:
        self._real().setValueString(value)

    def getActiveFilePrefix(self) -> str:
        return self.node.getActiveFilePrefix()

    def hasFilePrefix(self) -> bool:
        return False

    def setFilePrefix(self, prefix: str) -> None:
        self._real().setFilePrefix(prefix)


def set_vector2(inp: mx.Input, value) -> None:
    """Set a vector2 with full float precision (MaterialX's own formatting keeps 6 digits)."""
    inp.setValueString(fmt((float(value[0]), float(value[1]))))


def gltf_identity(node: mx.Node) -> bool:
    """Whether a gltf image node's own UV transform (scale, rotate, offset) is the identity."""
    for name, identity in (("scale", "1, 1"), ("rotate", "0"), ("offset", "0, 0")):
        inp = node.getInput(name)
        text = inp.getValueString() if inp is not None else ""
        if text and [float(v) for v in text.split(",")] != [float(v) for v in identity.split(",")]:
            return False
        if inp is not None and (inp.getNodeName() or inp.getInterfaceName()):
            return False
    return True


def vector2(text: str) -> tuple[float, float]:
    x, y = (float(v) for v in text.split(","))
    return (x, y)


def fmt(values) -> str:
    return ", ".join(repr(float(v)) if isinstance(v, float) else str(v) for v in values)


def own_file_input(node: mx.Node, file_input) -> tuple:
    """(the input to write ``node``'s tile to, what was changed to make it so or None): ``file_input`` (where its file
    value is authored), unless that is a nodegraph's interface input another node reads too (a decal left alone,
    another material's image): then the node's own file input, its read of the interface input cut and the
    interface's colour space kept on it, so the other node keeps its file (as a USD texture node's own file is set
    where a material input is shared). The interface input was set, and the other node showed the tile."""
    own = node.getInput(MtlxNames.FILE)
    name = own.getInterfaceName() if own is not None else ""
    graph = node.getParent()
    if own is not None and not name and own.getValueString() and file_input is not own:
        return own, None  # cut by an earlier run, on the document it wrote: the node reads its own input
    if not name or file_input is own or not isinstance(graph, mx.NodeGraph):
        return file_input, None
    others = _other_readers(node, graph, name)
    if not others:
        return file_input, None
    space = file_input.getActiveColorSpace() if isinstance(file_input, mx.Input) else ""
    own.removeAttribute("interfacename")
    if space and not own.getColorSpace():
        own.setColorSpace(space)
    return own, (f"read <{node.getNamePath()}>'s file from its own input, not from <{graph.getNamePath()}>.{name}, "
                 f"which <{others[0]}> reads too")


def _other_readers(node: mx.Node, graph, name: str) -> list[str]:
    """The nodes of ``graph`` other than ``node`` that read its interface input ``name``."""
    return [n.getNamePath() for n in graph.getNodes() if n != node
            and any(i.getInterfaceName() == name for i in n.getInputs())]


def own_input(node: mx.Node, name: str, authored) -> tuple:
    """(the input to edit ``node``'s ``name`` on, what was changed to make it so or None): ``authored`` (where the
    value is authored), unless that is a nodegraph's interface input another node reads too (a decal's address
    modes, left alone): then the node's own input, holding the interface's value, its read of the interface cut."""
    own = node.getInput(name)
    graph = node.getParent()
    interface = own.getInterfaceName() if own is not None else ""
    if not interface or authored is own or not isinstance(graph, mx.NodeGraph):
        return authored, None
    others = _other_readers(node, graph, interface)
    if not others:
        return authored, None
    value = authored.getValueString()
    own.removeAttribute("interfacename")
    own.setValueString(value)
    return own, (f"read <{node.getNamePath()}>'s {name} from its own input, not from <{graph.getNamePath()}>."
                 f"{interface}, which <{others[0]}> reads too")
