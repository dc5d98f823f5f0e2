"""Where a report may be written: a path the user named, never over a file this tool did not write.

``--report scene.usda`` or ``--report albedo.png`` must not replace the stage or the picture with a page, and a
page or JSON file of someone else's must not be lost either. A report path that does not end in ``.html`` gets
that suffix (the JSON report of ``process`` goes beside it, ending in ``.json``), and an existing file there is
replaced only when it is one of this tool's own reports, or empty.
"""
from __future__ import annotations

import json
from pathlib import Path

from seamless_usd.errors import InputError
from seamless_usd.findings import asset_ref

__all__ = ["GENERATOR", "clear_stale_pages", "is_own_report", "report_target"]

#: What every page this tool writes holds in its head (:func:`.htmlparts.page`): a page is one of its reports only
#: with it (a page of the user's that merely names the tool is not).
GENERATOR = '<meta name="generator" content="seamless-usd">'
#: The keys of a JSON report of ``process`` (:meth:`.model.Report.to_dict`).
_JSON_KEYS = frozenset({"tool_version", "exit_code", "stacks", "findings"})
_HEAD = 4096


def is_own_report(path: Path) -> bool:
    """Whether ``path`` is a page (``.html``, ``.htm``) or JSON report this tool wrote."""
    suffix = Path(path).suffix.lower()
    try:
        if suffix == ".json":
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
            return isinstance(data, dict) and _JSON_KEYS <= data.keys()
        if suffix in (".html", ".htm"):
            with open(path, "rb") as f:
                head = f.read(_HEAD).decode("utf-8", "replace").lower()
            return head.startswith("<!doctype html") and GENERATOR in head
    except (OSError, ValueError):
        return False
    return False


def _pages_folder(page: Path) -> Path:
    """The folder of a library report's pages beside its index ``page`` (:func:`.index.write_library_html`)."""
    return page.with_name(f"{page.stem}.files")


def clear_stale_pages(page: Path, keep: frozenset[str] = frozenset()) -> None:
    """Remove the pages this tool wrote in ``page``'s pages folder that are not in ``keep`` (names): an earlier
    run's pages left beside a report that no longer links them; the folder too once empty. A file of anyone
    else's there is left as it is."""
    folder = _pages_folder(page)
    if not folder.is_dir():
        return
    for f in folder.iterdir():
        if f.name not in keep and f.is_file() and is_own_report(f):
            f.unlink(missing_ok=True)
    if not keep and not any(folder.iterdir()):
        folder.rmdir()


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
    # an empty file holds nothing to lose: the shell made it (``--report out/r.html --json > out/r.json``)
    empty = target.is_file() and target.stat().st_size == 0
    if target.exists() and not empty and not is_own_report(target):
        raise InputError(f"{asset_ref(target)} exists and is not a report this tool wrote: it is not replaced; "
                         "remove it or name another report path")
    folder = _pages_folder(target)
    if suffix == ".html" and folder.exists():  # a library report's pages go there, replacing the tool's own only
        others = [f for f in sorted(folder.iterdir()) if not is_own_report(f)] if folder.is_dir() else [folder]
        if others:
            raise InputError(f"{asset_ref(others[0])} is in the way of the report's pages ({asset_ref(folder)}) and is "
                             "not a page this tool wrote: it is not replaced; move it or name another report path")
    return target
