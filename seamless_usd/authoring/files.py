"""File helpers for authoring: atomic layer/document writes, backups, relative asset paths."""
from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Callable

from filelock import FileLock
from pxr import Sdf, Tf

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write
from seamless_usd.findings import asset_ref

__all__ = ["BACKUP_SUFFIX", "write_atomically", "check_layer", "layer_lock", "backup_once", "linked_target",
           "relative_asset_path"]

BACKUP_SUFFIX = ".bak"


def write_atomically(dest: Path, write: Callable[[Path], object],
                     check: Callable[[Path], None] | None = None) -> Path:
    """Call ``write(tmp)`` on a temporary file beside ``dest``, then rename it over ``dest``.

    The temporary name keeps ``dest``'s extension (USD picks the file format from it). A reader
    sees the old file or the new one, never a half-written one. ``write`` returning ``False``
    (as ``Sdf.Layer.Export`` does on failure) or raising a USD error is an
    :class:`~seamless_usd.errors.InputError` naming ``dest``; ``check(tmp)``, when given, runs
    on the complete temporary file and raises :class:`~seamless_usd.errors.InputError` with the
    reason to refuse it (e.g. it does not read back); the message is prefixed with ``dest``.
    """
    dest = Path(dest)
    try:
        dest.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"{asset_ref(dest)}: cannot create its folder ({exc.strerror}); "
                         "check permissions or choose another output") from exc

    def checked(tmp: Path) -> None:
        try:
            ok = write(tmp)
        except Tf.ErrorException as exc:
            raise InputError(f"{asset_ref(dest)}: cannot write it ({_first_line(exc)}); "
                             "check free disk space and permissions") from None
        if ok is False:
            raise InputError(f"{asset_ref(dest)}: cannot write it; check free disk space and permissions")
        if check is not None:
            try:
                check(tmp)
            except InputError as exc:
                raise InputError(f"{asset_ref(dest)}: {exc}; check free disk space and permissions") from None

    return atomic_write(dest, checked)


def _first_line(exc: BaseException) -> str:
    """The useful part of a Tf error on one line (``Error occurred writing file: ...``)."""
    text = str(exc)
    quoted = [part.split(" : ", 1)[-1].strip(" '") for part in text.splitlines() if " : " in part]
    return quoted[0] if quoted else " ".join(text.split()) or type(exc).__name__


def check_layer(tmp: Path) -> None:
    """Refuse a written layer that does not open again as a USD layer (short write, disk full)."""
    try:
        layer = Sdf.Layer.OpenAsAnonymous(str(tmp))
    except Tf.ErrorException as exc:
        raise InputError(f"the written layer does not read back ({_first_line(exc)})") from None
    if not layer:
        raise InputError("the written layer does not read back")


@contextlib.contextmanager
def layer_lock(path: Path) -> Iterator[None]:
    """Hold the lock of the layer or document at ``path`` while reading, backing up and writing it.

    Every write is atomic on its own; the lock keeps two runs on one library from interleaving
    the steps around it (a ``.bak`` copied from a layer the other run has just edited). The lock
    file lives in the temporary folder, keyed by the resolved path, so scene folders stay clean;
    it serialises the writers of one machine.
    """
    key = hashlib.sha256(str(Path(path).resolve()).encode("utf-8")).hexdigest()[:32]
    uid = getattr(os, "getuid", lambda: 0)()
    folder = Path(tempfile.gettempdir()) / f"seamless-usd-locks-{uid}"
    folder.mkdir(mode=0o700, exist_ok=True)
    with FileLock(str(folder / f"{key}.lock")):
        yield


def backup_once(path: Path) -> Path:
    """A backup of ``path`` as it is now, before it is edited in place: ``path.bak`` (made by the first run that edits
    it, then kept: the original), or, where ``path.bak`` holds something else (the file changed since that run, or a
    ``.bak`` of the user's own, or one a stopped run left), ``path.1.bak``, ``path.2.bak`` ...: the first that is free
    or already holds this content. No file is edited in place without a copy of what the edit replaces, and no
    ``.bak`` there is ever replaced."""
    path = Path(path)
    data = path.read_bytes()
    for n in range(0, 1000):
        bak = path.with_name(path.name + (f".{n}" if n else "") + BACKUP_SUFFIX)
        if not bak.exists():
            break
        try:
            if bak.is_file() and bak.stat().st_size == len(data) and bak.read_bytes() == data:
                return bak
        except OSError:
            continue
    else:
        raise InputError(f"{asset_ref(path)}: a thousand backups of it are there already; move them away")
    size = len(data)

    def same_size(tmp: Path) -> None:
        if tmp.stat().st_size != size:
            raise InputError("the backup copy is incomplete")

    write_atomically(bak, lambda tmp: tmp.write_bytes(data), check=same_size)
    return bak


def linked_target(path: Path) -> tuple[Path, str | None]:
    """The file an in-place edit of ``path`` writes, and what to say where that is not ``path`` itself: a layer or
    document reached through a link is edited in the file it links to, so the link (and every stage that shares that
    file through it) stays as it was; replaced by a file of its own, the link was cut without a word."""
    path = Path(path)
    if not path.is_symlink():  # a link among its folders is no matter: the file is replaced in the folder it is in
        return path, None
    real = Path(os.path.realpath(path))
    return real, (f"a link to {asset_ref(real)}: edited in place there, so every stage that links or uses that file "
                  "shows the tiles now (leave out --in-place for a layer of this stage's own)")


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


#: What an output this tool wrote earlier holds, set by hand, is left as it is (:func:`set_by_hand`).
SET_BY_HAND = ("its file is set{where} to {asset}, neither its source nor a tile of this tool's (set by hand?): left "
               "as it is; remove that value from the {kind} to have it replaced")


def set_by_hand(current: str, scanned: str) -> bool:
    """Whether the file ``current`` a texture reads in an output an earlier run wrote (a new layer or document the
    run edits again) was set there by hand: a file that is neither the one the scan read (``scanned``: the stage or
    document without that output) nor a tile of this tool's. A file that is not there is simply replaced."""
    from seamless_usd.imaging.tag import read_tag
    from seamless_usd.naming import is_tile_name

    if not current or not os.path.isfile(current):
        return False
    try:
        if scanned and os.path.samefile(current, scanned):
            return False
    except OSError:
        pass
    return not (is_tile_name(current) or read_tag(current))
