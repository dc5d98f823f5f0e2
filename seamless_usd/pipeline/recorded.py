"""Where a tile's source is recorded, for ``check`` to judge the tile against it as ``process`` did: on the texture
prim of a USD stage this tool wrote (``SeamlessTileAPI``), on the node of a MaterialX document it wrote (its
``seamless_*`` attributes), or in the tile's own file (:mod:`seamless_usd.imaging.tag`)."""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from seamless_usd.findings import asset_ref

__all__ = ["recorded_source", "stack_sources", "keystone_of"]


def recorded_source(path: Path, record: dict) -> tuple[tuple | None, str]:
    """((tile, source, provenance), "") of a tile whose file records its source, when that source is still the file
    it was made from; else (None, why), and the tile is judged against itself."""
    from seamless_usd.fileio import source_sha256
    from seamless_usd.pipeline.madefrom import recorded_maps

    tile, source, prov = recorded_maps(path, record)
    where = asset_ref(Path(source.resolved))
    try:
        same = source_sha256(source.resolved) == record.get("sha256")
    except OSError:
        return None, (f"its source {where} is not there: judged against itself (check the stage or document that "
                      "uses it to judge it against its source)")
    if not same:
        return None, f"its source {where} has changed since the tile was made: judged against itself (process again)"
    return (tile, source, prov), ""


def stack_sources(stage, stack) -> tuple[tuple[list, object] | None, str]:
    """((the maps' recorded sources, the provenance recorded with them: its UV scale, straightening turn, and how far
    the source was levelled or evened before it was cut), "") when every map is a tile this tool wrote, into the USD
    ``stage`` (``SeamlessTileAPI``) or into a MaterialX document (its ``seamless_*`` attributes), and its source is
    still the file it was made from; else (None, why: "" for a map that is no tile of this tool's). A stack found
    under another variant selection reads its provenance under that selection."""
    if stage is None or not stack.selection:
        return _stack_sources(stage, stack)
    from seamless_usd.discover.variants import apply_selection

    session = stage.GetSessionLayer()
    held = session.ExportToString()
    apply_selection(session, stack.selection)
    try:
        return _stack_sources(stage, stack)
    finally:
        session.ImportFromString(held)


def _stack_sources(stage, stack) -> tuple[tuple[list, object] | None, str]:
    from seamless_usd.imaging.tag import source_changed
    from seamless_usd.textures import Origin

    sources, prov = [], None
    for m in stack.maps:
        prov = _mtlx_provenance(m) if m.origin is Origin.MTLX else _usd_provenance(stage, m)
        if prov is None:
            return None, ""
        resolved = m.recorded_source.resolved if m.recorded_source else ""  # as the scan read it
        if not resolved:
            return None, (f"the source recorded for {asset_ref(m.asset)}, {asset_ref(prov.source_asset)}, is not there: "
                          "judged against itself")
        if source_changed(m.resolved, resolved):
            return None, (f"its source {asset_ref(Path(resolved))} has changed since the tile was made: judged against "
                          "itself (process again)")
        sources.append(dataclasses.replace(m, resolved=resolved, asset=prov.source_asset))
    return (sources, prov), ""


def _usd_provenance(stage, m):
    """The provenance recorded on the texture prim of ``m`` in ``stage``, or None."""
    if stage is None:
        return None
    from seamless_usd.authoring.schema import read_provenance

    prim = stage.GetPrimAtPath(m.node.strip("<>"))
    return read_provenance(prim) if prim else None


_MTLX_DOCUMENTS: dict[str, object] = {}


def _mtlx_provenance(m):
    """The provenance recorded on the MaterialX node of ``m``, or None."""
    import MaterialX as mx

    from seamless_usd.authoring.mtlx import read_mtlx_provenance

    try:
        st = os.stat(m.document or "")
    except OSError:
        return None
    key = f"{os.path.realpath(m.document)}|{st.st_size}|{st.st_mtime_ns}"  # the document as it is on disk now
    doc = _MTLX_DOCUMENTS.get(key)
    if doc is None:
        doc = mx.createDocument()
        try:
            mx.readFromXmlFile(doc, m.document)
        except (mx.Exception, OSError):  # it was read by the scan a moment ago: whoever reads it next says why
            return None
        _MTLX_DOCUMENTS.clear()  # one document at a time
        _MTLX_DOCUMENTS[key] = doc
    node = doc.getDescendant(m.node)
    prov = read_mtlx_provenance(node) if node is not None else None
    return prov if prov is not None and prov.source_asset else None


def keystone_of(prov):
    """The rectification recorded in ``prov`` (``seamless:rectified``: the point and the leans' spread), or None."""
    if not prov.rectified[2]:
        return None
    from seamless_usd.imaging.perspective import Keystone

    return Keystone(*prov.rectified)
