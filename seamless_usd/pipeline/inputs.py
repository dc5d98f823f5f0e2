"""Turn what the user named (files, folders, glob patterns) into the stages and documents to process."""
from __future__ import annotations

import glob
from collections.abc import Sequence
from pathlib import Path

from seamless_usd.errors import UsageError

__all__ = ["expand_inputs", "SCENE_SUFFIXES", "is_own_output"]

SCENE_SUFFIXES = frozenset({".usd", ".usda", ".usdc", ".usdz", ".mtlx"})
_GLOB_CHARS = frozenset("*?[")
OUTPUT_MARK = ".seamless."  # scene.seamless.usda, doc.seamless.mtlx: written by this tool
OUTPUT_DIR_NAME = "tileable"


def is_own_output(path: Path) -> bool:
    """A layer or document this tool wrote (or its backups): not an input when walking folders."""
    return OUTPUT_MARK in path.name or path.suffix == ".bak" or OUTPUT_DIR_NAME in path.parent.parts


def _walk(folder: Path) -> list[Path]:
    found = [
        p for p in folder.rglob("*")
        if p.is_file() and p.suffix.lower() in SCENE_SUFFIXES and not is_own_output(p.relative_to(folder))
    ]
    return sorted(found)


def expand_inputs(items: Sequence[str | Path]) -> list[Path]:
    """Files as given; folders walked recursively for USD and MaterialX files; globs expanded.

    Folder walks and globs leave out this tool's own outputs (``*.seamless.usda``,
    ``*.seamless.mtlx``, ``.bak`` copies, ``tileable/`` folders) so a re-run does not process
    them. A file named explicitly is always taken. Duplicates are removed, order is kept.
    A glob that matches nothing is a usage error; a missing file is left for the caller to
    report (it is unreadable input, not a usage error).

    >>> expand_inputs([]) == []
    True
    """
    out: list[Path] = []
    for item in items:
        text = str(item)
        path = Path(text)
        if path.is_dir():
            out.extend(_walk(path))
        elif _GLOB_CHARS & set(text) and not path.exists():
            matches = [
                Path(m) for m in sorted(glob.glob(text, recursive=True))
                if Path(m).is_file() and Path(m).suffix.lower() in SCENE_SUFFIXES and not is_own_output(Path(m))
            ]
            if not matches:
                raise UsageError(f"the pattern {text!r} matches no USD or MaterialX file")
            out.extend(matches)
        else:
            out.append(path)
    seen: set[Path] = set()
    unique = []
    for p in out:
        key = p.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique
