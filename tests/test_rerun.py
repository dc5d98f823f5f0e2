"""An unchanged rerun is a no-op: the tiles a previous run wrote are still on disk, so their judged result is
taken back (pipeline/rerun.py); a tile changed or removed since is written and judged again."""
from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _run(root: Path, capsys, *extra: str) -> dict:
    code = main(["process", str(root / "brick" / "scene.usda"), "--preset", "tiny", "--max-size", "128",
                 "--cache-dir", str(root / "cache"), "--json", *extra])
    report = json.loads(capsys.readouterr().out)
    assert code == report["exit_code"]
    return report


def _judged(report: dict) -> list[dict]:
    """What a run says of its stacks, less how long it took and where the result came from."""
    return [{k: v for k, v in s.items() if k not in ("timings", "origin", "message", "peak_rss_mb")}
            for s in report["stacks"]]


def _outputs(report: dict) -> dict[str, str]:
    return {m["output"]: hashlib.sha256(Path(m["output"]).read_bytes()).hexdigest()
            for s in report["stacks"] for m in s["maps"] if m.get("output")}


def test_an_unchanged_rerun_takes_the_judged_result_back_and_a_changed_tile_is_judged_again(tmp_path, capsys):
    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    first = _run(tmp_path, capsys)
    written = _outputs(first)
    assert written and first["stacks"][0]["status"] == "passed"
    layer = tmp_path / "brick" / "scene.seamless.usda"
    stamps = {p: Path(p).stat().st_mtime_ns for p in [*written, str(layer)]}

    again = _run(tmp_path, capsys)
    assert _judged(again) == _judged(first) and again["stacks"][0]["origin"] == "cache"
    assert {p: Path(p).stat().st_mtime_ns for p in stamps} == stamps  # nothing written again, the layer neither
    assert not again["layers_written"] and "already has these edits; no layer written" in json.dumps(again["findings"])
    assert again["stacks"][0]["timings"] == first["stacks"][0]["timings"]  # not judged again: the same record

    # a tile changed by hand (a dark stripe across it) is the TD's now: left as it is, its stack failing, naming it
    albedo = next(p for p in written if "albedo" in p)
    pixels = oiio.ImageBuf(albedo).get_pixels(oiio.FLOAT)
    pixels[40:48] *= 0.2
    out = oiio.ImageOutput.create(albedo)
    out.open(albedo, oiio.ImageSpec(pixels.shape[1], pixels.shape[0], pixels.shape[2], oiio.UINT8))
    out.write_image(np.ascontiguousarray(pixels))
    out.close()
    painted = Path(albedo).read_bytes()
    third = _run(tmp_path, capsys)
    assert third["stacks"][0]["status"] == "failed" and "changed since this tool wrote it" in third["stacks"][0]["message"]
    assert Path(albedo).read_bytes() == painted
    # deleted, it is made again from the cache, the cached one byte for byte, and judged again
    Path(albedo).unlink()
    fourth = _run(tmp_path, capsys)
    assert _outputs(fourth) == written
    assert _judged(fourth) == _judged(first)

    # another output folder is a different set of files: written and judged there
    elsewhere = _run(tmp_path, capsys, "--output-dir", str(tmp_path / "elsewhere"))
    assert all(p.startswith(str(tmp_path / "elsewhere")) for p in _outputs(elsewhere))
    assert [s["verdict"] for s in elsewhere["stacks"]] == [s["verdict"] for s in first["stacks"]]


def test_the_same_tiles_written_into_several_folders_keep_their_pictures_once(tmp_path, capsys):
    """Copies of a library processed with one cache: each folder keeps its own small record, the report's pictures
    of the same tiles once (the cache no longer grows by them for every copy)."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for copy in ("a", "b"):
        for name in ("brick", "textures"):
            shutil.copytree(samples / name, tmp_path / copy / name)
        assert main(["process", str(tmp_path / copy / "brick" / "scene.usda"), "--preset", "tiny", "--max-size", "128",
                     "--cache-dir", str(tmp_path / "cache")]) in (0, 1)
    judged = list((tmp_path / "cache").rglob("judged/*"))
    assert len([p for p in judged if p.name.endswith(".json")]) == 2
    assert len([p for p in judged if p.name.endswith(".pictures.safetensors")]) == 1


def test_a_run_keeps_no_report_pictures_in_memory_and_its_report_still_shows_them(tmp_path):
    """Each stack's pictures (a few MB) were held for the whole run and decoded again for every cache hit, with or
    without a report: a library run of 337 small materials peaked at 2 GB. Kept in the cache, they are read only
    while the report draws that stack, first run and again."""
    import re

    import seamless_usd
    from seamless_usd.report.stored import loaded, thumbnail_picture

    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    for run in ("first", "again"):
        report_file = tmp_path / run / "report.html"
        report = seamless_usd.process_paths([tmp_path / "brick" / "scene.usda"], seamless_usd.Options(
            preset="tiny", max_size=128, cache_dir=tmp_path / "cache", report=report_file))
        [stack] = report.stacks
        held = stack.previews
        assert held.stored and not held.tile_view and not held.source_view and held.lit_tile is None, run
        assert loaded(held).tile_view and thumbnail_picture(held) is not None
        page = report_file.read_text(encoding="utf-8")
        assert len(re.findall(r'src="data:image/', page)) >= 8, run  # source and tile of 3 maps and the lit pair
