"""``check``: the verdict on the textures of a library, before or after processing, with no training.

Each texture stack of a stage or MaterialX document that is meant to tile (intent ``tiling`` or
``already-tileable``), and each picture named alone, gets the verdict of :mod:`seamless_usd.verdict`:

* a map this tool wrote is judged against the source recorded with it (:mod:`.recorded`: ``SeamlessTileAPI`` on
  its USD texture prim, the ``seamless_*`` attributes of its MaterialX node, or, for a tile named alone, its own
  file, with the other tiles of its stack), brought to the tile's texel grid with the recorded UV scale;
* anything else has no separate source and is judged against itself: its own interior lines are the
  reference, and a seam is a line unlike them (no fidelity figure applies). Its files are read and judged by
  :func:`seamless_usd.verdict.alone.judge_alone`, exactly as the scan's triage reads and judges them, so a
  texture ``check`` passes is one the scan calls ``already-tileable`` when it is meant to tile.
"""
from __future__ import annotations

import functools
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from seamless_usd.errors import InputError, SeamlessUsdError
from seamless_usd.discover.images import IMAGE_SUFFIXES
from seamless_usd.findings import asset_ref
from seamless_usd.pipeline.checkinputs import check_inputs, missing_reason, real_path
from seamless_usd.pipeline.inputs import SCENE_SUFFIXES
from seamless_usd.pipeline.recorded import keystone_of, recorded_source, stack_sources
from seamless_usd.report.contact import SheetCard, thumbnail

__all__ = ["IMAGE_SUFFIXES", "CheckItem", "CheckReport", "check_paths"]

_JUDGED_INTENTS = ("tiling", "already-tileable")


@dataclass
class CheckItem:
    """One texture or stack checked: what it is, its verdict, or why it could not be judged."""

    name: str  # the material's prim path, or the picture's path
    source: str  # the stage, document or picture it came from
    maps: list[str]  # asset paths as authored (or the picture's path)
    verdict: dict = field(default_factory=dict)  # Verdict.as_dict(); empty when unreadable
    error: str = ""
    note: str = ""  # what to know of how it was judged: a recorded source gone or changed (judged against itself
    #   instead), tiles of its stack not beside it, a normal map that does not read as one
    seconds: float = 0.0
    thumbnail: tuple = field(default=(), repr=False)  # (data URI, (w, h), texel scale, how shown) of the first map, 2 x 2

    def words(self) -> str:
        """Where its seams run and what is outside its tolerance, or why it could not be judged."""
        from seamless_usd.verdict import Verdict

        if self.error:
            return self.error
        v = Verdict.from_dict(self.verdict)
        said = "; ".join(v.reasons()) or ("seamless and faithful" if v.reference == "source" else
                                          "seamless (judged against itself)")
        if self.name == self.source and len(self.maps) > 1:  # a tile judged with its stack's other tiles
            said += f" (judged with the {len(self.maps) - 1} other tile(s) of its stack beside it)"
        return f"{said} ({self.note})" if self.note else said

    def card(self) -> SheetCard:
        """The item as a card of the contact sheet (:mod:`seamless_usd.report.contact`): its seams brought to
        the thumbnail's pixels."""
        status = "error" if self.error else "passed" if self.passed else "not-passed"
        words = self.words()
        title = self.name if self.source == self.name else f"{self.name} in {self.source}"  # a stack: its stage too
        if not self.thumbnail:
            return SheetCard(title, status, words)
        uri, size, scale, shown = self.thumbnail
        seams = [{**s, "position": s["position"] * scale, "start": s["start"] * scale, "end": s["end"] * scale}
                 for s in self.verdict.get("seams", [])]
        words = f"{words} (the picture is {shown})" if shown else words  # an HDR or a faint picture
        return SheetCard(title, status, words, uri, size, seams)

    @property
    def passed(self) -> bool:
        return bool(self.verdict.get("passed")) and not self.error

    def to_dict(self) -> dict:
        return {"name": self.name, "source": self.source, "maps": list(self.maps), "passed": self.passed,
                "verdict": self.verdict, "error": self.error, "note": self.note, "seconds": round(self.seconds, 3)}


@dataclass
class CheckReport:
    items: list[CheckItem] = field(default_factory=list)
    unreadable: list[str] = field(default_factory=list)  # inputs that could not be opened, with why
    not_judged: list[str] = field(default_factory=list)  # pictures in folders of scenes that no scene uses
    interrupted: bool = False  # stopped by Ctrl-C or SIGTERM: ``items`` are those judged by then

    @property
    def exit_code(self) -> int:
        """0 everything tiles; 1 something does not (or a texture could not be read); 2 unreadable input; 130
        stopped by Ctrl-C or SIGTERM (what was judged by then is reported)."""
        if self.interrupted:
            return 130
        if self.unreadable:
            return 2
        return 0 if all(i.passed for i in self.items) else 1

    def to_dict(self) -> dict:
        return {"items": [i.to_dict() for i in self.items], "unreadable": list(self.unreadable),
                "not_judged": list(self.not_judged),
                **self.counts(), "interrupted": self.interrupted, "exit_code": self.exit_code}

    def counts(self) -> dict[str, int]:
        """Items passed, judged and not passed, and not judged for an error (a texture that could not be read, a
        picture too small): the counts the text summary, the JSON and the contact sheet all give."""
        errors = sum(bool(i.error) for i in self.items)
        passed = sum(i.passed for i in self.items)
        return {"passed": passed, "not_passed": len(self.items) - passed - errors, "errors": errors}


def _alone(item: CheckItem, files: list) -> None:
    """``item`` judged against itself from ``files`` (:func:`seamless_usd.verdict.alone.judge_alone`, the reading
    the scan's triage uses too), with its thumbnail."""
    from seamless_usd.verdict.alone import judge_alone, left_unread, normal_doubts

    verdict, reading = judge_alone(files)
    item.verdict = verdict.as_dict()
    doubts = normal_doubts(files)  # a normal map that does not read as one: said, as process says it
    headers = [_header(m) for m in files]  # each file's header, read once for the two questions below
    if item.name == item.source:  # a picture: what of its file the verdict did not read (alpha, layers, parts)
        doubts += [f for f in (left_unread(m, h) for m, h in zip(files, headers)) if f]
    if doubts:
        item.note = "; ".join(([item.note] if item.note else []) + doubts)
    # a float file's colour is linear light: shown through the sRGB transfer, as a viewer shows it
    linear = headers[0] is not None and headers[0].dtype in ("half", "float") and not files[0].is_normal \
        and len(files[0].channels) >= 3
    uri, size, scale, shown = thumbnail(reading, linear=linear)
    item.thumbnail = (uri, size, scale * reading.shape[1] / verdict.size[1], shown)  # px per full-size texel


def _header(m):
    """The header of a map judged on its own (:func:`seamless_usd.imaging.io.read_info`), None when unreadable."""
    from seamless_usd.imaging.io import read_info

    try:
        return read_info(m.path, max_pixels=None)
    except SeamlessUsdError:
        return None


def _picture_groups(pictures: list[Path]) -> list[tuple[list[Path], list[dict | None]]]:
    """The pictures as judged, each (files, their records): a tile this tool wrote first, with the other tiles of
    its stack that its file names (:mod:`seamless_usd.imaging.tag`) and that lie beside it (a stack is judged
    together, as ``process`` judged it, and once when several of its tiles are named); any other picture alone.
    Each file's record is read once."""
    from seamless_usd.imaging.tag import read_tag

    tags: dict[Path, dict | None] = {}

    def tag(q: Path) -> dict | None:
        if q not in tags:
            tags[q] = read_tag(q) if q.is_file() else None
        return tags[q]

    groups, seen = [], set()
    for p in pictures:
        stack = [p.parent / str(n) for n in (tag(p) or {}).get("stack", [])]
        files = [p] + [q for q in stack if q.name != p.name and q.is_file()]
        key = frozenset(real_path(q) for q in files)
        if key not in seen:
            seen.add(key)
            groups.append((files, [tag(q) for q in files]))
    return groups


def _judge_picture(group: tuple[list[Path], list[dict | None]], named: frozenset = frozenset()) -> list[CheckItem]:
    """Pictures judged (``group``: files and their records, :func:`_picture_groups`): tiles this tool wrote whose
    files record their sources (a tile, then the other tiles of its stack beside it) together against those
    sources, as ``process`` judged them; a picture that records nothing, or a tile whose source is gone or has
    changed since, against itself, saying why. Of a stack's tiles, those named or found (``named``, as
    paths as :func:`.checkinputs.real_path` gives them) have items, the first file always."""
    files, records = group
    made, notes = zip(*(recorded_source(f, r) if r else (None, "") for f, r in zip(files, records)))
    wanted = [k == 0 or real_path(f) in named for k, f in enumerate(files)]
    together = [k for k, m in enumerate(made) if m]
    items = []
    if together and any(wanted[k] for k in together):
        t0 = time.perf_counter()
        first = files[together[0]]
        item = CheckItem(str(first), str(first), [str(files[k]) for k in together])
        recorded = {str(n) for n in records[together[0]].get("stack", [])}
        without = sorted(recorded - {files[k].name for k in together})
        if without:
            item.note = f"judged without the other tile(s) of its stack: {', '.join(without)}"
        tiles, sources, prov = [made[k][0] for k in together], [made[k][1] for k in together], made[together[0]][2]
        _judged(item, lambda: _against_source(item, tiles, sources, prov))
        item.seconds = time.perf_counter() - t0
        items.append(item)
    return items + [_picture_alone(files[k], records[k], notes[k]) for k in range(len(files))
                    if not made[k] and wanted[k]]


def _picture_alone(path: Path, record: dict | None, note: str) -> CheckItem:
    """``path`` judged against itself (a tile whose record says how its source was read: its channels, and a
    normal map as one); ``note``: why a tile is not judged against its source."""
    from seamless_usd.naming import is_tile_name
    from seamless_usd.textures import NORMAL_ROLES
    from seamless_usd.verdict.alone import FileMap

    t0 = time.perf_counter()
    if record is None and is_tile_name(path.name):  # saved again by a program that drops what the file records
        note = ("named as a tile seamless-usd writes, but it records no source (saved again by another program?): "
                "judged against itself, where the verdict is least sure; check the stage or document that uses it, "
                "whose record names the source")
    item = CheckItem(str(path), str(path), [str(path)], note=note)
    read = (record or {}).get("map", {})
    roles = read.get("roles", [])
    channels = "".join(c for c in "rgba" if any(c in str(used) for _, used in roles)) or "rgb"
    normal = any(role in NORMAL_ROLES for role, _ in roles)
    scale, bias = (tuple(read.get("scale", ())), tuple(read.get("bias", ()))) if normal else ((), ())
    _judged(item, lambda: _alone(item, [FileMap(str(path), channels, normal, path.name, scale, bias)]))
    item.seconds = time.perf_counter() - t0
    return item


def _judged(item: CheckItem, judge) -> None:
    """``judge()`` fills ``item``; an input that cannot be judged becomes its error, naming the file."""
    try:
        judge()
    except (SeamlessUsdError, ValueError, OSError, RuntimeError) as exc:
        where = asset_ref(item.name)
        item.error = str(exc) if where in str(exc) else f"{where}: cannot be judged: {exc}"


def _against_source(item: CheckItem, tile_maps: list, src_maps: list, prov) -> None:
    """``item`` judged as ``process`` judged it: the tiles ``tile_maps`` against their sources ``src_maps`` made as
    the provenance ``prov`` records (straightened, levelled, evened) and brought to the tiles' texel grid."""
    from seamless_usd.discover.images import read_image_info
    from seamless_usd.imaging import WorkingResolution, load_stack_pixels
    from seamless_usd.pipeline.madefrom import made_values, on_tile_grid
    from seamless_usd.verdict import judge

    normals = [m.is_normal for m in tile_maps]
    info = read_image_info(tile_maps[0].resolved)
    uv = prov.uv_scale
    grid = (round(info.height * uv[1]), round(info.width * uv[0]))
    # the source on the tile's grid, resampled as process resampled it (its working-resolution policy)
    made = load_stack_pixels(src_maps, WorkingResolution(max_size=max(grid)))
    sources = list(made.values)
    # the tiles read as process read them: with their sources' encodings (a float file's fitted range)
    tiles = list(load_stack_pixels(tile_maps, encodings=made.encodings).values)
    # made from the source straightened, levelled or evened as recorded: judged against it made so
    h, w = sources[0].shape[:2]
    sources = made_values(sources, normals, prov.straightened, bool(prov.levelled), bool(prov.evened),
                          turn_vectors=not prov.uv_turn, rectified=keystone_of(prov))
    uv = (uv[0] * sources[0].shape[1] / w, uv[1] * sources[0].shape[0] / h)
    sources = on_tile_grid(sources, normals, tiles[0].shape[:2], uv)
    item.verdict = judge(tiles, sources, normals, [m.asset for m in tile_maps],
                         codes=[e.network_code for e in made.encodings]).as_dict()
    item.thumbnail = thumbnail(tiles[0])


def _judge_stack(stage_path: Path, stage, stack) -> CheckItem:
    from seamless_usd.textures import describe_selection
    from seamless_usd.verdict.alone import file_map

    name = stack.material + (f" in {describe_selection(stack.selection)}" if stack.selection else "")
    item = CheckItem(name, str(stage_path), [m.asset for m in stack.maps])
    t0 = time.perf_counter()
    packed = [m for m in stack.maps if m.in_package]
    try:
        if packed:
            raise InputError(f"{asset_ref(packed[0].asset)} is inside a .usdz package: its pixels are not judged "
                             "there (unpack the package, or check the files it was made from)")
        gone = [m for m in stack.maps if m.tile_missing]
        if gone:  # its source is there, not the tile: nothing of this stack's tiles to judge
            raise InputError(f"its tile {asset_ref(gone[0].asset)} is not there (its recorded source is): process "
                             "again to make it")
        recorded, item.note = stack_sources(stage, stack)
        if recorded is None:  # no separate source: judged against itself, as the scan's triage judges it
            _alone(item, [file_map(m) for m in stack.maps])
        else:
            _against_source(item, list(stack.maps), *recorded)
    except (SeamlessUsdError, ValueError, OSError, RuntimeError) as exc:
        item.error = str(exc)
    item.seconds = time.perf_counter() - t0
    return item


def _unread_item(scene: Path, material: str, skipped: list, maps: list[str]) -> CheckItem:
    from seamless_usd.discover.select import unread_files

    files = unread_files(skipped)
    return CheckItem(material, str(scene), maps + [f.where.split(" ")[-1].strip("@") for f in skipped],
                     error=f"not judged: a texture of it cannot be read: {files}; fix or restore it and check again")


def _judged_pictures(pictures: list[tuple], jobs: int, named: frozenset) -> Iterator[list[CheckItem]]:
    """The items of each group of pictures (:func:`_picture_groups`; ``named``: the pictures named or found, as
    paths as :func:`.checkinputs.real_path` gives them), in order; ``jobs`` > 1 judges them in that many worker processes (a picture is judged in
    numpy alone, one core each)."""
    judge = functools.partial(_judge_picture, named=named)
    if jobs <= 1 or len(pictures) < 2 * jobs:
        yield from map(judge, pictures)
        return
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    methods = multiprocessing.get_all_start_methods()
    context = multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")
    with ProcessPoolExecutor(jobs, mp_context=context) as pool:
        yield from pool.map(judge, pictures, chunksize=max(1, min(8, len(pictures) // (4 * jobs))))


def check_paths(paths: Sequence[str | Path], progress: Callable[[str, int, int], None] | None = None,
                jobs: int = 1) -> CheckReport:
    """The verdict on every stack meant to tile in ``paths`` (stages, documents, folders) and every picture.
    ``progress(name, done, total)`` is called before each stage or document is judged and as each picture's
    verdict comes in. ``jobs``: worker processes judging the pictures (1: in this process). Stopped by Ctrl-C
    (or SIGTERM, which the command line raises as one), it returns what was judged by then, ``interrupted``."""
    report = CheckReport()
    try:
        _check_into(report, paths, progress, jobs)
    except KeyboardInterrupt:
        report.interrupted = True
    return report


def _check_into(report: CheckReport, paths: Sequence[str | Path], progress: Callable[[str, int, int], None] | None,
                jobs: int) -> None:
    scenes, pictures, loose, report.unreadable = check_inputs(paths)
    used: set[Path] = set()  # the files the scenes use: judged with their stacks, not listed as not judged
    if scenes:  # USD and MaterialX are imported only for scenes: a picture is judged without them
        from seamless_usd.discover import scan_paths
        from seamless_usd.discover.scan import open_stage
        from seamless_usd.discover.select import set_aside_reasons, unread_findings
    total = len(scenes) + len(pictures)
    done = 0

    def emit(name: str) -> None:
        if progress is not None:
            progress(name, done, total)

    for scene in scenes:
        emit(str(scene))
        done += 1
        if scene.suffix.lower() not in SCENE_SUFFIXES:
            report.unreadable.append(f"{asset_ref(scene)}: not a USD stage, MaterialX document or picture")
            continue
        try:
            result = scan_paths([scene])
        except InputError as exc:
            report.unreadable.append(str(exc))
            continue
        used.update(real_path(m.resolved) for st in result.stacks for m in st.maps if m.resolved)
        used.update(real_path(m.recorded_source.resolved) for st in result.stacks for m in st.maps  # a tile's source
                    if m.recorded_source and m.recorded_source.resolved)
        judged, seen = [], set()
        for s in result.stacks:  # a stack the same as one judged is judged once (its twin may be one not judged)
            # a material with a UDIM set or a picture too small is left alone by process: not judged here either
            if s.intent in _JUDGED_INTENTS and s.content_key not in seen and not set_aside_reasons(result, s):
                seen.add(s.content_key)
                judged.append(s)
        unread = unread_findings(result)
        stage = open_stage(scene) if judged and scene.suffix.lower() != ".mtlx" else None  # once per stage
        for stack in judged:
            if stack.material in unread:  # judged on the maps that are left, it would pass a broken material
                report.items.append(_unread_item(scene, stack.material, unread.pop(stack.material),
                                                 [m.asset for m in stack.maps]))
            else:
                report.items.append(_judge_stack(scene, stage, stack))
        for material, skipped in unread.items():  # no map of it could be read: it has no stack
            report.items.append(_unread_item(scene, material, skipped, []))
    known = {real_path(p) for p in pictures}
    report.not_judged = [str(p) for p in loose if real_path(p) not in used and real_path(p) not in known]
    found = []
    for picture in pictures:
        if picture.is_file():
            found.append(picture)
        else:  # found in a folder (one named and not there is said before): a picture that cannot be read, exit 1
            done += 1
            report.items.append(CheckItem(str(picture), str(picture), [str(picture)],
                                          error=f"{asset_ref(picture)}: {missing_reason(picture)}"))
    groups = _picture_groups(found)  # a stack's tiles are judged together
    for (files, _), items in zip(groups, _judged_pictures(groups, jobs, frozenset(map(real_path, found)))):
        emit(items[0].name)
        done += len(files)
        report.items += items
    if progress is not None:
        progress("", done, total)
