"""A MaterialX document's text as the user wrote it: its comments read with it and written back."""
from __future__ import annotations

import re
from pathlib import Path

import MaterialX as mx

__all__ = ["read_options", "stated_version", "with_leading_comments"]


def read_options() -> mx.XmlReadOptions:
    """A document read to be written back: its comments (and blank lines between elements) are kept."""
    options = mx.XmlReadOptions()
    options.readComments = True
    options.readNewlines = True
    return options


def with_leading_comments(text: str, src: Path | None) -> str:
    """``text`` (a written document) with the comments ``src`` holds before its root element (a header, a licence),
    which a MaterialX document does not keep (the ones inside it it does, read as comment elements)."""
    try:
        head = src.read_text(encoding="utf-8").split("<materialx", 1)[0] if src is not None else ""
    except (OSError, UnicodeDecodeError):
        return text
    comments = "".join(f"{c}\n" for c in re.findall(r"<!--.*?-->", head, flags=re.S))
    if not comments:
        return text
    at = text.find("?>") + 2 if text.lstrip().startswith("<?xml") else 0
    return f"{text[:at]}\n{comments}{text[at:].lstrip(chr(10))}" if at else comments + text


def stated_version(path: Path) -> str:
    """The ``version`` a MaterialX document's root element states, as written ("" when it cannot be read): the
    library upgrades an older document as it reads it."""
    try:
        head = path.read_text(encoding="utf-8", errors="replace")[:4096]
    except OSError:
        return ""
    found = re.search(r"<materialx\b[^>]*\bversion\s*=\s*[\"']([^\"']+)[\"']", head)
    return found.group(1) if found else ""
