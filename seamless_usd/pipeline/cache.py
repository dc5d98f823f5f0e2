"""Content-addressed cache of trained stacks: checkpoints while training, tiles when done.

An entry is keyed by a hash of the stack's working pixels, the maps' channels and roles, the
synthesis config, the seed, the code version and the tiles' revision (:data:`TILE_REVISION`), so the
same stack found in several files (or in a re-run) is trained once. A finished entry holds the sampled
tiles and a manifest with the SHA-256 of every file; entries are verified before use and a corrupt one is
discarded and redone.
Writers hold a file lock per entry, so two processes never train or write the same entry at once.
"""
from __future__ import annotations

import contextlib

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

from seamless_usd.version import __version__
from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write, atomic_write_text, file_sha256, source_sha256
from seamless_usd.findings import asset_ref

__all__ = ["StackCache", "CacheEntry", "JobIndex", "stack_key", "job_fingerprint", "default_cache_dir"]

MANIFEST = "manifest.json"
#: What a stack's result reads from its entry's metadata (:func:`.outcome.outcome_from_record`): an entry without
#: them is made again.
_META_KEYS = ("crop_size", "uv_scale", "scale", "q", "candidates", "model_hash", "device", "precision")
TILES = "tiles.safetensors"
CACHE_FORMAT = 1  # bump when the entry layout changes
#: Bump whenever the same inputs and settings make a different tile (a candidate added or refused, a cut
#: changed): entries made before are then not reused. 2: the window cut is offered only where the texture
#: continues itself (``synthesis.lattice.window.continues_itself``). 3: a stack with no lattice and no window
#: weighs quilts (``synthesis.lattice.quilt``), and the candidates' score counts the structure figure. 4: the
#: cuts are tried in turn (lattice, window, the source mended, ``synthesis.lattice.mend``, then a quilt) until
#: one passes.
TILE_REVISION = 4


def default_cache_dir() -> Path:
    import platformdirs

    return Path(platformdirs.user_cache_dir("seamless-usd"))


def stack_key(pixels: Iterable[tuple[str, np.ndarray, str]], config: Mapping[str, Any], seed: int) -> str:
    """SHA-256 over (name, pixels, descriptor) per map, the config, the seed and the code version.

    ``descriptor`` says how the pixels are meant (channels, roles, colour space, normal or not):
    the same pixels used differently are a different stack.
    """
    h = hashlib.sha256()
    h.update(f"seamless-usd {__version__} cache {CACHE_FORMAT} tiles {TILE_REVISION}\n".encode())
    for name, array, descriptor in pixels:
        arr = np.ascontiguousarray(array, dtype=np.float32)
        h.update(f"{name}|{descriptor}|{arr.shape}\n".encode())
        h.update(arr.tobytes())
    h.update(json.dumps(config, sort_keys=True, default=str).encode())
    h.update(f"seed={seed}".encode())
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

    @contextlib.contextmanager
    def guard(self):
        """The entry's lock held, yielding True; in a cache folder this process cannot write (a read-only shared
        cache) no lock can be taken, and it yields False: a finished result can still be read, nothing written."""
        lock = self.lock()
        try:
            lock.acquire()
        except OSError:
            yield False
            return
        try:
            yield True
        finally:
            lock.release()

    def load(self) -> tuple[dict[str, np.ndarray], dict[str, Any]] | None:
        """The finished tiles and metadata, or None when absent or failing verification."""
        manifest_path = self.root / MANIFEST
        if not manifest_path.is_file():
            return None
        try:
            manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
            files, meta = manifest["files"], manifest["meta"]
            if not isinstance(files, dict) or TILES not in files or not isinstance(meta, dict):
                raise ValueError("the manifest does not name its tiles and metadata")
            missing = [k for k in _META_KEYS if k not in meta]
            if missing:
                raise ValueError(f"the manifest's metadata lacks {', '.join(missing)}")
            for name, digest in files.items():
                if file_sha256(self.root / name) != digest:
                    raise ValueError(f"{name} does not match its recorded hash")
            tiles = load_file(str(self.root / TILES))
        except (OSError, ValueError, KeyError, TypeError, SafetensorError) as exc:  # TypeError: JSON of another shape
            self.discard_result(reason=str(exc))
            return None
        return tiles, meta

    def store(self, tiles: Mapping[str, np.ndarray], meta: Mapping[str, Any]) -> None:
        """Write tiles then the manifest (the manifest, written last and atomically, marks completion)."""
        arrays = {k: np.ascontiguousarray(v, dtype=np.float32) for k, v in tiles.items()}
        try:
            self.root.mkdir(parents=True, exist_ok=True)
            atomic_write(self.root / TILES, lambda tmp: save_file(arrays, str(tmp)))
            manifest = {"format": CACHE_FORMAT, "key": self.key, "files": {TILES: file_sha256(self.root / TILES)},
                        "meta": dict(meta)}
            atomic_write_text(self.root / MANIFEST, json.dumps(manifest, indent=1, default=str))
        except (OSError, SafetensorError) as exc:
            raise InputError(
                f"the cache folder {asset_ref(self.root.parent.parent)} cannot be written ({exc}); "
                "free some space or choose another with --cache-dir"
            ) from None

    def discard_result(self, reason: str = "") -> None:
        for name in (MANIFEST, TILES):
            with contextlib.suppress(OSError):  # a read-only cache keeps it: it is not read as a result either
                (self.root / name).unlink(missing_ok=True)

    def remove(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)


class StackCache:
    """A folder of :class:`CacheEntry` values, two-level fan-out by key prefix."""

    def __init__(self, root: Path | None = None):
        self.root = Path(root) if root is not None else default_cache_dir()

    def entry(self, key: str) -> CacheEntry:
        return CacheEntry(key, self.root / key[:2] / key)


JOBS = "jobs"  # the client's index of finished jobs, beside the entries


def job_fingerprint(stack, settings) -> str:
    """Identity of a stack job the client can compute without decoding pixels.

    SHA-256 over the code version, the job settings (not the cache folder), and per map its use
    (channels, colour space, scale/bias, roles) and the SHA-256 of the file's bytes. Same
    fingerprint, same inputs to the cache key computed by the worker from the decoded pixels.
    """
    import dataclasses

    h = hashlib.sha256()
    h.update(f"seamless-usd {__version__} job {CACHE_FORMAT} tiles {TILE_REVISION}\n".encode())
    fields = {k: v for k, v in dataclasses.asdict(settings).items() if k != "cache_dir"}
    h.update(json.dumps(fields, sort_keys=True, default=str).encode())
    for m in sorted(stack.maps, key=lambda m: (m.resolved, m.channels_used)):
        roles = sorted(r.role for r in m.roles)
        h.update(json.dumps([m.channels_used, m.color_space.value, list(m.scale), list(m.bias), roles,
                             m.is_normal, m.normal_y_flip]).encode())
        h.update(source_sha256(Path(m.resolved)).encode())
    return h.hexdigest()


class JobIndex:
    """Which jobs finished, so a warm run finds them before starting any executor.

    One small JSON file per job fingerprint (``<cache>/jobs/ab/<fingerprint>.json``) naming the
    model hash and the key of its cache entry; written atomically by the client after a job returns. A hit
    counts only while that entry is still in the cache (a record without a key, from an older run: while an
    entry with its model hash is, verified once per run).
    """

    def __init__(self, root: Path | None = None):
        self.cache_root = Path(root) if root is not None else default_cache_dir()
        self.root = self.cache_root / JOBS
        self._live: set[str] | None = None

    def _path(self, fingerprint: str) -> Path:
        return self.root / fingerprint[:2] / f"{fingerprint}.json"

    def _live_models(self) -> set[str]:
        if self._live is None:
            self._live = set()
            for manifest in self.cache_root.glob(f"??/*/{MANIFEST}"):
                try:
                    self._live.add(str(json.loads(manifest.read_text(encoding="utf-8"))["meta"]["model_hash"]))
                except (OSError, ValueError, KeyError, TypeError):
                    continue
        return self._live

    def _record(self, fingerprint: str) -> dict | None:
        try:
            record = json.loads(self._path(fingerprint).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return record if isinstance(record, dict) else None

    def _entry_of(self, record: dict | None) -> Path | None:
        key = str((record or {}).get("key", ""))
        if len(key) < 3 or not all(c in "0123456789abcdef" for c in key):
            return None
        folder = self.cache_root / key[:2] / key
        return folder if (folder / MANIFEST).is_file() else None

    def entry(self, fingerprint: str) -> Path | None:
        """The folder of the cache entry this job finished with, while it is still there; None when the job did not
        finish, or its record names no entry (an older run's)."""
        return self._entry_of(self._record(fingerprint))

    def finished(self, fingerprint: str) -> bool:
        """True when this job finished before and its cache entry is still there."""
        record = self._record(fingerprint)
        if record is None:
            return False
        if record.get("key"):
            return self._entry_of(record) is not None
        return str(record.get("model_hash", "")) in self._live_models()

    def record(self, fingerprint: str, model_hash: str, key: str = "") -> None:
        """Note a finished job and its entry's ``key``; a cache that cannot be written only costs the shortcut."""
        path = self._path(fingerprint)
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_text(path, json.dumps({"model_hash": model_hash, "key": key}))
        except (OSError, InputError):  # a read-only cache: said as InputError by the atomic writer
            return
        if self._live is not None:
            self._live.add(model_hash)
