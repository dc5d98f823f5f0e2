"""Authoring: write tileable maps back into USD stages and MaterialX documents.

Knows nothing about torch: it takes the files other steps wrote (:class:`MapResult`) grouped per
stack (:class:`StackResult`) and edits the scene: asset paths relative to the layer they are
written in, wrap modes set to repeat, the UV scale (W / 2c, H / 2c) composed after the existing
UV chain, and provenance recorded with the ``SeamlessTileAPI`` schema shipped in
``seamless_usd_schemas``. Importing this package registers that schema with USD, so import it
before opening any stage.
"""
from __future__ import annotations

from seamless_usd.authoring.schema import (
    Schema,
    read_provenance,
    register_schemas,
    schemas_known,
    write_provenance,
)
from seamless_usd.authoring.types import (
    AuthoringResult,
    Codes,
    MapResult,
    Provenance,
    StackResult,
    UVTurn,
    WriteMode,
    uv_scale_for,
)

register_schemas()

from seamless_usd.authoring.mtlx import author_mtlx, default_output_document, read_mtlx_provenance  # noqa: E402
from seamless_usd.authoring.usd import (  # noqa: E402
    author_usd,
    author_usd_stage,
    default_output_layer,
    uv_affine,
)
from seamless_usd.authoring.uvmath import Affine2, place2d, scale2d, transform2d  # noqa: E402

__all__ = [
    "WriteMode",
    "MapResult",
    "StackResult",
    "UVTurn",
    "Provenance",
    "AuthoringResult",
    "uv_scale_for",
    "author_usd",
    "author_usd_stage",
    "author_mtlx",
    "default_output_layer",
    "default_output_document",
    "register_schemas",
    "schemas_known",
    "read_provenance",
    "write_provenance",
    "Codes",
    "read_mtlx_provenance",
    "uv_affine",
    "Schema",
    "Affine2",
    "transform2d",
    "place2d",
    "scale2d",
]
