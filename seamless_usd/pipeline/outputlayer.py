"""The one layer or document ``-o/--output-layer`` names: refused, before any work, where it would not be the new
layer of the one input, or would replace a file this tool did not write."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from seamless_usd.discover.tokens import MTLX_SUFFIX
from seamless_usd.errors import UsageError
from seamless_usd.findings import asset_ref

__all__ = ["MTLX_SUFFIXES", "check_output_layer"]

MTLX_SUFFIXES = {MTLX_SUFFIX}
_LAYER_SUFFIXES = (".usda", ".usdc", ".usd")  # the layers a new layer can be written as (not a .usdz package)


def check_output_layer(output: Path, inputs: Sequence[Path]) -> None:
    """-o/--output-layer names the one layer or document written: one input, of its kind."""
    if len(inputs) > 1:
        raise UsageError("-o/--output-layer names one layer or document, but several inputs were given; leave it out "
                         "(each stage then gets its own <name>.seamless.usda, each document <name>.seamless.mtlx)")
    if inputs and (inputs[0].suffix.lower() in MTLX_SUFFIXES) != (output.suffix.lower() in MTLX_SUFFIXES):
        kind = "a MaterialX document (.mtlx)" if inputs[0].suffix.lower() in MTLX_SUFFIXES else "a USD layer"
        raise UsageError(f"-o/--output-layer {output}: the input {inputs[0].name} is edited in {kind}; name one")
    if output.suffix.lower() not in MTLX_SUFFIXES and output.suffix.lower() not in _LAYER_SUFFIXES:
        raise UsageError(f"-o/--output-layer {output}: a new layer is written as .usda, .usdc or .usd (a .usdz "
                         "package cannot be written in place of a layer); name one of those")
    if inputs and output.resolve() == inputs[0].resolve():
        raise UsageError(f"-o/--output-layer {asset_ref(output)} is the input itself; name a new file (or use "
                         "--in-place to edit the input, with a backup)")
    if output.exists() and not _own_output(output):
        raise UsageError(f"-o/--output-layer {asset_ref(output)} exists and is not a layer or document this tool "
                         "wrote: it is not replaced; name a new file, or move that one away")


def _own_output(path: Path) -> bool:
    """Whether ``path`` is a new layer or document this tool wrote (it records what it was made from)."""
    if path.suffix.lower() in MTLX_SUFFIXES:
        import MaterialX as mx

        from seamless_usd.authoring.mtlxinputs import MtlxNames

        doc = mx.createDocument()
        try:
            mx.readFromXmlFile(doc, str(path))
        except Exception:  # noqa: BLE001 - not a document (any more): not one of ours either
            return False
        return bool(doc.getAttribute(MtlxNames.MADE_FROM))
    from pxr import Sdf, Tf

    from seamless_usd.authoring.usdnodes import Names

    try:
        layer = Sdf.Layer.OpenAsAnonymous(str(path))
    except Tf.ErrorException:
        return False
    return bool(layer and Names.MADE_FROM in dict(layer.customLayerData))
