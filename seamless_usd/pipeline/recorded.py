"""Where a tile's source is recorded, for ``check`` to judge the tile against it as ``process`` did: on the texture
prim of a USD stage this tool wrote (``SeamlessTileAPI``), on the node of a MaterialX document it wrote (its
``seamless_*`` attributes), or in the tile's own file (:mod:`seamless_usd.imaging.tag`)."""
from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from seamless_usd.findings import asset_ref

__all__ = ["recorded_source", "stack_sources", "keystone_of"]


def recorded_source(path: Path, record: dict, item):
    """(tile, source, provenance) of a tile whose file records its source, when that source is still the file it
    was made from; else None, with why in ``item.note`` (it is then judged against itself)."""
    from seamless_usd.fileio import source_sha256
    from seamless_usd.pipeline.madefrom import recorded_maps

    tile, source, prov = recorded_maps(path, record)
    try:
        same = source_sha256(source.resolved) == record.get("sha256")
    except OSError:
        item.note = (f"its source {asset_ref(record['source'])} is not beside it as recorded: judged against itself "
                     "(check the stage or document that uses it to judge it against its source)")
        return None
    if not same:
        item.note = (f"its source {asset_ref(record['source'])} has changed since the tile was made: judged against "
                     "itself (process the material again)")
        return None
    return tile, source, prov


def stack_sources(stage, stack) -> tuple[list, object] | None:
    """The maps' recorded sources and the provenance recorded with them (its UV scale, straightening turn, and
    how far the source was levelled or evened before it was cut), when every map is a tile this tool wrote: into
    the USD ``stage`` (``SeamlessTileAPI``) or into a MaterialX document (its ``seamless_*`` attributes)."""
    from seamless_usd.textures import Origin

    sources, prov = [], None
    for m in stack.maps:
        found = _mtlx_source(m) if m.origin is Origin.MTLX else _usd_source(stage, m)
        if found is None:
            return None
        resolved, prov = found
        sources.append(dataclasses.replace(m, resolved=resolved, asset=prov.source_asset))
    return sources, prov


def _usd_source(stage, m) -> tuple[str, object] | None:
    """(resolved source path, provenance) recorded on the texture prim of ``m`` in ``stage``, or None."""
    if stage is None:
        return None
    from seamless_usd.authoring.schema import Schema, read_provenance

    prim = stage.GetPrimAtPath(m.node.strip("<>"))
    prov = read_provenance(prim) if prim else None
    attr = prim.GetAttribute(Schema.SOURCE_ASSET) if prov is not None else None
    resolved = attr.Get().resolvedPath if attr and attr.Get() is not None else ""
    return (resolved, prov) if resolved else None


_MTLX_DOCUMENTS: dict[str, object] = {}


def _mtlx_source(m) -> tuple[str, object] | None:
    """(resolved source path, provenance) recorded on the MaterialX node of ``m`` (its source asset relative to the
    document it is written in), or None."""
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
    if prov is None or not prov.source_asset:
        return None
    resolved = Path(m.document).parent / prov.source_asset
    return (str(resolved.resolve()), prov) if resolved.is_file() else None


def keystone_of(prov):
    """The rectification recorded in ``prov`` (``seamless:rectified``: the point and the leans' spread), or None."""
    if not prov.rectified[2]:
        return None
    from seamless_usd.imaging.perspective import Keystone

    return Keystone(*prov.rectified)
