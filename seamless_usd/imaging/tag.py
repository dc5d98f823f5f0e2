"""What a tile records in its own file about how it was made: the source file it was made from (its path from
the tile's folder and its SHA-256), how that source's values are read, and how the source was made before it
was cut (its UV scale, straightened, levelled, evened). With it ``check tile.png`` judges the tile against its
source as ``process`` did, instead of against itself (``seamless_usd.pipeline.check``).

Tiles are written as PNG, OpenEXR or TIFF (:func:`.io.output_extension`). PNG and OpenEXR headers keep an
attribute of any name (``seamless:madefrom``); a TIFF keeps its image description, which then holds
:data:`DESCRIPTION_PREFIX` and the record.
"""
from __future__ import annotations

import json
import os

__all__ = ["TAG", "DESCRIPTION_PREFIX", "tag_attributes", "read_tag", "source_changed"]

#: The header attribute holding the record, as JSON.
TAG = "seamless:madefrom"
#: How an image description holding the record starts (formats with no attributes of their own).
DESCRIPTION_PREFIX = "seamless-usd madefrom "
_FREE_FORM = (".png", ".exr")


def tag_attributes(extension: str, record: dict) -> list[tuple[str, str]]:
    """The header attributes that carry ``record`` in a file with this extension."""
    text = json.dumps(record, sort_keys=True, separators=(",", ":"))
    if extension.lower() in _FREE_FORM:
        return [(TAG, text)]
    return [("ImageDescription", DESCRIPTION_PREFIX + text)]


def read_tag(path: str | os.PathLike) -> dict | None:
    """The record a tile holds (:func:`tag_attributes`), or None: no record, not a tile this tool wrote, or a file
    that cannot be opened (whoever reads its pixels next says why)."""
    import OpenImageIO as oiio

    from seamless_usd.errors import InputError
    from seamless_usd.imaging.io import oiio_name

    try:
        inp = oiio.ImageInput.open(oiio_name(os.fspath(path)))
    except InputError:  # a name the image library cannot open: the reader of the pixels says so
        return None
    if inp is None:
        oiio.geterror()  # the reader of the pixels reports it
        return None
    try:
        spec = inp.spec()
        text = str(spec.getattribute(TAG) or "")
        if not text:
            described = str(spec.getattribute("ImageDescription") or "")
            text = described[len(DESCRIPTION_PREFIX):] if described.startswith(DESCRIPTION_PREFIX) else ""
    finally:
        inp.close()
    if not text:
        return None
    try:
        record = json.loads(text)
    except ValueError:
        return None
    ok = isinstance(record, dict) and isinstance(record.get("source"), str) and isinstance(record.get("map"), dict)
    return record if ok and isinstance(record.get("made"), dict) else None


def source_changed(tile: str | os.PathLike, source: str | os.PathLike) -> bool:
    """Whether ``source`` differs from the file the tile ``tile`` records it was made from (a tile that records
    nothing, written before tiles recorded their sources, cannot say: False)."""
    from seamless_usd.fileio import source_sha256

    record = read_tag(tile) if tile else None
    if not record or not record.get("sha256"):
        return False
    try:
        return source_sha256(source) != record["sha256"]
    except OSError:
        return True
