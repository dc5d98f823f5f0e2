"""Schemas shipped with seamless-usd: JSON Schemas for machine output and the USD schema plugin."""
from __future__ import annotations

import json
from functools import lru_cache
from pathlib import Path

__all__ = ["SCHEMA_DIR", "json_schema", "usd_plugin_dir"]

SCHEMA_DIR = Path(__file__).resolve().parent


@lru_cache(maxsize=None)
def json_schema(name: str) -> dict:
    """Load the JSON Schema ``<name>.schema.json`` shipped in this package."""
    return json.loads((SCHEMA_DIR / f"{name}.schema.json").read_text(encoding="utf-8"))


def usd_plugin_dir() -> Path:
    """Folder holding the codeless USD schema plugin (``plugInfo.json``)."""
    return SCHEMA_DIR / "usd"
