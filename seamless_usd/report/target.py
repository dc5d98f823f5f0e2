"""Where a report may be written: a path the user named, never over a file this tool did not write.

``--report scene.usda`` or ``--report albedo.png`` must not replace the stage or the picture with a page, and a
page or JSON file of someone else's must not be lost either. A report path that does not end in ``.html`` gets
that suffix (the JSON report of ``process`` goes beside it, ending in ``.json``), and an existing file there is
replaced only when it is one of this tool's own reports.
"""
from __future__ import annotations

from pathlib import Path

from seamless_usd.errors import InputError
from seamless_usd.findings import asset_ref

__all__ = ["report_target"]

#: What the start of a file this tool wrote holds, by suffix (read case-insensitively from its first bytes).
_OWN = {".html": ("<!doctype html", "seamless-usd"), ".htm": ("<!doctype html", "seamless-usd"),
        ".json": ('"tool_version"',)}
_HEAD = 4096


def _is_own(path: Path) -> bool:
    try:
        with open(path, "rb") as f:
            head = f.read(_HEAD).decode("utf-8", "replace").lower()
    except OSError:
        return False
    return all(mark in head for mark in _OWN.get(path.suffix.lower(), ("\0",)))


def report_target(path: str | Path, suffix: str = ".html") -> Path:
    """The file a report asked for at ``path`` is written to: ``path`` itself when it ends in ``suffix`` (``.htm``
    too for a page), ``report<suffix>`` inside it when it is a folder, else ``path`` with ``suffix``. Raises
    :class:`InputError` naming it when that is a folder, or a file that is not one of this tool's reports (a
    stage, a picture, another page), which is never replaced.

    >>> report_target("out/run").name, report_target("out/run.HTML").name, report_target("run", ".json").name
    ('run.html', 'run.HTML', 'run.json')
    """
    p = Path(path)
    if p.is_dir() or str(path).endswith(("/", "\\")):  # a folder named: the report goes inside it
        p = p / f"report{suffix}"
    kept = (suffix, ".htm") if suffix == ".html" else (suffix,)
    target = p if p.suffix.lower() in kept else p.with_suffix(suffix)
    if target.is_dir():
        raise InputError(f"{asset_ref(target)} is a folder: name a file for the report (e.g. report.html)")
    if target.exists() and not _is_own(target):
        raise InputError(f"{asset_ref(target)} exists and is not a report this tool wrote: it is not replaced; "
                         "remove it or name another report path")
    return target
