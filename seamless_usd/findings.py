"""Findings: warnings, skipped items and errors collected while working, printed at the edge."""
from __future__ import annotations

from dataclasses import asdict, dataclass
from enum import Enum
from pathlib import Path

__all__ = ["Severity", "Finding", "prim_ref", "asset_ref", "not_found_words"]


class Severity(str, Enum):
    WARNING = "warning"  # work went on; the user should look (e.g. roughness tagged sRGB)
    SKIPPED = "skipped"  # an item was left out on purpose, with the reason (e.g. UDIM, missing file)
    ERROR = "error"  # an item failed; the rest of the run went on


@dataclass(frozen=True)
class Finding:
    severity: Severity
    code: str  # stable machine-readable kind, e.g. "missing-file", "udim", "colorspace-mismatch"
    where: str  # USD notation: "<prim/path>" or "@asset/path@" (or both, space separated)
    message: str  # one line: what is wrong and what to do
    material: str = ""  # "<material path>" the finding belongs to, when it belongs to one
    source: str = ""  # the stage or document of a run's inputs it was found in (a material path recurs across files)

    def __str__(self) -> str:
        return f"{self.severity.value}: {self.where}: {self.message}"

    def to_dict(self) -> dict:
        d = asdict(self)
        d["severity"] = self.severity.value
        for name in ("material", "source"):
            if not d[name]:
                del d[name]
        return d


def prim_ref(path: object) -> str:
    """``<path>``: how USD tools name a prim or property in messages."""
    return f"<{path}>"


def asset_ref(path: object) -> str:
    """``@path@``: how USD tools name an asset in messages."""
    return f"@{path}@"


GLOB_CHARS = frozenset("*?[")


def not_found_words(path: object, pictures: bool = False) -> str:
    """Why an input named on the command line gives nothing to read: a folder with no stage or document in it, a
    pattern that matches nothing, or a path that is not there (``pictures``: ``check``, which takes them too)."""
    things = "USD stage, MaterialX document or picture" if pictures else "USD stage or MaterialX document"
    p = Path(str(path))
    if p.is_dir():
        return f"no {things} found in this folder"
    if GLOB_CHARS & set(str(path)) and not p.exists():
        return f"the pattern matches no {things}; check the pattern"
    return "no such file; check the path"
