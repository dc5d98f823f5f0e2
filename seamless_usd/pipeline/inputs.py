"""Turn what the user named (files, folders, glob patterns) into the stages and documents to process."""
from __future__ import annotations

import os

import glob
from collections.abc import Sequence
from pathlib import Path

from seamless_usd.findings import GLOB_CHARS

__all__ = ["expand_inputs", "SCENE_SUFFIXES", "is_hidden", "is_own_output"]

SCENE_SUFFIXES = frozenset({".usd", ".usda", ".usdc", ".usdz", ".mtlx"})
OUTPUT_MARK = ".seamless."  # scene.seamless.usda, doc.seamless.mtlx: written by this tool
OUTPUT_DIR_NAME = "tileable"


def is_own_output(path: Path) -> bool:
    """A layer, document or tile this tool wrote (or a backup): not an input when walking folders (a picture in a
    ``tileable`` folder below is a tile, judged with the stage that uses it)."""
    return _own_layer(path) or OUTPUT_DIR_NAME in path.parent.parts


def is_hidden(relative: Path) -> bool:
    """A file or folder whose name starts with a dot, below the folder walked: left out of folder walks (a write's
    temporary file, this tool's or USD's, left by a killed run; version control's and editors' own files)."""
    return any(part.startswith(".") for part in relative.parts)


def _own_layer(path: Path) -> bool:
    """A layer or document this tool wrote, or a backup (no stage is ever written into a ``tileable`` folder: a
    stage there is the user's)."""
    return OUTPUT_MARK in path.name or path.suffix == ".bak"


def _walk(folder: Path, outputs: bool = False) -> list[Path]:
    """The stages and documents in ``folder`` and below that no other one there composes: a sublayer, a payload, a
    reference or a ``.mtlx`` document a stage uses is processed through that stage (on its own it has no geometry
    bound, so a UV atlas would read as a material meant to tile), not again as a scene of its own.

    ``outputs``: the scenes as this tool left them: a stage's new layer (``scene.seamless.usda``, which composes
    the stage) and a document's new document (``doc.seamless.mtlx``) instead of what they were made from."""
    found = sorted(
        p for p in folder.rglob("*")
        if p.is_file() and p.suffix.lower() in SCENE_SUFFIXES and (outputs or not _own_layer(p))  # .bak: no scene
        and not is_hidden(p.relative_to(folder))
    )
    if outputs:  # a document's new document is a whole document: the one it was made from is left out
        remade = {p.with_name(p.name.replace(OUTPUT_MARK, ".", 1)) for p in found if p.suffix.lower() == ".mtlx"
                  and OUTPUT_MARK in p.name}
        found = [p for p in found if p not in remade]
    used = _composed_by(found)
    roots = [p for p in found if p.resolve() not in used]
    return roots or found  # layers that only compose one another (a cycle): every one is a scene


def _composed_by(files: Sequence[Path]) -> set[Path]:
    """The files (resolved) that the USD layers among ``files`` compose directly: sublayers, references, payloads.
    A layer among ``files`` that does not open is composed by none: it is a scene of its own, reported as unreadable
    (the stage that composes it only warns that its composition failed), as it is when it is alone in the folder."""
    layers = [f for f in files if f.suffix.lower() != ".mtlx"]
    if not layers:
        return set()
    from pxr import Sdf  # only for a folder that holds stages

    opened, broken = [], set()
    for f in layers:  # each layer parsed once, here: whether it opens, and what it composes
        try:
            layer = Sdf.Layer.FindOrOpen(str(f))
        except Exception:  # noqa: BLE001 - Tf.ErrorException: reported when it is processed
            layer = None
        if layer is None:
            broken.add(f.resolve())
        else:
            opened.append((f, layer))
    used: set[Path] = set()
    for f, layer in opened:
        for dep in layer.GetCompositionAssetDependencies():
            target = Path(dep) if Path(dep).is_absolute() else f.parent / dep
            if target.exists() and target.resolve() not in broken:
                used.add(target.resolve())
    return used


def expand_inputs(items: Sequence[str | Path], outputs: bool = False, require_scenes: bool = False) -> list[Path]:
    """Files as given; folders walked recursively for USD and MaterialX files; globs expanded.

    Folder walks and globs leave out this tool's own outputs (``*.seamless.usda``,
    ``*.seamless.mtlx``, ``.bak`` copies, ``tileable/`` folders) so a re-run does not process
    them; ``outputs`` (``check``): a folder walk takes each scene as this tool left it instead (its new layer or
    document where there is one; see :func:`_walk`). A glob, like a folder walk, leaves out the layers its matched
    stages compose. A file named explicitly is always taken. Duplicates are removed, order is kept.
    A glob that matches nothing, and with ``require_scenes`` (``process``, ``scan``) a folder that holds no stage or
    document, is given back as it is, as a missing file is: each caller reports them as inputs that cannot be read
    (:func:`seamless_usd.findings.not_found_words`; exit code 2, a batch pointed at the wrong folder must not read as a
    run that went well), in its ``--json`` report as well.

    >>> expand_inputs([]) == []
    True
    """
    out: list[Path] = []
    for item in items:
        text = str(item)
        path = Path(text)
        if path.is_dir():
            found = _walk(path, outputs)
            out.extend(found or ([path] if require_scenes else []))
        elif GLOB_CHARS & set(text) and not path.exists():
            matches = [
                Path(m) for m in sorted(glob.glob(text, recursive=True))
                if Path(m).is_file() and Path(m).suffix.lower() in SCENE_SUFFIXES and not _own_layer(Path(m))
            ]
            if not matches:
                out.append(path)
                continue
            used = _composed_by(matches)  # as a folder walk: a layer a matched stage composes goes through it
            out.extend([m for m in matches if m.resolve() not in used] or matches)
        else:
            out.append(path)
    seen: set[Path] = set()
    unique = []
    for p in out:
        key = Path(os.path.realpath(p))  # a link that loops is kept as itself, and reported when it is opened
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique
