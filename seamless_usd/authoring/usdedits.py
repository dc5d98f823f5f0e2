"""Spec-level edits planned by authoring and applied with the Sdf API in one change block, and
where a new layer's edits go when the opinion they override is authored inside a variant."""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from pxr import Sdf, Usd

from seamless_usd.authoring.types import AuthoringResult, Codes, StackResult, node_key

from seamless_usd.authoring.usdnodes import Names
from seamless_usd.textures import TextureStack, describe_selection
from seamless_usd.findings import Finding, Severity, asset_ref, prim_ref

__all__ = ["variant_edit_target", "variant_not_composed", "check_uv_composed", "keep_whole_stacks", "not_composed",
           "strongest_layer"]


class _EditKind:
    VALUE = "value"  # set an attribute's default value (None: declare the attribute only)
    CONNECT = "connect"  # replace an input's connections with one source (None: with none)
    DEFINE = "define"  # define a Shader prim
    SCHEMA = "schema"  # prepend an applied API schema
    RETARGET = "retarget"  # delete a reference and prepend one to another file (value: (old, new))


@dataclass
class _Edit:
    """One spec-level edit: a value, a connection, a new node or an applied schema."""

    target: Usd.EditTarget
    kind: str  # an _EditKind
    path: Sdf.Path  # stage namespace: property path, or prim path for define / schema
    type_name: Sdf.ValueTypeName | None = None
    value: object = None
    variability: object = Sdf.VariabilityVarying

    def describe(self, layer_name: str) -> str:
        where = f"in {asset_ref(layer_name)}"
        spec = self.target.MapToSpecPath(self.path)
        if spec.ContainsPrimVariantSelection():  # inside a variant: the other selections keep their opinions
            site = spec
            while not site.IsPrimVariantSelectionPath():
                site = site.GetParentPath()
            vset, vsel = site.GetVariantSelection()
            where += f", inside variant {{{vset}={vsel}}} of {prim_ref(site.GetParentPath().StripAllVariantSelections())}"
        if self.kind == _EditKind.VALUE and self.value is None:
            return f"declare {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.VALUE and isinstance(self.value, Sdf.ValueBlock):
            return f"block {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.VALUE:
            shown = asset_ref(self.value.path) if isinstance(self.value, Sdf.AssetPath) else self.value
            return f"set {prim_ref(self.path)} = {shown} {where}"
        if self.kind == _EditKind.CONNECT and self.value is None:
            return f"disconnect {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.CONNECT:
            return f"connect {prim_ref(self.path)} -> {prim_ref(self.value)} {where}"
        if self.kind == _EditKind.DEFINE:
            return f"define {self.value} {prim_ref(self.path)} {where}"
        if self.kind == _EditKind.RETARGET:
            old, new = self.value
            return (f"reference {prim_ref(self.path)}: {asset_ref(old.assetPath)} -> "
                    f"{asset_ref(new.assetPath)} {where}")
        return f"apply {self.value} to {prim_ref(self.path)} {where}"

    def apply(self) -> None:
        layer = self.target.GetLayer()
        spec_path = self.target.MapToSpecPath(self.path)
        if self.kind == _EditKind.RETARGET:
            old, new = self.value
            references = Sdf.CreatePrimInLayer(layer, spec_path).referenceList
            references.deletedItems.append(old)
            references.prependedItems.append(new)
            return
        if self.kind in (_EditKind.DEFINE, _EditKind.SCHEMA):
            prim_spec = Sdf.CreatePrimInLayer(layer, spec_path)
            if self.kind == _EditKind.DEFINE:
                prim_spec.specifier = Sdf.SpecifierDef
                prim_spec.typeName = Names.SHADER_TYPE
            else:
                _prepend_api_schema(prim_spec, self.value)
            return
        prim_spec = Sdf.CreatePrimInLayer(layer, spec_path.GetPrimPath())
        attr_spec = layer.GetAttributeAtPath(spec_path)
        if not attr_spec:
            attr_spec = Sdf.AttributeSpec(prim_spec, spec_path.name, self.type_name, self.variability)
        if self.kind == _EditKind.VALUE:
            if self.value is not None:
                attr_spec.default = self.value
        elif self.value is None:
            attr_spec.connectionPathList.ClearEditsAndMakeExplicit()  # an explicit empty list: no connection
        else:
            # connection paths never hold variant selections, even when authored inside a variant
            attr_spec.connectionPathList.explicitItems = [
                self.target.MapToSpecPath(self.value).StripAllVariantSelections()]


def _prepend_api_schema(prim_spec: Sdf.PrimSpec, name: str) -> None:
    ops = prim_spec.GetInfo("apiSchemas") if prim_spec.HasInfo("apiSchemas") else Sdf.TokenListOp()
    if ops.isExplicit:
        if name not in ops.explicitItems:
            ops.explicitItems = list(ops.explicitItems) + [name]
    elif name not in ops.prependedItems and name not in ops.appendedItems:
        ops.prependedItems = list(ops.prependedItems) + [name]
    prim_spec.SetInfo("apiSchemas", ops)




def _opinion_node(prim: Usd.Prim, attr: Usd.Attribute | None):
    """The prim-index node of the strongest opinion: ``attr``'s value, else ``prim``'s spec."""
    if attr and attr.HasAuthoredValue():
        node = attr.GetResolveInfo().GetNode()
        if node:
            return node
    specs = prim.GetPrimStack()
    if not specs:
        return None
    strongest = specs[0]
    stack = [prim.GetPrimIndex().rootNode]
    while stack:
        node = stack.pop(0)
        if node.path == strongest.path and strongest.layer in node.layerStack.layers:
            return node
        stack.extend(node.children)
    return None


def variant_edit_target(layer: Sdf.Layer, prim: Usd.Prim, attr: Usd.Attribute | None):
    """Edit target in ``layer`` (a layer over the stage) for overriding ``attr`` / ``prim``.

    When the strongest opinion is authored inside variants (``/Asset{finish=wood}Looks/...``,
    possibly in a payload or reference), the edits go inside the same variant selections at
    the corresponding stage paths (``/Asset{finish=wood}``): an override outside the variant
    would also replace the other variants' textures. A :class:`Finding` when a variant's site
    cannot be mapped to the stage's namespace (the edit cannot be made from this layer).
    """
    node = _opinion_node(prim, attr)
    if node is None:
        return Usd.EditTarget(layer)
    chain = []  # the opinion's node and the nodes that brought it in: a payload or reference authored inside a
    while node:  # variant is a child of that variant's node, whose path holds the selection
        chain.append(node)
        node = node.parent
    selections = []
    for node in reversed(chain):
        for prefix in node.path.GetPrefixes():
            if not prefix.IsPrimVariantSelectionPath():
                continue
            vset, vsel = prefix.GetVariantSelection()
            site = node.mapToRoot.MapSourceToTarget(prefix.GetParentPath().StripAllVariantSelections())
            if site.isEmpty:
                return Finding(
                    Severity.ERROR, Codes.VARIANT_NOT_EDITABLE, prim_ref(prim.GetPath()),
                    f"its value is authored inside variant {{{vset}={vsel}}} of {prim_ref(prefix.GetParentPath())}, "
                    "which cannot be reached from the stage's namespace; nothing written for it "
                    "(edit that variant's layer with --in-place)")
            if (site, vset, vsel) not in selections:
                selections.append((site, vset, vsel))
    if not selections:
        return Usd.EditTarget(layer)
    path, previous = Sdf.Path.absoluteRootPath, Sdf.Path.absoluteRootPath
    for site, vset, vsel in selections:
        path = path.AppendPath(site.MakeRelativePath(previous)).AppendVariantSelection(vset, vsel)
        previous = site
    return Usd.EditTarget.ForLocalDirectVariant(layer, path)


def variant_not_composed(stack: TextureStack) -> Finding:
    """Why a stack found under another variant selection is not written into an open stage that
    authoring must not recompose (a DCC's stage): edited as the stage selects, the selected
    variant's look would change instead."""
    return Finding(
        Severity.SKIPPED, Codes.VARIANT_NOT_EDITABLE, stack.material,
        f"found under variant selection {describe_selection(stack.selection)}, which this open stage does not "
        "make; nothing written for it (process the file to edit that variant)", material=stack.material)


def check_uv_composed(author, results: Sequence[StackResult], result: AuthoringResult) -> None:
    """Every texture-coordinate connection authored (a texture's ``st`` / ``texcoord`` to its UV scale) is the one
    the stage composes, under the variant selection its stack was found in; a texture whose new connection loses to a
    stronger one (an ``st`` authored outside the variant that holds its file) is recorded as not written, with a
    finding: its tile would show at the wrong scale."""
    from seamless_usd.discover.variants import apply_selection

    selections = {r.stack.id: r.stack.selection for r in results}
    nodes = {(str(Sdf.Path(m.map.node.strip("<>"))), r.stack.id): node_key(m.map) for r in results for m in r.maps}
    session = author.stage.GetSessionLayer()
    composed = None
    try:
        for edit, owner in zip(author.edits, author.owners):
            if edit.kind != _EditKind.CONNECT or edit.path.name not in ("inputs:st", "inputs:texcoord"):
                continue
            node = nodes.get((str(edit.path.GetPrimPath()), owner))
            if node is None or node in result.unwritten_nodes():
                continue
            selection = selections.get(owner, ())
            if selection != composed:
                apply_selection(session, selection)
                composed = selection
            attr = author.stage.GetAttributeAtPath(edit.path)
            if attr and edit.value in attr.GetConnections():
                continue
            layer = edit.target.GetLayer()
            written = author.layer_names.get(layer) or layer.realPath or layer.identifier
            fix = ("(an st connection outside the variant that sets the file): connect st inside each variant, or "
                   "write the edits into that layer" if selection or edit.target.MapToSpecPath(
                       edit.path).ContainsPrimVariantSelection() else
                   "(it is authored in a stronger layer than the file value): author the file value there too, or "
                   "leave out --in-place (a new layer is stronger than both)")
            not_composed(result, node, (
                f"its new UV scale is authored in {asset_ref(written)}, but the texture-coordinate connection "
                f"{asset_ref(strongest_layer(attr, author.layer_names))} holds is stronger and the stage keeps it, so the "
                f"tile would show at the wrong scale {fix}"))
    finally:
        if composed:
            apply_selection(session, ())


def strongest_layer(attr: Usd.Attribute | None, names: dict | None = None) -> str:
    """The file (or identifier) of the layer holding ``attr``'s strongest opinion, for a message; ``names``: the
    layers being written, by the file each becomes (a layer is written to a temporary file first)."""
    specs = attr.GetPropertyStack() if attr else []
    if not specs:
        return "another layer"
    layer = specs[0].layer
    return (names or {}).get(layer) or layer.realPath or layer.identifier


def not_composed(result: AuthoringResult, node: str, why: str) -> None:
    """Record that the texture ``node``'s edits are not the ones the stage composes: not written, with an error
    finding saying ``why`` (once a node)."""
    if node not in result.unwritten_nodes():
        result.not_written.append((node, why))
        result.findings.append(Finding(Severity.ERROR, Codes.EDIT_NOT_COMPOSED, node, why))


def keep_whole_stacks(author, results: Sequence[StackResult], result: AuthoringResult, before: dict, planned: int
                       ) -> None:
    """A stack one of whose maps' edits the stage does not compose keeps none of its edits (its maps would no
    longer line up): the layers go back to what they held and the other stacks' edits are made again."""
    unwritten = result.unwritten_nodes()
    failed = {r.stack.id for r in results for m in r.maps if node_key(m.map) in unwritten}
    if not failed:
        return
    for layer, text in before.items():
        layer.ImportFromString(text)
    author.edits = [e for e, owner in zip(author.edits, author.owners) if owner not in failed]
    author.owners = [o for o in author.owners if o not in failed]
    del result.plan[planned:]
    result.edited_prims = [p for p in result.edited_prims if p not in {
        prim_ref(m.map.node.strip("<>")) for r in results if r.stack.id in failed for m in r.maps}]
    author.apply()
    for r in results:
        if r.stack.id in failed:
            for m in r.maps:
                node = node_key(m.map)
                if node not in result.unwritten_nodes():
                    result.not_written.append((node, "another map of its stack cannot be edited here, so none of "
                                                     "its edits are kept (its maps would no longer line up)"))
