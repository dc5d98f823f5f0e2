"""Test helper: wait for a file-system condition without busy polling.

On Linux the wait sleeps in ``select`` on an inotify descriptor that watches the given folders (and
every folder created under them) and re-checks the condition on each event: a kill point reacts within
a millisecond of the file operation it waits for and costs no CPU meanwhile. Elsewhere it falls back to
checking every 20 ms.
"""
from __future__ import annotations

import ctypes
import os
import select
import struct
import sys
import time
from collections.abc import Callable, Iterable
from pathlib import Path

_IN_MODIFY, _IN_CLOSE_WRITE, _IN_MOVED_TO, _IN_CREATE, _IN_DELETE = 0x2, 0x8, 0x80, 0x100, 0x200
_IN_ISDIR = 0x40000000
_MASK = _IN_MODIFY | _IN_CLOSE_WRITE | _IN_MOVED_TO | _IN_CREATE | _IN_DELETE
_HEADER = struct.Struct("iIII")  # wd, mask, cookie, len


class _Inotify:
    def __init__(self) -> None:
        self.libc = ctypes.CDLL(None, use_errno=True)
        self.fd = self.libc.inotify_init1(os.O_NONBLOCK | os.O_CLOEXEC)
        if self.fd < 0:
            raise OSError(ctypes.get_errno(), "inotify_init1")
        self.watched: dict[int, Path] = {}

    def watch_tree(self, root: Path) -> None:
        """Watch ``root`` and the folders under it (those that exist now)."""
        for folder, subdirs, _ in os.walk(root):
            wd = self.libc.inotify_add_watch(self.fd, os.fsencode(folder), _MASK)
            if wd >= 0:
                self.watched[wd] = Path(folder)

    def wait(self, timeout: float) -> None:
        """Sleep until an event or ``timeout``; watch the folders the events created."""
        ready, _, _ = select.select([self.fd], [], [], max(0.0, timeout))
        if not ready:
            return
        try:
            data = os.read(self.fd, 1 << 16)
        except BlockingIOError:
            return
        offset = 0
        while offset < len(data):
            wd, mask, _, length = _HEADER.unpack_from(data, offset)
            name = data[offset + _HEADER.size: offset + _HEADER.size + length].rstrip(b"\0")
            offset += _HEADER.size + length
            if mask & _IN_ISDIR and mask & (_IN_CREATE | _IN_MOVED_TO) and wd in self.watched:
                self.watch_tree(self.watched[wd] / os.fsdecode(name))

    def close(self) -> None:
        os.close(self.fd)


def wait_until(ready: Callable[[], bool], roots: Iterable[Path], timeout: float,
               stop: Callable[[], bool] | None = None, step: float = 0.1) -> bool:
    """Return True as soon as ``ready()`` holds; False when ``stop()`` holds first. Raises
    ``TimeoutError`` after ``timeout`` seconds. ``roots`` (existing folders) are watched with the folders
    created under them; ``ready`` is re-checked on every change there and at least every ``step`` seconds
    (``stop``, say a process that ended, needs no file event)."""
    deadline = time.monotonic() + timeout
    watcher = _Inotify() if sys.platform.startswith("linux") else None
    try:
        if watcher is not None:
            for root in roots:
                watcher.watch_tree(Path(root))
        while True:
            if ready():
                return True
            if stop is not None and stop():
                return ready()
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"the condition did not hold within {timeout:.0f} s")
            if watcher is not None:
                watcher.wait(min(step, left))
            else:
                time.sleep(min(0.02, left))
    finally:
        if watcher is not None:
            watcher.close()
