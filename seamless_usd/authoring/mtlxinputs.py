"""Small helpers of :mod:`.mtlx` on MaterialX inputs: an input a node does not have yet, vector2 values written
with full float precision, and whether a gltf image node's own UV transform is the identity."""
from __future__ import annotations

import MaterialX as mx

__all__ = ["UnauthoredInput", "set_vector2", "gltf_identity", "vector2", "fmt"]


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
