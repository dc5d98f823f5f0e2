"""Content-addressed cache of trained stacks: checkpoints while training, tiles when done.

An entry is keyed by a hash of the stack's working pixels, the maps' channels and roles, the
synthesis config, the seed and the code version, so the same stack found in several files (or
in a re-run) is trained once. A finished entry holds the sampled tiles and a manifest with the
SHA-256 of every file; entries are verified before use and a corrupt one is discarded and redone.
Writers hold a file lock per entry, so two processes never train or write the same entry at once.
"""
from __future__ import annotations

import hashlib
import json
import shutil
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from filelock import FileLock
from safetensors import SafetensorError
from safetensors.numpy import load_file, save_file

from seamless_usd import __version__
from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write, atomic_write_text
from seamless_usd.findings import asset_ref

__all__ = ["StackCache", "CacheEntry", "stack_key", "default_cache_dir"]

MANIFEST = "manifest.json"
TILES = "tiles.safetensors"
CACHE_FORMAT = 1  # bump when the entry layout changes


def default_cache_dir() -> Path:
    import platformdirs

    return Path(platformdirs.user_cache_dir("seamless-usd"))


def stack_key(pixels: Iterable[tuple[str, np.ndarray, str]], config: Mapping[str, Any], seed: int) -> str:
    """SHA-256 over (name, pixels, descriptor) per map, the config, the seed and the code version.

    ``descriptor`` says how the pixels are meant (channels, roles, colour space, normal or not):
    the same pixels used differently are a different stack.
    """
    h = hashlib.sha256()
    h.update(f"seamless-usd {__version__} cache {CACHE_FORMAT}\n".encode())
    for name, array, descriptor in pixels:
        arr = np.ascontiguousarray(array, dtype=np.float32)
        h.update(f"{name}|{descriptor}|{arr.shape}\n".encode())
        h.update(arr.tobytes())
    h.update(json.dumps(config, sort_keys=True, default=str).encode())
    h.update(f"seed={seed}".encode())
    return h.hexdigest()


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


@dataclass(frozen=True)
class CacheEntry:
    key: str
    root: Path

    @property
    def checkpoint_dir(self) -> Path:
        return self.root / "checkpoints"

    def lock(self, timeout: float = -1) -> FileLock:
        """Exclusive lock on this entry (re-entrant within a process)."""
        try:
            self.root.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(
                f"the cache folder {asset_ref(self.root.parent.parent)} cannot be used ({exc.strerror}); "
                "choose another with --cache-dir"
            ) from None
        return FileLock(str(self.root) + ".lock", timeout=timeout)

    def load(self) -> tuple[dict[str, np.ndarray], dict[str, Any]] | None:
        """The finished tiles and metadata, or None when absent or failing verification."""
        manifest_path = self.root / MANIFEST
        if not manifest_path.is_file():
            return None
        try:
            manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
            files = manifest["files"]
            for name, digest in files.items():
                if _sha256(self.root / name) != digest:
                    raise ValueError(f"{name} does not match its recorded hash")
            tiles = load_file(str(self.root / TILES))
        except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
            self.discard_result(reason=str(exc))
            return None
        return tiles, manifest["meta"]

    def store(self, tiles: Mapping[str, np.ndarray], meta: Mapping[str, Any]) -> None:
        """Write tiles then the manifest (the manifest, written last and atomically, marks completion)."""
        arrays = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in tiles.items()}
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            atomic_write(self.root / TILES, lambda tmp: save_file(arrays, str(tmp)))
            manifest = {"format": CACHE_FORMAT, "key": self.key, "files": {TILES: _sha256(self.root / TILES)},
                        "meta": dict(meta)}
            atomic_write_text(self.root / MANIFEST, json.dumps(manifest, indent=1, default=str))
        except (OSError, SafetensorError) as exc:
            raise InputError(
                f"the cache folder {asset_ref(self.root.parent.parent)} cannot be written ({exc}); "
                "free some space or choose another with --cache-dir"
            ) from None

    def discard_result(self, reason: str = "") -> None:
        for name in (MANIFEST, TILES):
            (self.root / name).unlink(missing_ok=True)

    def remove(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


class StackCache:
    """A folder of :class:`CacheEntry` values, two-level fan-out by key prefix."""

    def __init__(self, root: Path | None = None):
        self.root = Path(root) if root is not None else default_cache_dir()

    def entry(self, key: str) -> CacheEntry:
        return CacheEntry(key, self.root / key[:2] / key)
