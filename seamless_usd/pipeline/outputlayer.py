"""The new layer or document a run writes (``-o/--output-layer``'s, or the default one beside each input): refused,
before any work, where it would not be the new layer of its input, or would replace a file this tool did not write
or a new layer it wrote over another stage."""
from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from seamless_usd.discover.tokens import MTLX_SUFFIX
from seamless_usd.errors import UsageError
from seamless_usd.findings import asset_ref

__all__ = ["MTLX_SUFFIXES", "check_output_layer", "default_layer_problem", "replace_problem"]

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
    problem = replace_problem(output, inputs[0]) if inputs else None
    if problem:
        raise UsageError(f"-o/--output-layer {asset_ref(output)} {problem}; name a new file, or move that one away")


def default_layer_problem(source: Path) -> str | None:
    """Why the new layer (a stage's) or document (a ``.mtlx``'s) a run writes beside ``source`` without ``-o`` cannot
    be written (:func:`replace_problem`), in the words its stacks fail with; None where it can."""
    from seamless_usd import authoring

    out = (authoring.default_output_document(source) if source.suffix.lower() in MTLX_SUFFIXES
           else authoring.default_output_layer(source))
    problem = replace_problem(out, source)
    if problem is None:
        return None
    return f"its new layer {asset_ref(out)} {problem}; move that file away, or name another with -o"


def replace_problem(output: Path, source: Path) -> str | None:
    """Why the new layer or document ``output`` of the input ``source`` may not be written where it would replace a
    file: one this tool did not write (a user's own layer of that name), or a new layer it wrote over another stage
    (its first sublayer is not ``source``: another shot's overrides); None where it may."""
    if not output.exists():
        return None
    owner = _own_output(output)
    if owner is False:
        return "exists and is not a layer or document this tool wrote: it is not replaced"
    if isinstance(owner, Path) and owner.resolve() != Path(source).resolve():
        return f"is the new layer this tool wrote over another stage ({asset_ref(owner)}): it is not replaced"
    return None


def _own_output(path: Path) -> bool | Path:
    """Whether ``path`` is a new layer or document this tool wrote (it records what it was made from): for a layer,
    the stage it was written over (its first sublayer), True where that cannot be read; False where not ours."""
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
    if not layer or Names.MADE_FROM not in dict(layer.customLayerData):
        return False
    below = list(layer.subLayerPaths)
    if not below:
        return True
    first = Path(below[0])
    return first if first.is_absolute() else path.parent / first
