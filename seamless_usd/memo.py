"""Results kept per process by the *content* of the arrays they were computed from.

A batch measures the same pictures many times: every map's tile against its source in the verdict and
again in the report's figures, the same source for every seed, candidate and duplicated stack, and
``check`` after ``process``. Figures that depend only on their arrays (and a few settings) are kept
here, keyed by a digest of the arrays' bytes, shapes and dtypes, so a repeat costs one hash.
"""
from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from typing import Callable, Generic, Hashable, TypeVar

import numpy as np

__all__ = ["ContentMemo"]

T = TypeVar("T")


class ContentMemo(Generic[T]):
    """The last ``keep`` results of ``compute``, by the content of its array arguments (thread-safe)."""

    def __init__(self, keep: int = 64):
        self.keep = keep
        self._items: OrderedDict[bytes, T] = OrderedDict()
        self._lock = threading.Lock()

    @staticmethod
    def key(arrays: tuple[np.ndarray, ...], settings: Hashable) -> bytes:
        digest = hashlib.blake2b(digest_size=20)
        for a in arrays:
            a = np.ascontiguousarray(a)
            digest.update(repr((a.shape, a.dtype.str)).encode())
            digest.update(a.reshape(-1).view(np.uint8))
        digest.update(repr(settings).encode())
        return digest.digest()

    def get(self, arrays: tuple[np.ndarray, ...], settings: Hashable, compute: Callable[[], T]) -> T:
        """The kept result for these arrays and settings, else ``compute()`` (kept; the oldest is dropped)."""
        return self.get_keyed(self.key(arrays, settings), compute)

    def get_keyed(self, k: Hashable, compute: Callable[[], T]) -> T:
        """The kept result for a key the caller made (e.g. a file's path, size and modification time), else
        ``compute()``, kept as :meth:`get` keeps it."""
        with self._lock:
            if k in self._items:
                self._items.move_to_end(k)
                return self._items[k]
        value = compute()
        with self._lock:
            self._items[k] = value
            while len(self._items) > self.keep:
                self._items.popitem(last=False)
        return value

    def __len__(self) -> int:
        return len(self._items)

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
