"""File helpers for authoring: atomic layer/document writes, backups, relative asset paths."""
from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Callable

from seamless_usd.fileio import atomic_write
from seamless_usd.findings import asset_ref

__all__ = ["BACKUP_SUFFIX", "write_atomically", "backup_once", "relative_asset_path"]

BACKUP_SUFFIX = ".bak"


def write_atomically(dest: Path, write: Callable[[Path], object]) -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``dest``, then rename it over ``dest``.

    The temporary name keeps ``dest``'s extension (USD picks the file format from it). A reader
    sees the old file or the new one, never a half-written one. ``write`` returning ``False``
    (as ``Sdf.Layer.Export`` does on failure) is an error.
    """
    dest = Path(dest)
    dest.parent.mkdir(parents=True, exist_ok=True)

    def checked(tmp: Path) -> None:
        if write(tmp) is False:
            raise OSError(f"could not write {asset_ref(dest)}")

    return atomic_write(dest, checked)


def backup_once(path: Path) -> Path:
    """Copy ``path`` to ``path.bak`` unless that backup exists (it then holds the original)."""
    path = Path(path)
    bak = path.with_name(path.name + BACKUP_SUFFIX)
    if not bak.exists():
        write_atomically(bak, lambda tmp: shutil.copyfile(path, tmp))
    return bak


def relative_asset_path(target: Path, anchor_dir: Path) -> str:
    """``target`` as an asset path relative to ``anchor_dir`` (``./x.png``, ``../t/x.png``).

    Forward slashes on every platform; absolute when no relative path exists (another drive).
    """
    target, anchor_dir = Path(target).resolve(), Path(anchor_dir).resolve()
    try:
        rel = os.path.relpath(target, anchor_dir)
    except ValueError:
        return target.as_posix()
    rel = rel.replace(os.sep, "/")
    return rel if rel.startswith("../") else f"./{rel}"
