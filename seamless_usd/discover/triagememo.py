"""The triage's pixel figures kept on disk, by the content of the files they were measured from.

Deciding whether a stack is already tileable decodes its maps and judges them (the verdict against
themselves, an atlas's islands): a few tenths of a second for a 512 px map, seconds at 4K, and the verdict's
resampling imports torch. A library processed again, unchanged, would pay that for every stack
before finding its tiles in the cache. The figures depend only on the files' bytes, the channels read and
the triage's settings, so they are kept here under a digest of exactly that (and of the code's version) and
taken back instead. A file edited in any way has another digest and is measured again.

Each figure is one small JSON file, written atomically; an unreadable one is measured again.
"""
from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write_text, file_sha256
from seamless_usd.textures import TextureMap
from seamless_usd.version import __version__

__all__ = ["TriageMemo", "TRIAGE_REVISION"]

#: Bump whenever the same files would be triaged differently (a rule or a figure changed).
TRIAGE_REVISION = 4  # 3: a normal map read as its vectors, with its scale and bias; 4: a file that does not decode named


class TriageMemo:
    """Figures by (what was measured, the maps' content, the settings); ``folder`` None keeps them in memory;
    ``keep`` False reads the figures already in ``folder`` and writes none (a dry run writes nothing)."""

    def __init__(self, folder: Path | None = None, settings: str = "", keep: bool = True):
        self.folder = None if folder is None else Path(folder)
        self.settings = settings
        self.keep = keep
        self._values: dict[str, Any] = {}
        self._digests: dict[tuple, str] = {}

    def _digest(self, path: str) -> str:
        st = os.stat(path)
        stamp = (path, st.st_size, st.st_mtime_ns)
        if stamp not in self._digests:
            self._digests[stamp] = file_sha256(path)
        return self._digests[stamp]

    def key(self, kind: str, maps: Sequence[TextureMap]) -> str | None:
        """The digest naming ``kind`` measured on ``maps``, or None when a map has no file to digest."""
        h = hashlib.sha256(f"seamless-usd {__version__} triage {TRIAGE_REVISION} {kind} {self.settings}".encode())
        for m in maps:
            if not m.resolved or m.in_package:
                return None
            try:
                decoding = f":{tuple(m.scale)}:{tuple(m.bias)}" if m.is_normal else ""  # how a normal map is read
                h.update(f"|{self._digest(m.resolved)}:{m.channels_used}:{m.is_normal}{decoding}".encode())
            except OSError:
                return None
        return h.hexdigest()

    def seen(self, kind: str, maps: Sequence[TextureMap]) -> Any:
        """The figure for ``maps`` measured or read back by this memo so far, else None (nothing is measured)."""
        key = self.key(kind, maps)
        return None if key is None else self._values.get(key)

    def get(self, kind: str, maps: Sequence[TextureMap], compute: Callable[[], Any]) -> Any:
        """The figure ``compute()`` gives for ``maps`` (JSON-able), measured at most once per content."""
        key = self.key(kind, maps)
        if key is None:
            return compute()
        if key in self._values:
            return self._values[key]
        path = None if self.folder is None else self.folder / key[:2] / f"{key}.json"
        if path is not None:
            try:
                self._values[key] = json.loads(path.read_text(encoding="utf-8"))["value"]
                return self._values[key]
            except (OSError, ValueError, KeyError, TypeError):
                pass
        value = json.loads(json.dumps(compute()))  # the same form whether measured now or read back
        self._values[key] = value
        if path is not None and self.keep:
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                atomic_write_text(path, json.dumps({"kind": kind, "value": value}))
            except (OSError, InputError):  # a read-only cache: the figure is simply measured again next time
                pass
        return value
