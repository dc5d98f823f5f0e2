"""A stack's judged result kept beside its cache entry, so that an unchanged rerun is a no-op.

A cache hit still wrote the tiles, read them back and judged them again: a second or more a small stack,
tens of seconds at 2K. When the tiles a previous run wrote into the same folder for the same stack are still
on disk, byte for byte (SHA-256 of each file), that run's figures, verdict and pictures are what judging them
again would give: they are kept here, one record per output folder and stack (its pictures once, by their content, for every folder
the same tiles went to), and taken back instead. A file
missing or changed (edited by hand, half written) is written and judged again.

Records are JSON (figures, verdict) and safetensors (the report's pictures); nothing is unpickled.
"""
from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from safetensors import SafetensorError
from safetensors.numpy import save

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write_bytes, atomic_write_text, file_sha256
from seamless_usd.report.model import Previews
from seamless_usd.report.stored import previews_to_arrays, stored_previews
from seamless_usd.version import __version__

__all__ = ["JUDGED", "judged_key", "record_paths", "read_record", "written_state", "save_judged", "load_judged",
           "changed_words", "verdict_elsewhere"]

#: Folder of an entry that holds the judged records.
JUDGED = "judged"
#: A record's pictures, named by their content: the same stack written into several folders keeps them once.
PICTURES_SUFFIX = ".pictures.safetensors"


def judged_key(stack) -> str:
    """What a judged record is kept under, beside the folder it was written into: the stack's id and its content
    (its files). Two stages whose materials share a path and whose files hold the same bytes share a cache entry;
    each keeps its own record, whose outputs name its own files."""
    return f"{stack.id}|{stack.content_key}"


def record_paths(entry_root: Path, out_dir: Path, stack_id: str) -> tuple[Path, Path]:
    """The record's JSON and pictures for the stack ``stack_id`` (:func:`judged_key`) written into ``out_dir``."""
    name = hashlib.sha256(f"{Path(out_dir).resolve()}|{stack_id}".encode()).hexdigest()[:32]
    folder = Path(entry_root) / JUDGED
    return folder / f"{name}.json", folder / f"{name}.safetensors"


def save_judged(entry_root: Path, out_dir: Path, stack_id: str, record: dict[str, Any], previews: Previews
                ) -> Previews | None:
    """Keep ``record`` (JSON-able; ``record["outputs"]`` maps each map to ``{"path": ...}``, whose digests are
    taken here) and the previews; returns the previews as kept (read from their file when the report draws them),
    None when the record cannot be written (it is then simply not kept)."""
    paths = record_paths(entry_root, out_dir, stack_id)
    arrays, info = previews_to_arrays(previews)
    try:
        outputs = {k: {**v, "sha256": file_sha256(Path(v["path"]))} for k, v in record["outputs"].items()}
        paths[0].parent.mkdir(parents=True, exist_ok=True)
        blob = save(arrays)
        digest = hashlib.sha256(blob).hexdigest()
        pictures = paths[0].parent / f"{digest[:32]}{PICTURES_SUFFIX}"  # by content: kept once for every folder
        if not pictures.is_file() or file_sha256(pictures) != digest:
            atomic_write_bytes(pictures, blob)
        body = {**record, "outputs": outputs, "previews": info, "version": __version__, "pictures": digest,
                "pictures_file": pictures.name}
        atomic_write_text(paths[0], json.dumps(body, default=str))
    except (OSError, InputError, SafetensorError):  # a read-only cache, say: the record is not kept
        return None
    return stored_previews(str(pictures), info)


def read_record(entry_root: Path, out_dir: Path, stack_id: str) -> dict[str, Any] | None:
    """The record a previous run kept of this stack's tiles written into ``out_dir``, None where none is kept (or it
    does not read as one)."""
    try:
        record = json.loads(record_paths(entry_root, out_dir, stack_id)[0].read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return record if isinstance(record, dict) else None


def written_state(record: dict[str, Any]) -> tuple[bool, list[Path]]:
    """Whether every tile the record names is on disk as it was written, and the ones that are there but no longer
    what was written (painted over, saved again by another program): each tile's file read once."""
    same, changed = True, []
    for out in record["outputs"].values():
        path = Path(out["path"])
        try:
            digest = file_sha256(path)
        except OSError:  # gone (or unreadable): made again, as on a first run
            same = False
            continue
        if digest != out["sha256"]:
            same = False
            changed.append(path)
    return same, changed


def changed_words(changed: list) -> str:
    """What a stack says whose tiles a TD changed since they were written (:func:`written_state`)."""
    one = len(changed) == 1
    names = ", ".join(f"@{p}@" for p in changed)
    return (f"{names} {'was' if one else 'were'} changed since this tool wrote {'it' if one else 'them'} (painted "
            "over, or saved again by another program): not replaced; move or delete "
            f"{'it' if one else 'them'} to have this stack's tiles made again")


def verdict_elsewhere(entry_root: Path) -> dict[str, Any] | None:
    """The verdict this version gave the tiles of this cache entry when they were written into any folder (a copy of
    the library, another output folder): an entry holds one stack's tiles, made of the same source files with the
    same settings, so the verdict they will get again wherever they are written; None when no record is kept."""
    for path in sorted((Path(entry_root) / JUDGED).glob("*.json")):
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
            if record.get("version") == __version__:
                return dict(record["verdict"])
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            continue
    return None


def load_judged(entry_root: Path, out_dir: Path, stack_id: str) -> tuple[tuple[dict[str, Any], Previews] | None,
                                                                         list[Path]]:
    """The record and previews of a previous run, when every output it names is still on disk unchanged (and
    the record is this version's and whole), else None; and the outputs that are there but changed since they were
    written (:func:`written_state`; none where no record is kept)."""
    paths = record_paths(entry_root, out_dir, stack_id)
    record = read_record(entry_root, out_dir, stack_id)
    try:
        if record is None:
            return None, []
        same, changed = written_state(record)
        pictures = paths[0].parent / str(record.get("pictures_file", paths[1].name))
        if not same or record.get("version") != __version__ or file_sha256(pictures) != record["pictures"]:
            return None, changed
        previews = stored_previews(str(pictures), record["previews"])  # read when the report draws them (its
        #                                                                     digest, just checked, says they are whole)
    except (OSError, ValueError, KeyError, TypeError, AttributeError, SafetensorError):  # AttributeError: JSON of
        return None, []  # another shape (a list where the record is a mapping): judged again
    return (record, previews), []
