"""``seamless-usd check FOLDER``: every picture judged, bad files named and the rest go on, a progress count,
JSON, and a contact sheet that draws where each seam runs; nothing is written beside the pictures."""
from __future__ import annotations

import hashlib
import json
import re
from pathlib import Path

import jsonschema
import numpy as np
import OpenImageIO as oiio

from seamless_usd.pipeline.check import check_paths
from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets" / "textures"


def _write(path: Path, pixels: np.ndarray, fmt=oiio.UINT8) -> Path:
    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), oiio.ImageSpec(w, h, c, fmt)), out.geterror()
    assert out.write_image(np.ascontiguousarray(pixels, dtype=np.float32)), out.geterror()
    out.close()
    return path


def _wood() -> np.ndarray:
    return oiio.ImageBuf(str(SAMPLES / "wood_tileable.jpg")).get_pixels(oiio.FLOAT)[:256, :256]


def _folder(root: Path) -> Path:
    """Good and bad pictures as a library holds them."""
    lib = root / "lib"
    lib.mkdir()
    wood = oiio.ImageBuf(str(SAMPLES / "wood_tileable.jpg")).get_pixels(oiio.FLOAT)  # tiles as a whole
    _write(lib / "tileable.png", np.roll(wood, (60, 90), (0, 1)), oiio.UINT16)
    window = np.concatenate([wood, wood], axis=1)[:300, 100:400]  # not a whole period: its wrap is a seam
    _write(lib / "window.png", window)
    rgba = np.concatenate([np.roll(wood, 33, 0), np.full(wood.shape[:2] + (1,), 0.5, np.float32)], axis=2)
    _write(lib / "with_alpha.png", rgba)
    _write(lib / "one_pixel.png", np.full((1, 1, 3), 0.5, np.float32))
    nan = np.roll(wood, 7, 1).astype(np.float32)
    nan[10, 10, 0] = np.nan
    _write(lib / "nan.exr", nan, oiio.HALF)
    (lib / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"not really a png" * 8)
    return lib


def _digests(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())}


def test_check_a_folder_with_json_and_a_contact_sheet(tmp_path, capsys):
    lib = _folder(tmp_path)
    before = _digests(lib)
    sheet = tmp_path / "out" / "sheet.html"
    code = main(["check", str(lib), "--json", "--report", str(sheet)])
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("check"))
    assert code == 1 == payload["exit_code"]
    items = {Path(i["name"]).name: i for i in payload["items"]}
    assert set(items) == {"tileable.png", "window.png", "with_alpha.png", "one_pixel.png", "nan.exr", "broken.png"}
    assert items["tileable.png"]["passed"] and items["with_alpha.png"]["passed"]  # alpha is not part of the look
    assert not items["window.png"]["passed"] and items["window.png"]["verdict"]["seams"]
    for bad, why in (("one_pixel.png", "too small to be judged"), ("nan.exr", "NaN or infinite"), ("broken.png", "broken.png")):
        assert not items[bad]["passed"] and why in items[bad]["error"], items[bad]
    assert _digests(lib) == before  # nothing written beside the pictures, nothing changed
    html = sheet.read_text(encoding="utf-8")
    cards = {re.search(r'alt="[^"]*/([^/"]+)"|<b>[^<]*/([^/<]+)</b>', c).group(1) or
             re.search(r"<b>[^<]*/([^/<]+)</b>", c).group(1): c for c in html.split('<div class="card ')[1:]}
    assert set(cards) == set(items)
    assert sum(c.startswith("s-passed") for c in cards.values()) == 2
    assert sum(c.startswith("s-error") for c in cards.values()) == 3
    # each seam drawn on all four repeats of the window; none on a picture that passed
    assert cards["window.png"].count("<line") == 4 * len(items["window.png"]["verdict"]["seams"])
    assert "<line" not in cards["tileable.png"] and "<img" not in cards["broken.png"]


def test_progress_counts_every_input_and_ends_at_the_total(tmp_path):
    lib = _folder(tmp_path)
    seen = []
    report = check_paths([lib], progress=lambda name, done, total: seen.append((name, done, total)))
    assert len(report.items) == 6
    assert seen[-1] == ("", 6, 6) and [d for _, d, _ in seen] == list(range(7))
    assert all(t == 6 for _, _, t in seen)


def test_a_check_stopped_part_way_reports_what_was_judged_by_then(tmp_path):
    """Ctrl-C or SIGTERM (which the command line raises as Ctrl-C) on a folder of pictures: the verdicts given by then
    are reported, with exit code 130 (the run printed nothing, as if nothing had been judged)."""
    lib = _folder(tmp_path)

    def stop_at_the_fourth(name, done, total):
        if done == 3:
            raise KeyboardInterrupt

    report = check_paths([lib], progress=stop_at_the_fourth)
    assert report.interrupted and report.exit_code == 130 and len(report.items) == 3
    payload = report.to_dict()
    jsonschema.validate(payload, json_schema("check"))
    assert payload["interrupted"] and payload["exit_code"] == 130
    assert not check_paths([lib]).to_dict()["interrupted"]


def test_pictures_judged_in_worker_processes_give_the_same_answers_in_order(tmp_path):
    lib = _folder(tmp_path)
    seen = []
    serial = check_paths([lib])
    parallel = check_paths([lib], progress=lambda name, done, total: seen.append((Path(name).name, done, total)),
                           jobs=2)
    assert [i.to_dict() | {"seconds": 0} for i in parallel.items] == [i.to_dict() | {"seconds": 0}
                                                                       for i in serial.items]
    assert [d for _, d, _ in seen] == list(range(len(serial.items))) + [len(serial.items)]
    assert {n for n, _, _ in seen[:-1]} == {Path(i.name).name for i in serial.items}


def test_a_stack_inside_a_usdz_package_is_named_not_misread(tmp_path):
    """A library material packaged with its texture (usd-core's packager): check names the packaged map and
    says what to do instead of reporting a missing file."""
    import shutil

    from pxr import Sdf, UsdUtils

    floor = (Path(__file__).resolve().parents[1] / "sample_assets" / "tileable" / "floor.usda").read_text()
    (tmp_path / "floor.usda").write_text(floor.replace("@../textures/", "@./"))
    for name in ("wood_tileable.jpg", "wood_tileable_roughness.jpg"):
        shutil.copy(SAMPLES / name, tmp_path / name)
    (tmp_path / "pkg").mkdir()
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(tmp_path / "floor.usda")), str(tmp_path / "pkg" / "floor.usdz"))
    report = check_paths([tmp_path / "pkg" / "floor.usdz"])
    [item] = report.items
    assert not item.passed and "inside a .usdz package" in item.error and "@./wood_tileable" in item.error
    assert report.exit_code == 1


def test_a_name_that_is_not_utf8_and_a_small_picture_are_named_and_the_rest_judged(tmp_path, capsys):
    """A file name the image library cannot take (an undecodable byte) and a picture too small to be judged on its
    own each get an error naming them; the other pictures are judged and the contact sheet is written."""
    import os
    import shutil

    lib = tmp_path / "lib"
    lib.mkdir()
    wood = oiio.ImageBuf(str(SAMPLES / "wood_tileable.jpg")).get_pixels(oiio.FLOAT)  # tiles as a whole
    _write(lib / "tileable.png", wood)
    shutil.copy(lib / "tileable.png", os.fsdecode(bytes(lib) + b"/odd\xff.png"))
    _write(lib / "icon.png", wood[:40, :40])
    _write(lib / "strip.png", np.tile(wood[:96], (1, 12, 1)))  # 96 px tall, 12 times as wide
    sheet = tmp_path / "sheet.html"
    assert main(["check", str(lib), "--json", "--report", str(sheet)]) == 1
    items = {Path(i["name"]).name: i for i in json.loads(capsys.readouterr().out)["items"]}
    assert items["tileable.png"]["passed"]
    odd = items[os.fsdecode(b"odd\xff.png")]
    assert "not valid UTF-8" in odd["error"] and "rename" in odd["error"]
    assert "40 x 40 px: too small to be judged on its own" in items["icon.png"]["error"]
    strip = items["strip.png"]["error"]  # both sides above 64 px, but a strip read at 512 px across is too thin
    assert "x 96 px: a strip thinner than 1:8 is too thin" in strip and "against its source" in strip
    assert "not valid UTF-8" in sheet.read_text(encoding="utf-8")


def test_folders_with_nothing_to_judge_and_pictures_no_stage_uses_are_named(tmp_path, capsys):
    """An empty folder or a path that does not exist is unreadable input (exit 2), not '0 of 0 passed'; in a folder
    of stages the pictures none of them uses are listed as not judged, and ``scan`` walks folders as ``process``."""
    import shutil

    (tmp_path / "empty").mkdir()
    sheet = tmp_path / "sheet.html"  # the contact sheet says what the command says
    assert main(["check", str(tmp_path / "empty"), str(tmp_path / "nowhere"), "--report", str(sheet)]) == 2
    out = capsys.readouterr().out
    assert "no USD stage, MaterialX document or picture found in this folder" in out and "no such file or folder" in out
    assert "┏" not in out and "of 0 passed" not in out  # no empty table, no count of nothing: the lines say why
    html = sheet.read_text(encoding="utf-8")
    assert "Could not be opened" in html and "nowhere" in html and "Exit code 2" in html
    lib = tmp_path / "lib"
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES.parent / name, lib / name)
    _write(lib / "loose.png", _wood())
    assert main(["check", str(lib), "--json", "--report", str(sheet)]) == 1
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("check"))
    assert [i["name"] for i in payload["items"]] == ["</World/Looks/Brick>"]
    html = sheet.read_text(encoding="utf-8")
    assert "1 texture or stack:" in html and "Not judged" in html and "loose.png" in html and "Exit code 1" in html
    not_judged = {Path(p).name for p in payload["not_judged"]}
    assert "loose.png" in not_judged and "brick_albedo.png" not in not_judged  # used by the stage: judged there
    assert main(["scan", str(lib)]) == 0 and "</World/Looks/Brick>" in capsys.readouterr().out
    # once processed, the stage as this tool left it reads the tiles: their sources are still used, not loose
    main(["process", str(lib / "brick" / "scene.usda"), "--preset", "tiny", "--seeds", "1", "--max-size", "128",
          "--cache-dir", str(tmp_path / "cache")])
    capsys.readouterr()
    main(["check", str(lib), "--json"])
    not_judged = {Path(p).name for p in json.loads(capsys.readouterr().out)["not_judged"]}
    assert "loose.png" in not_judged and not not_judged & {"brick_albedo.png", "brick_normal.png"}, not_judged
    assert main(["scan", str(tmp_path / "empty")]) == 2
    assert "no USD stage or MaterialX document found" in capsys.readouterr().err


def test_stacks_of_two_stages_are_told_apart_and_a_broken_link_is_named(tmp_path, capsys):
    import os
    import shutil

    for stage in ("a", "b"):
        shutil.copytree(SAMPLES.parent / "brick", tmp_path / "lib" / stage)
    shutil.copytree(SAMPLES, tmp_path / "lib" / "textures")
    sheet = tmp_path / "sheet.html"
    main(["check", str(tmp_path / "lib"), "--report", str(sheet)])
    out = " ".join(capsys.readouterr().out.split())
    assert out.count("</World/Looks/Brick> in ") == 2
    html = sheet.read_text(encoding="utf-8")
    assert all(f"&lt;/World/Looks/Brick&gt; in {tmp_path / 'lib' / s / 'scene.usda'}" in html for s in ("a", "b"))
    pictures = tmp_path / "pictures"
    pictures.mkdir()
    _write(pictures / "ok.png", _wood())
    os.symlink(pictures / "gone.png", pictures / "link.png")
    assert main(["check", str(pictures)]) == 1  # a picture of the folder that cannot be read; the folder is there
    [gone] = [i for i in check_paths([pictures]).items if i.error]
    assert gone.error.endswith("link.png@: no such file (a link to a file that is gone)")
    assert main(["check", str(pictures / "link.png")]) == 2  # named: a path that is not there


def test_links_that_loop_are_named_and_the_rest_judged(tmp_path, capsys):
    """Two links that lead to each other are each named as a picture that cannot be read (exit 1, as any picture of
    the folder that cannot be read); the picture beside them is judged; no crash. Named, such a link is a path that
    is not there (exit 2)."""
    lib = tmp_path / "lib"
    lib.mkdir()
    _write(lib / "wood.png", _wood())
    (lib / "x.png").symlink_to("y.png")
    (lib / "y.png").symlink_to("x.png")
    report = check_paths([lib])
    assert sorted(Path(i.name).name for i in report.items) == ["wood.png", "x.png", "y.png"]
    errors = [i.error for i in report.items if i.error]
    assert len(errors) == 2 and all("loop of links" in e for e in errors) and not report.unreadable
    assert report.exit_code == 1
    assert main(["check", str(lib / "x.png")]) == 2 and "loop of links" in capsys.readouterr().out


def test_a_folder_walk_for_check_takes_each_scene_as_processed_and_one_for_process_as_made():
    """``check`` walks a processed library as it now is: a stage's new layer (which composes the stage) instead of
    the stage, a document's new document instead of the document; ``.bak`` copies and stages in ``tileable``
    folders never. ``process`` and ``scan`` walk the sources, leaving every output out."""
    import tempfile

    from seamless_usd.pipeline.inputs import expand_inputs

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "a").mkdir()
        (root / "a" / "scene.usda").write_text('#usda 1.0\ndef Xform "World" {}\n')
        (root / "a" / "scene.seamless.usda").write_text('#usda 1.0\n(\n    subLayers = [@./scene.usda@]\n)\n')
        (root / "a" / "scene.usda.bak").write_text('#usda 1.0\n')
        (root / "b").mkdir()
        (root / "b" / "doc.mtlx").write_text('<?xml version="1.0"?>\n<materialx version="1.38"/>\n')
        (root / "b" / "doc.seamless.mtlx").write_text('<?xml version="1.0"?>\n<materialx version="1.38"/>\n')
        (root / "b" / "other.mtlx").write_text('<?xml version="1.0"?>\n<materialx version="1.38"/>\n')
        names = lambda found: sorted(str(p.relative_to(root)) for p in found)  # noqa: E731
        assert names(expand_inputs([root], outputs=True)) == ["a/scene.seamless.usda", "b/doc.seamless.mtlx",
                                                              "b/other.mtlx"]
        assert names(expand_inputs([root])) == ["a/scene.usda", "b/doc.mtlx", "b/other.mtlx"]


def test_what_a_picture_holds_beyond_what_is_judged_is_named(tmp_path):
    """A picture's colour is judged; its alpha, channels beyond colour and alpha (an OpenEXR's depth) and images after
    its first (a multi-part OpenEXR) are not, and the answer says so instead of passing them silently."""
    wood = _wood()
    seamed = np.roll(wood, (128, 128), (0, 1))[..., :1]  # a seam through its middle
    from imagefiles import write_raw_image

    codes = np.round(np.concatenate([wood, seamed], axis=2) * 255).astype(np.uint8)
    write_raw_image(tmp_path / "cutout.png", codes)  # straight alpha, as stored
    write_raw_image(tmp_path / "plain.png", codes[..., :3])
    spec = oiio.ImageSpec(256, 256, 4, oiio.HALF)
    spec.channelnames = ("R", "G", "B", "Z")
    out = oiio.ImageOutput.create(str(tmp_path / "depth.exr"))
    assert out.open(str(tmp_path / "depth.exr"), spec) and out.write_image(np.concatenate([wood, seamed], axis=2))
    out.close()
    parts = [oiio.ImageSpec(256, 256, 3, oiio.HALF) for _ in range(2)]
    for n, part in enumerate(parts):
        part.attribute("name", f"layer{n}")
    out = oiio.ImageOutput.create(str(tmp_path / "parts.exr"))
    assert out.open(str(tmp_path / "parts.exr"), parts) and out.write_image(wood)
    assert out.open(str(tmp_path / "parts.exr"), parts[1], "AppendSubimage") and out.write_image(np.roll(wood, 128, 1))
    out.close()
    items = {Path(i.name).name: i for i in check_paths([tmp_path]).items}
    assert items["cutout.png"].note == "not judged: its alpha channel"
    assert items["depth.exr"].note == "not judged: its other channel(s) Z"
    assert items["parts.exr"].note == "not judged: its second image (the file holds 2; only the first is read)"
    assert items["plain.png"].note == ""
    assert items["cutout.png"].verdict == items["plain.png"].verdict  # its colour, judged as the picture without alpha


def test_a_linear_openexrs_thumbnail_shows_as_its_8_bit_twin_does():
    """The sample brick colour stored as 8-bit sRGB and as linear half OpenEXR: the contact sheet shows both through
    the same display transfer, so the two thumbnails look alike instead of the EXR's reading far darker."""
    import base64
    import io

    from PIL import Image

    def shown(item) -> np.ndarray:
        uri = item.thumbnail[0]
        return np.asarray(Image.open(io.BytesIO(base64.b64decode(uri.split(",", 1)[1]))).convert("RGB"), np.float64)

    png, exr = check_paths([SAMPLES / "brick_albedo.png", SAMPLES / "brick_albedo_linear.exr"]).items
    a, b = shown(png), shown(exr)
    assert a.shape == b.shape and abs(a.mean() - b.mean()) < 3.0 and np.abs(a - b).mean() < 6.0, (a.mean(), b.mean())


def test_an_hdr_and_a_faint_picture_are_shown_readable_on_the_sheet_and_say_so(tmp_path):
    """A linear OpenEXR whose values reach 50 was a white square, a 16-bit map holding 1.5 % of its range a flat one;
    each is now shown exposed or stretched, and its card says how."""
    import base64
    import io

    import OpenImageIO as oiio
    from PIL import Image

    linear = np.asarray(oiio.ImageBuf(str(SAMPLES / "brick_albedo_linear.exr")).get_pixels(oiio.FLOAT))[..., :3]
    hdr = tmp_path / "hdr.exr"
    out = oiio.ImageBuf(oiio.ImageSpec(linear.shape[1], linear.shape[0], 3, oiio.HALF))
    out.set_pixels(oiio.ROI(0, linear.shape[1], 0, linear.shape[0], 0, 1, 0, 3), np.ascontiguousarray(linear * 50))
    assert out.write(str(hdr))
    grey = np.asarray(Image.open(SAMPLES / "brick_albedo.png").convert("L"), np.float64) / 255
    faint = tmp_path / "faint.png"
    Image.fromarray((1000 + grey * 1000).astype(np.uint16)).save(faint)  # 1.5 % of the 16-bit range
    for item in check_paths([hdr, faint]).items:
        shown = np.asarray(Image.open(io.BytesIO(base64.b64decode(item.thumbnail[0].split(",", 1)[1]))).convert("L"),
                           np.float64)
        assert shown.std() > 20 and 20 < shown.mean() < 235, (item.name, shown.mean(), shown.std())
        word = "exposed" if item.name.endswith(".exr") else "stretched"
        assert f"the picture is shown {word}" in item.card().words, item.card().words


def test_the_last_line_counts_the_inputs_that_could_not_be_read(tmp_path, capsys):
    """``check good.png missing.usda`` ended '1 of 1 passed' with exit code 2: the count now says what was not read."""
    _write(tmp_path / "good.png", _wood())
    assert main(["check", str(tmp_path / "good.png"), str(tmp_path / "missing.usda")]) == 2
    last = capsys.readouterr().out.strip().splitlines()[-1]
    assert last.endswith(" of 1 passed; 1 input could not be read")


def test_each_seams_figure_is_written_once_beside_its_own_line_on_the_sheet():
    """A picture seamed at both wraps had both figures written at its corner, the weaker over the stronger, and every
    seam's figure four times (once a repeat): each is now written once, on the copy through the middle."""
    import re

    from seamless_usd.report.contact import SheetCard, _segments
    from seamless_usd.report.htmlparts import seams_svg

    card = SheetCard("p.png", "not-passed", "", size=(100, 80), seams=[
        {"axis": "y", "position": 0, "start": 0, "end": 99, "figure": 1.01, "map": "stack"},
        {"axis": "x", "position": 0, "start": 0, "end": 79, "figure": 5.98, "map": "stack"}])
    svg = seams_svg((200, 160), _segments(card))
    texts = re.findall(r'<text x="([\d.]+)" y="([\d.]+)">([^<]+)</text>', svg)
    assert sorted(t[2] for t in texts) == ["+1.01", "+5.98"] and svg.count("<line") == 8
    (x1, y1), (x2, y2) = [(float(x), float(y)) for x, y, _ in texts]
    assert abs(x1 - x2) > 40 or abs(y1 - y2) > 14  # apart, each beside its line through the middle
    by_figure = {t[2]: (float(t[0]), float(t[1])) for t in texts}
    assert abs(by_figure["+5.98"][0] - 104) < 1 and abs(by_figure["+1.01"][1] - 94) < 1
    # two horizontal seams 16 texels apart: the weaker's figure would overlap the stronger's (a bold 12 px figure
    # with its halo is taller than 14): only the stronger is written
    close = SheetCard("q.png", "not-passed", "", size=(100, 80), seams=[
        {"axis": "y", "position": 46, "start": 0, "end": 99, "figure": 2.90, "map": "stack"},
        {"axis": "y", "position": 62, "start": 0, "end": 99, "figure": 1.76, "map": "stack"}])
    assert re.findall(r"<text[^>]*>([^<]+)</text>", seams_svg((200, 160), _segments(close))) == ["+2.90"]


def test_a_material_with_a_udim_set_is_left_alone_by_check_as_by_process(tmp_path, capsys):
    """A material reading a UDIM set beside a plain roughness: process leaves it alone (tiling the roughness alone
    would misalign it), and check judged the roughness against itself, not passed, exit 1."""
    import shutil

    tex = tmp_path / "tex"
    tex.mkdir()
    shutil.copyfile(SAMPLES / "brick_albedo.png", tex / "u.1001.png")
    shutil.copyfile(SAMPLES / "brick_roughness.png", tex / "brick_roughness.png")
    doc = tmp_path / "udim.mtlx"
    doc.write_text(
        '<?xml version="1.0"?>\n<materialx version="1.39">'
        '<image name="a" type="color3"><input name="file" type="filename" value="tex/u.&lt;UDIM&gt;.png"/></image>'
        '<image name="r" type="float"><input name="file" type="filename" value="tex/brick_roughness.png"/></image>'
        '<standard_surface name="S" type="surfaceshader"><input name="base_color" type="color3" nodename="a"/>'
        '<input name="specular_roughness" type="float" nodename="r"/></standard_surface>'
        '<surfacematerial name="M_udim" type="material"><input name="surfaceshader" type="surfaceshader" nodename="S"/>'
        '</surfacematerial></materialx>\n')
    assert main(["process", "--dry-run", "--json", str(doc)]) == 0
    [row] = json.loads(capsys.readouterr().out)["stacks"]
    assert row["status"] == "left-alone" and "udim" in row["message"]
    assert main(["check", "--json", str(doc)]) == 0
    assert json.loads(capsys.readouterr().out)["items"] == []


def test_an_empty_file_and_a_named_pipe_are_named_for_what_they_are(tmp_path):
    """A picture of 0 bytes read 'Not a PNG file' (to check and to the scan), and a named pipe 'no such file'."""
    import os

    from test_reliability_inputs import write_scene

    from seamless_usd.discover import scan_paths

    (tmp_path / "empty.png").write_bytes(b"")
    os.mkfifo(tmp_path / "pipe.png")
    report = check_paths([tmp_path / "empty.png", tmp_path / "pipe.png"])
    [empty] = report.items
    assert "the file is empty (0 bytes)" in empty.error
    assert report.unreadable == [f"@{tmp_path / 'pipe.png'}@: not a regular file (a named pipe, a device or a "
                                 "socket): only files are judged"]
    scene = write_scene(tmp_path / "scene.usda", {"Empty": "./empty.png"})
    [skip] = [f for f in scan_paths([scene]).findings if f.code == "unreadable-file"]
    assert "the file is empty (0 bytes)" in skip.message


def test_a_tile_saved_again_without_its_record_says_it_is_judged_on_its_own(tmp_path):
    """A tile this tool wrote, saved again by an image editor that drops what the file records: judged against itself
    its verdict can flip (the bundled brick's passed tile read seamed at a mortar edge), and nothing said why."""
    import shutil

    shutil.copy(SAMPLES / "brick_albedo.png", tmp_path / "brick_albedo.World_Looks_Brick-e1bb29ea54.bc9ef6bb.tile.png")
    shutil.copy(SAMPLES / "brick_albedo.png", tmp_path / "brick_albedo.png")
    notes = {Path(i.name).name: i.note for i in check_paths([tmp_path]).items}
    assert "records no source (saved again by another program?)" in notes[
        "brick_albedo.World_Looks_Brick-e1bb29ea54.bc9ef6bb.tile.png"]
    assert not notes["brick_albedo.png"]


def test_pictures_that_cannot_be_judged_are_counted_apart_everywhere(tmp_path, capsys):
    """A broken file and a picture too small to judge were counted as not passed in the JSON, while the contact
    sheet said they could not be judged: the JSON, the text summary and the sheet give the same three counts."""
    import shutil

    lib = tmp_path / "lib"
    lib.mkdir()
    shutil.copy(SAMPLES / "wood_tileable.jpg", lib / "wood.jpg")
    (lib / "broken.png").write_bytes(b"not a png")
    small = oiio.ImageBuf(oiio.ImageSpec(2, 2, 3, "uint8"))
    assert small.write(str(lib / "small.png"))
    sheet = tmp_path / "sheet.html"
    assert main(["check", str(lib), "--json", "--report", str(sheet)]) == 1
    report = json.loads(capsys.readouterr().out)
    jsonschema.validate(report, json_schema("check"))
    assert (report["passed"], report["not_passed"], report["errors"]) == (1, 0, 2)
    assert "1 passed, 0 not passed, 2 could not be judged." in sheet.read_text()
    assert main(["check", str(lib)]) == 1
    assert "1 of 3 passed, 2 could not be judged" in capsys.readouterr().out
