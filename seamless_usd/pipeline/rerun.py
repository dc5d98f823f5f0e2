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

import numpy as np
from safetensors import SafetensorError
from safetensors.numpy import load_file, save

from seamless_usd.errors import InputError
from seamless_usd.fileio import atomic_write_bytes, atomic_write_text, file_sha256
from seamless_usd.report.model import Previews
from seamless_usd.version import __version__

__all__ = ["JUDGED", "judged_key", "record_paths", "save_judged", "load_judged", "previews_to_arrays", "previews_from_arrays"]

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


def previews_to_arrays(p: Previews) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """The pictures as named arrays, and what is not a picture as JSON."""
    arrays = {f"source_view/{k}": v for k, v in p.source_view.items()}
    arrays |= {f"tile_view/{k}": v for k, v in p.tile_view.items()}
    arrays |= {name: v for name in ("lit_source", "lit_tile", "thumbnail", "discriminator", "asset_source", "asset_tile")
               if (v := getattr(p, name)) is not None}
    arrays |= {f"level/{i}": pic for i, (_, pic) in enumerate(p.levels)}
    return ({k: np.ascontiguousarray(v) for k, v in arrays.items()},
            {"lit_note": p.lit_note, "view": p.view, "levels": [caption for caption, _ in p.levels],
             "source_view": list(p.source_view), "tile_view": list(p.tile_view)})


def previews_from_arrays(arrays: dict[str, np.ndarray], info: dict[str, Any]) -> Previews:
    return Previews(
        source_view={k: arrays[f"source_view/{k}"] for k in info["source_view"]},
        tile_view={k: arrays[f"tile_view/{k}"] for k in info["tile_view"]},
        lit_source=arrays.get("lit_source"), lit_tile=arrays.get("lit_tile"), lit_note=info["lit_note"],
        view=info["view"], thumbnail=arrays.get("thumbnail"), discriminator=arrays.get("discriminator"),
        levels=[(caption, arrays[f"level/{i}"]) for i, caption in enumerate(info["levels"])],
        asset_source=arrays.get("asset_source"), asset_tile=arrays.get("asset_tile"),
    )


def save_judged(entry_root: Path, out_dir: Path, stack_id: str, record: dict[str, Any], previews: Previews) -> None:
    """Keep ``record`` (JSON-able; ``record["outputs"]`` maps each map to ``{"path": ...}``, whose digests are
    taken here) and the previews. A record that cannot be written is simply not kept."""
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
        return


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


def load_judged(entry_root: Path, out_dir: Path, stack_id: str) -> tuple[dict[str, Any], Previews] | None:
    """The record and previews of a previous run, when every output it names is still on disk unchanged (and
    the record is this version's and whole); else None."""
    paths = record_paths(entry_root, out_dir, stack_id)
    try:
        record = json.loads(paths[0].read_text(encoding="utf-8"))
        pictures = paths[0].parent / str(record.get("pictures_file", paths[1].name))
        if record.get("version") != __version__ or file_sha256(pictures) != record["pictures"]:
            return None
        for out in record["outputs"].values():
            if file_sha256(Path(out["path"])) != out["sha256"]:
                return None
        previews = previews_from_arrays(load_file(str(pictures)), record["previews"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError, SafetensorError):  # AttributeError: JSON of
        return None  # another shape (a list where the record is a mapping): judged again
    return record, previews
