"""Atomic file writing and output-path confinement, shared by every step that writes files.

A reader never sees a half-written file: data go to a temporary file in the target's directory
(same file system), are flushed and fsynced, then ``os.replace`` moves them over the target in
one step. On any failure the temporary file is removed and an existing target is left intact.

Example
-------
>>> import tempfile
>>> from pathlib import Path
>>> d = Path(tempfile.mkdtemp())
>>> atomic_write_text(d / "hello.txt", "hi\\n").read_text()
'hi\\n'
"""
from __future__ import annotations

import contextlib
import glob
import hashlib
import os
import re
import socket
import tempfile
from collections.abc import Callable
from pathlib import Path

from seamless_usd.errors import InputError
from seamless_usd.findings import asset_ref

__all__ = ["atomic_write", "atomic_write_bytes", "atomic_write_text", "confine", "file_sha256", "folder_problem",
           "marked_writable", "source_sha256"]

_UMASK = os.umask(0o022)  # read once at import (os.umask can only be read by setting it)
os.umask(_UMASK)
_OWNER = re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname())[:32] or "host"  # in temporary file names


def atomic_write(path: str | os.PathLike, writer: Callable[[Path], None]) -> Path:
    """Write ``path`` atomically by calling ``writer`` on a temporary path beside it.

    Parameters
    ----------
    path
        The file to create or replace. Its directory must exist.
    writer
        Called once with the temporary path; it must create that file (it may write it by name,
        e.g. an image library choosing the format from the extension: the temporary name keeps
        the target's suffix, ``.name.<host>-<pid>.<random>.tmp.png``). Temporary files of the
        same target left by a killed process on this host are removed first.

    Returns
    -------
    Path
        ``path`` as a :class:`~pathlib.Path`, now holding the complete new content.

    Raises
    ------
    InputError
        When the directory does not exist or is not writable, or writing failed with an
        :class:`OSError` (disk full, quota, read-only file system); names the file as ``@path@``.
    Exception
        Whatever else ``writer`` raised. In every case the temporary file is removed and the old
        target, if any, is unchanged.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> d = Path(tempfile.mkdtemp())
    >>> atomic_write(d / "a.bin", lambda tmp: tmp.write_bytes(b"ok")).read_bytes()
    b'ok'
    """
    target = Path(path)
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise InputError(
            f"{asset_ref(target)}: cannot write, the folder {asset_ref(directory)} does not exist; "
            "create it or choose another output folder"
        )
    suffix = "".join(target.suffixes[-1:])  # keep ".png" so format-by-extension writers work
    _remove_stale_temps(target, suffix)
    try:
        fd, tmp_name = tempfile.mkstemp(prefix=f".{target.stem}.{_OWNER}-{os.getpid()}.", suffix=f".tmp{suffix}",
                                        dir=directory)
    except OSError as exc:
        raise InputError(
            f"{asset_ref(target)}: cannot write in {asset_ref(directory)} ({exc.strerror}); "
            "check its permissions or choose another output folder"
        ) from exc
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        writer(tmp)
        if not tmp.is_file():
            raise RuntimeError(f"the writer for {asset_ref(target)} did not create its file")
        _fsync_file(tmp)
        _keep_mode(tmp, target)
        os.replace(tmp, target)
    except OSError as exc:  # disk full, quota, read-only or vanished folder: the user can act on it
        tmp.unlink(missing_ok=True)
        reason = exc.strerror or str(exc) or type(exc).__name__
        raise InputError(
            f"{asset_ref(target)}: cannot write it ({reason}); check free disk space and permissions"
        ) from exc
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _fsync_dir(directory)
    return target


def _remove_stale_temps(target: Path, suffix: str) -> None:
    """Remove temporary files of ``target`` left by a killed writer on this host.

    Temporary names carry the host and process id of their writer (``.a.host-123.x1y2.tmp.png``);
    one whose process no longer exists is a leftover (SIGKILL, power loss) and goes, with the file USD's own
    writer makes beside a layer it saves there (the name's extension replaced by six random characters:
    ``.a.host-123.x1y2.tmp.Hv97tP``). Files of live processes, of other hosts (shared storage) or of other names
    are never touched.
    """
    pattern = re.compile(
        re.escape(f".{target.stem}.") + r"(?P<owner>[A-Za-z0-9_]+)-(?P<pid>\d+)\.[^.]+\.tmp"
        + f"(?:{re.escape(suffix)}|\\.[A-Za-z0-9]{{6}})"
    )
    try:
        siblings = list(target.parent.glob(f".{glob.escape(target.stem)}.*.tmp*"))
    except OSError:
        return
    for path in siblings:
        match = pattern.fullmatch(path.name)
        if match is None or match["owner"] != _OWNER or _alive(int(match["pid"])):
            continue
        try:
            path.unlink()
        except OSError:
            pass


def _alive(pid: int) -> bool:
    if pid == os.getpid() or os.name != "posix":  # os.kill(pid, 0) probes only on POSIX
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


def file_sha256(path: str | os.PathLike) -> str:
    """The SHA-256 of a file's bytes (hex), read a megabyte at a time."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


#: Source digests already read in this process, by the file's identity on disk (path, inode, size, modification
#: time): a run hashes each source for its job's fingerprint and again for its tiles' names.
_SOURCE_DIGESTS: dict[tuple, str] = {}


def source_sha256(path: str | os.PathLike) -> str:
    """:func:`file_sha256` of a source file (an input, read only), read once per process while it is unchanged on
    disk. Not for checking a file this tool wrote: that is read again every time (:func:`file_sha256`)."""
    st = os.stat(path)
    key = (os.path.realpath(path), st.st_ino, st.st_size, st.st_mtime_ns)
    if key not in _SOURCE_DIGESTS:
        if len(_SOURCE_DIGESTS) >= 4096:
            _SOURCE_DIGESTS.clear()
        _SOURCE_DIGESTS[key] = file_sha256(path)
    return _SOURCE_DIGESTS[key]


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (see :func:`atomic_write`).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> atomic_write_bytes(Path(tempfile.mkdtemp()) / "x.bin", b"\\x00\\x01").stat().st_size
    2
    """
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def atomic_write_text(path: str | os.PathLike, text: str, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically (see :func:`atomic_write`); newlines kept as given. A character
    the encoding cannot hold (a file name's undecodable byte, kept by Python as a lone surrogate) is written as
    ``?``: a report naming such a file is still written.

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> atomic_write_text(Path(tempfile.mkdtemp()) / "r.json", "{}").read_text()
    '{}'
    """
    data = text.encode(encoding, errors="replace")
    return atomic_write(path, lambda tmp: tmp.write_bytes(data))


def confine(path: str | os.PathLike, root: str | os.PathLike) -> Path:
    """``path`` resolved, checked to lie inside the folder ``root``.

    A relative ``path`` is taken relative to ``root``. Symbolic links and ``..`` are resolved
    before the check, so ``../../etc/passwd`` or a link pointing outside are refused.

    Parameters
    ----------
    path
        An output file name or path (e.g. built from an asset name found in a stage).
    root
        The output folder everything must stay in.

    Returns
    -------
    Path
        The absolute, resolved path inside ``root``.

    Raises
    ------
    InputError
        When the path would land outside ``root``.

    Examples
    --------
    >>> confine("maps/a.png", "/out").as_posix()
    '/out/maps/a.png'
    """
    base = Path(root).resolve()
    candidate = Path(path)
    if not candidate.is_absolute():
        candidate = base / candidate
    resolved = candidate.resolve()
    if resolved != base and base not in resolved.parents:
        raise InputError(
            f"{asset_ref(path)}: refusing to write outside the output folder {asset_ref(base)}; "
            "use a name without '..' or absolute parts"
        )
    return resolved


def _fsync_file(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _fsync_dir(directory: Path) -> None:
    """Persist the rename itself (POSIX); a no-op where directories cannot be opened."""
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _keep_mode(tmp: Path, target: Path) -> None:
    """Give the new file the old file's permissions, or the usual umask-based ones."""
    try:
        mode = target.stat().st_mode & 0o7777
    except FileNotFoundError:
        mode = 0o666 & ~_UMASK
    os.chmod(tmp, mode)


def folder_problem(path: str | os.PathLike) -> str | None:
    """Why files cannot be written in the folder ``path`` (made if it does not exist), or None when they can: a
    part of it that is a file, the deepest existing folder not writable, or the folder failing to be made (it is
    made and removed again: nothing is left behind).

    >>> folder_problem(tempfile.gettempdir()) is None
    True
    """
    p = Path(os.path.abspath(path))
    probe = p
    while not probe.exists():
        if probe.parent == probe:
            return f"{asset_ref(p)} cannot be made: no part of it exists"
        probe = probe.parent
    if not probe.is_dir():
        return f"{asset_ref(probe)} is a file, so the folder {asset_ref(p)} cannot be made there"
    if not os.access(probe, os.W_OK | os.X_OK):
        return (f"cannot write in {asset_ref(probe)}; check its permissions" if probe == p else
                f"cannot make the folder {asset_ref(p)}: {asset_ref(probe)} is not writable; check its permissions")
    made = [q for q in [p, *p.parents] if q.is_relative_to(probe) and q != probe]
    try:  # permissions are not the whole story (a read-only mount, a special file system): try, then undo
        p.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        return f"cannot make the folder {asset_ref(p)}: {exc.strerror or exc}"
    finally:
        for q in made:  # deepest first
            with contextlib.suppress(OSError):
                q.rmdir()
    return None


def marked_writable(path: str | os.PathLike) -> bool:
    """Whether the file may be edited in place: writable by this process, and marked writable at all (a file with
    no write permission is read-only on purpose, also to a super-user, who could replace it)."""
    try:
        marked = bool(os.stat(path).st_mode & 0o222)
    except OSError:
        return False
    return marked and os.access(path, os.W_OK)
