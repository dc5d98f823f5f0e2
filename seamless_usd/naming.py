"""Names of the files a run writes, derived from the source asset and the stack."""
from __future__ import annotations

import hashlib
import re
from pathlib import Path

__all__ = ["tile_filename", "stack_tile_filenames", "source_digest", "slug"]

_UNSAFE = re.compile(r"[^A-Za-z0-9._-]+")
_UNSAFE_IN_STEM = re.compile(r"[^\w.-]+")  # a source's own name keeps its letters in any script
#: What :func:`tile_filename` adds after a stem: the stack id, the source's digest, ``.tile``.
_OWN_TILE = re.compile(r"\.[A-Za-z0-9_.-]+-[0-9a-f]{10}(\.[0-9a-f]{8})?(\.[rgba]{1,4}[0-9]*)?\.tile$")


def is_tile_name(path: str) -> bool:
    """Whether ``path`` is named as :func:`tile_filename` names a tile.

    >>> is_tile_name("tileable/albedo.Looks_M-abcdef0123.0badf00d.tile.png"), is_tile_name("albedo.png")
    (True, False)
    """
    return bool(_OWN_TILE.search(Path(path.replace("\\", "/")).stem))


def slug(text: str, limit: int = 48) -> str:
    """A file-name-safe form of ``text`` (prim paths, material names)."""
    cleaned = _UNSAFE.sub("_", text.strip("<>/")).strip("._") or "x"
    return cleaned[:limit]


def tile_filename(source_asset: str, stack_id: str, extension: str, source_digest: str = "") -> str:
    """``brick_albedo.png`` of stack ``Looks_Brick-3f2a`` -> ``brick_albedo.Looks_Brick-3f2a.tile.png``; with a
    digest of the source file's bytes, its first eight characters too (``brick_albedo.Looks_Brick-3f2a.5d41402a
    .tile.png``).

    The stack id keeps two materials that share one source file from overwriting each other's tiles; the source's
    digest keeps two stages whose materials share a path and a file name (``albedo.png`` of two folders) from
    overwriting each other's tiles in one output folder, while a library copied elsewhere names its tiles alike.
    The stem keeps letters and digits in any script; spaces and other characters unsafe in a file name become ``_``.

    >>> tile_filename("tex/albedo.png", "Looks_M-1a", ".png", "5d41402abc4b2a76")
    'albedo.Looks_M-1a.5d41402a.tile.png'
    >>> tile_filename("tex/älbedo ü.png", "Looks_M-1a", ".png"), tile_filename("木材.png", "M-1a", ".png")
    ('älbedo_ü.Looks_M-1a.tile.png', '木材.M-1a.tile.png')
    >>> tile_filename("tileable/albedo.Looks_M-0123456789.5d41402a.tile.png", "Looks_M-abcdef0123", ".png")
    'albedo.Looks_M-abcdef0123.tile.png'
    """
    stem = _OWN_TILE.sub("", Path(source_asset.replace("\\", "/")).stem)  # a tile of a tile: the first stem
    digest = f".{slug(source_digest[:8])}" if source_digest else ""
    safe = _UNSAFE_IN_STEM.sub("_", stem).strip("._")[:48] or "x"
    return f"{safe}.{slug(stack_id, 64)}{digest}.tile{extension}"


def stack_tile_filenames(maps, stack_id: str, extensions: list[str], made_with: str = "") -> list[str]:
    """:func:`tile_filename` of each map of a stack (``TextureMap``), with a digest of its source's bytes and of the
    whole stack's (every map's tile is cut through one field made from all of them: two stacks of one material path
    that share a map but not the others make two tiles of it, neither overwriting the other, and a stack one of
    whose maps changed names every tile anew, so a layer written before keeps the tiles it names); maps of one file
    (two texture nodes reading its colour and its alpha) also name the channels they read, so that neither tile
    overwrites the other; two nodes reading the same channels of one file share one tile (the same texels cut
    through the same field; the run knows each map by its file and channels). The digest covers how each map is
    read (colour space, scale and bias) and ``made_with`` (the job's settings that change a tile, "" for the
    defaults): a stack made again with other settings, or one file read as sRGB by one stage and raw by another,
    names other tiles, so the tiles another layer names are never replaced by ones it did not judge.

    >>> from types import SimpleNamespace as M
    >>> stack_tile_filenames([M(asset="rgba.png", resolved="", channels_used="rgb"),
    ...                       M(asset="rgba.png", resolved="", channels_used="a")], "M-0123456789", [".png"] * 2)
    ['rgba.M-0123456789.rgb.tile.png', 'rgba.M-0123456789.a.tile.png']
    """
    digests = [source_digest(m.resolved) for m in maps]
    whole = "|".join(sorted(f"{d}:{m.channels_used}{_read_as(m)}" for d, m in zip(digests, maps)))
    whole += f"|{made_with}" if made_with else ""
    names = [tile_filename(m.asset, stack_id, ext, hashlib.sha256(f"{d}|{whole}".encode()).hexdigest() if d else "")
             for m, d, ext in zip(maps, digests, extensions)]
    out = []
    for m, name in zip(maps, names):
        if len({o.channels_used for o, n in zip(maps, names) if n == name}) > 1:
            name = name.replace(".tile", f".{m.channels_used}.tile", 1) if ".tile" in name else name
        out.append(name)
    return out


def _read_as(m) -> str:
    """How a map's file is read, where it is not as most are (sRGB or raw by the file, scale 1, bias 0): "" else."""
    space = getattr(getattr(m, "color_space", None), "value", "")
    scale, bias = tuple(getattr(m, "scale", (1.0,) * 4)), tuple(getattr(m, "bias", (0.0,) * 4))
    plain = scale == (1.0,) * 4 and bias == (0.0,) * 4 and not getattr(m, "normal_y_flip", False)
    return f":{space}" + ("" if plain else f":{scale}:{bias}:{getattr(m, 'normal_y_flip', False)}")


def source_digest(path: str) -> str:
    """The digest of a source file's bytes that its tiles' names carry (:func:`tile_filename`); "" when it cannot
    be read as a file (a map inside a package)."""
    from seamless_usd.fileio import source_sha256

    try:
        return source_sha256(path)
    except OSError:
        return ""
