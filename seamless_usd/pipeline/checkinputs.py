"""What ``check`` is given to judge: the stages, documents and pictures its paths name or hold (:mod:`.check`)."""
from __future__ import annotations

import errno
import glob
import os
from collections.abc import Sequence
from pathlib import Path

from seamless_usd.discover.images import IMAGE_SUFFIXES
from seamless_usd.findings import GLOB_CHARS, asset_ref, not_found_words
from seamless_usd.pipeline.inputs import expand_inputs, is_hidden, is_own_output

__all__ = ["check_inputs", "folder_pictures", "missing_reason", "real_path"]


def folder_pictures(folder: Path) -> list[Path]:
    """The pictures in ``folder`` and below (this tool's outputs left out); a link to a picture that is gone is
    kept, and reported as missing when judged."""
    return sorted(q for q in folder.rglob("*") if (q.is_file() or q.is_symlink()) and q.suffix.lower() in IMAGE_SUFFIXES
                  and not is_own_output(q.relative_to(folder)) and not is_hidden(q.relative_to(folder)))


def real_path(path) -> Path:
    """The file ``path`` names, links followed; a link that loops is its own (it is reported, not followed)."""
    return Path(os.path.realpath(path))


def missing_reason(picture: Path) -> str:
    """Why a picture named or found is not a file to judge."""
    if picture.exists() and not picture.is_dir():
        return "not a regular file (a named pipe, a device or a socket): only files are judged"
    if not picture.is_symlink():
        return "no such file"
    try:
        os.stat(picture)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "a link that leads back to itself (a loop of links); fix or remove it"
    return "no such file (a link to a file that is gone)"


def check_inputs(paths: Sequence[str | Path]) -> tuple[list[Path], list[Path], list[Path], list[str]]:
    """(scenes, pictures, loose, problems): the scenes and the pictures named or found in folders that hold no
    scene; ``loose``: the pictures of folders that hold scenes (a texture there is judged with its stack, the
    others are listed as not judged: a library's textures are judged by how its materials use them); and why an
    input gives nothing to judge (no such path, a folder with nothing in it to judge)."""
    scenes, pictures, loose, problems = [], [], [], []
    for item in paths:
        p = Path(item)
        if p.is_dir():
            found = expand_inputs([p], outputs=True)  # each scene as processed: what it now uses
            in_folder = folder_pictures(p)
            if found:
                scenes += found
                loose += in_folder
            elif in_folder:
                pictures += in_folder
            else:
                problems.append(f"{asset_ref(p)}: no USD stage, MaterialX document or picture found in this folder")
        elif GLOB_CHARS & set(str(p)) and not p.exists():  # a pattern (quoted, or from a script): pictures and scenes
            matched = [Path(m) for m in sorted(glob.glob(str(p), recursive=True))]
            found_pictures = [m for m in matched if m.suffix.lower() in IMAGE_SUFFIXES and m.is_file()]
            found_scenes = [m for m in expand_inputs([p]) if m.is_file()]
            if not found_pictures and not found_scenes:
                problems.append(f"{asset_ref(p)}: {not_found_words(p, pictures=True)}")
            pictures += found_pictures
            scenes += found_scenes
        elif p.suffix.lower() in IMAGE_SUFFIXES:
            if p.is_file():
                pictures.append(p)
            else:  # named and not there (a link to nothing, a loop of links): a path that does not exist, exit 2
                problems.append(f"{asset_ref(p)}: {missing_reason(p)}")
        elif not p.exists():
            problems.append(f"{asset_ref(p)}: no such file or folder")
        else:
            scenes += expand_inputs([p])
    return scenes, pictures, loose, problems
