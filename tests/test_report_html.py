"""The HTML report: same-texel-scale pictures and their overlay, verdicts, weight, left-alone and
failed stacks, the library index. Built from real sample textures (no training)."""
from __future__ import annotations

import base64
import re
from pathlib import Path
from types import SimpleNamespace as NS

import numpy as np
import pytest

from seamless_usd.report.html import seam_segments, render_html, write_html
from seamless_usd.report.index import write_library_html
from seamless_usd.report.model import MapReport, Previews, Report, StackReport, StackStatus
from seamless_usd.report.previews import stack_previews
from seamless_usd.report.repeat import ViewGeometry, repeat_view, view_geometry
from specimen import specimen_stack

ROOT = Path(__file__).resolve().parents[1]
BRICK = ROOT / "sample_assets/brick/scene.usda"
MB = 1024 * 1024


def _map(node, role, channels="rgb", color_space="sRGB", is_normal=False):
    return NS(node=node, roles=(NS(role=role, channels=channels),), channels_used=channels,
              color_space=color_space, is_normal=is_normal)


@pytest.fixture(scope="module")
def brick_512():
    """The brick stack (albedo, normal, roughness) at 512 px with grain: hard to compress."""
    return specimen_stack(BRICK, "periodic", size=512, noise=0.06)


# --------------------------------------------------------------------------------------------
# Same texel scale
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("uv, window, tile_repeats", [((1.0, 1.0), 3.0, 3.0), ((0.5, 0.5), 6.0, 3.0),
                                                     ((2.0, 2.0), 3.0, 6.0)])
def test_window_covers_three_repeats_of_the_larger(uv, window, tile_repeats):
    g = view_geometry((512, 512), uv)
    assert g.window == (window, window) and g.tile_repeats == (tile_repeats, tile_repeats)
    assert g.size == (576, 576)


def test_window_keeps_texels_square_for_non_square_sources():
    g = view_geometry((512, 256), (1.0, 1.0))
    assert g.size == (576, 288)


def test_a_tile_covering_twice_the_uv_area_is_shown_at_the_source_texel_scale():
    rng = np.random.default_rng(0)
    source = rng.uniform(-1, 1, (64, 64, 3))
    tile = np.tile(source, (2, 2, 1))  # 128 px covering 2x2 UV units: uv scale 0.5, same texel density
    p = stack_previews([_map("/M/C", "diffuseColor")], [source], [tile], (0.5, 0.5), max_px=192)
    assert p.view["window"] == [6.0, 6.0]
    np.testing.assert_array_equal(p.source_view["/M/C"], p.tile_view["/M/C"])
    # At 2x the texel scale (the old side-by-side 2x2s) the two would differ.
    magnified = np.repeat(np.repeat(source, 2, axis=0), 2, axis=1)
    q = stack_previews([_map("/M/C", "diffuseColor")], [source], [magnified], (0.5, 0.5), max_px=192)
    assert np.abs(q.source_view["/M/C"].astype(int) - q.tile_view["/M/C"].astype(int)).mean() > 20


def test_repeat_view_wraps_at_the_borders_without_smearing_the_seam():
    img = np.zeros((8, 8))
    img[:, -1] = 1.0  # a hard seam between the last and the first column
    g = ViewGeometry(window=(2.0, 2.0), tile_extent=(1.0, 1.0), size=(16, 16))
    row = repeat_view(img, (1.0, 1.0), g)[0, :, 0]
    np.testing.assert_allclose(row, np.tile(img[0], 2))


def test_overlay_lines_sit_on_the_tile_borders_and_centre_lines(brick_512):
    stack = specimen_stack(BRICK, "periodic")
    stack.uv_scale = (0.5, 0.5)
    src = [np.zeros((64, 64, 3)), np.zeros((64, 64, 3)), np.zeros((64, 64, 1))]
    maps = [_map(m.node, m.roles[0], m.channels) for m in stack.maps]
    stack.previews = stack_previews(maps, src, [np.zeros((128, 128, c.shape[2])) for c in src], (0.5, 0.5))
    page = render_html(Report(sources=[stack.source], stacks=[stack]))
    svgs = re.findall(r'<svg class="overlay".*?</svg>', page)
    assert len(svgs) == 2 * 4  # source and tile, for 3 maps and the lit material
    tile_svg = svgs[1]
    borders = sorted({float(x) for x in re.findall(r'class="border" x1="([\d.]+)" y1="0"', tile_svg)})
    centres = sorted({float(x) for x in re.findall(r'class="centre" x1="([\d.]+)" y1="0"', tile_svg)})
    assert borders == [192.0, 384.0] and centres == [96.0, 288.0, 480.0]
    source_borders = sorted({float(x) for x in re.findall(r'class="border" x1="([\d.]+)" y1="0"', svgs[0])})
    assert source_borders == [96.0 * k for k in range(1, 6)]  # six source repeats across
    assert 'id="overlay-toggle"' in page and "#overlay-toggle:checked ~ main .overlay{display:block}" in page
    assert "6 x 6 repeats (as authored)" in page and "3 x 3 repeats (UV scale 0.5 x 0.5)" in page


# --------------------------------------------------------------------------------------------
# Verdicts, statuses
# --------------------------------------------------------------------------------------------


def test_verdicts_are_in_words_next_to_the_numbers_and_tolerances_are_the_stacks_own():
    m = MapReport(node="/M/C", asset="c.png", output=None, roles=["diffuseColor"], channels="rgb", color_space="sRGB",
                  metrics={"scale_ratio": 1.14, "patch_distance": 0.9, "centre_seam_x": 1.6, "centre_seam_y": 1.0,
                           "seam_ratio_x": 1.01, "seam_ratio_y": 1.3, "ssim": 0.5},
                  source_metrics={"seam_ratio_x": 2.5})
    verdict = {"passed": True, "seamless": True, "faithful": True, "seams": [], "size": [64, 64],
               "tolerances": {"c.png": {"scale_ratio": [0.8, 1.2], "patch_distance": [None, 1.2]}}}
    stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED, maps=[m],
                        verdict=verdict)
    page = render_html(Report(sources=["s.usda"], stacks=[stack]))
    # 1.14 is outside the fixed 0.9-1.1 but inside this source's own spread, 0.8-1.2
    assert "scale kept (1.14)" in page and "0.8–1.2" in page and "patches like the source&#x27;s (0.9)" in page
    assert 'class="v bad"' not in page  # the seam ratios are figures, not a verdict
    assert "Passed: seamless and faithful." in page and "other figures (no target)" in page


def test_a_seam_is_named_and_marked_on_the_tile_repeats():
    m = MapReport(node="/M/C", asset="c.png", output=None, roles=["diffuseColor"], channels="rgb", color_space="sRGB",
                  metrics={"scale_ratio": 1.0}, source_metrics={})
    seam = {"map": "c.png", "axis": "x", "position": 32, "start": 0, "end": 63, "figure": 1.4}
    stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.NOT_PASSED, maps=[m],
                        tile_size=(64, 64), uv_scale=(2.0, 2.0),
                        verdict={"passed": False, "seamless": False, "faithful": True, "seams": [seam], "size": [64, 64]})
    g = ViewGeometry(window=(1.5, 1.5), tile_extent=(0.5, 0.5), size=(576, 576))  # 3 x 3 repeats of 192 px
    segments = seam_segments(g, [seam], (64, 64))
    # the line at x = 32 of a 64 px tile is the middle of each 192 px repeat: 96, 288, 480, over each repeat's rows
    assert sorted({round(s[0]) for s in segments}) == [96, 288, 480] and len(segments) == 9
    assert all(s[0] == s[2] and s[3] - s[1] == pytest.approx(192.0) for s in segments)
    page = render_html(Report(sources=["s.usda"], stacks=[stack]))
    assert "Not passed" in page and "vertical line at x=32 (the centre), rows 0-63" in page
    assert "Look at the repeats" not in page


def test_run_details_list_each_seed_and_the_one_kept():
    seeds = [{"seed": 0, "q_passed": False, "score": 1.28, "chosen": False},
             {"seed": 1, "q_passed": True, "score": 2.29, "chosen": True}]
    stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED,
                        resampled={"gan": {"seeds": seeds}})
    page = render_html(Report(sources=["s.usda"], stacks=[stack]))
    assert "GAN seeds" in page and "seed 0: 1.28, seed 1: 2.29 (Q passed) — kept" in page
    one = StackReport(id="M-2", material="</M2>", source="s.usda", status=StackStatus.PASSED,
                      resampled={"gan": {"seeds": []}})
    assert "GAN seeds" not in render_html(Report(sources=["s.usda"], stacks=[one]))


def test_run_details_say_what_seeded_the_refinement():
    lattice = {"period_px": [107.49, 106.51], "strength": [0.51, 0.56], "tile": [215, 213], "band": [27, 27],
               "offset": [14, 16], "q_passed": True, "lattice_ratio": 0.97, "passes": True, "score": 0.98,
               "score_gan": 1.94, "q_passed_gan": False, "lattice_ratio_gan": 0.45, "passes_gan": False,
               "chosen": True}
    stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED,
                        resampled={"gan": {"layout": "lattice", "lattice": lattice}})
    page = render_html(Report(sources=["s.usda"], stacks=[stack]))
    # width x height: the period across x first, the tile's width first
    assert "a cut of whole lattice periods from the source; repeats every 106.51 x 107.49 px (across x, down y)" in page
    assert ("lattice cut 213x215 px scored 0.98 (Q passed, lattice ratio 0.97, passed as cut) against 1.94 from gan "
            "(Q not passed, lattice ratio 0.45)") in page
    plain = StackReport(id="M-2", material="</M2>", source="s.usda", status=StackStatus.PASSED,
                        resampled={"gan": {"layout": "gan", "lattice": {"period_px": [None, None]}}})
    page = render_html(Report(sources=["s.usda"], stacks=[plain]))
    assert "tile made from" in page and "the SeamlessGAN tile, refined" in page and "repeats every" not in page
    window = {"period_px": [None, None], "strength": [None, None], "cut": "window", "tile": [364, 386],
              "band": [51, 51], "offset": [5, 9], "q_passed": False, "passes": True, "score": 0.91,
              "score_random": 2.07, "q_passed_random": False, "passes_random": False, "chosen": True,
              "lag_difference": {"y": 0.73, "x": 0.78}}
    cut = StackReport(id="M-3", material="</M3>", source="s.usda", status=StackStatus.PASSED,
                      resampled={"gan": {"layout": "window", "lattice": window}})
    page = render_html(Report(sources=["s.usda"], stacks=[cut]))
    assert "one window of the source, joined across its wraps along minimum-error cuts" in page
    assert "repeats every" not in page
    assert ("window cut 386x364 px scored 0.91 (Q not passed, passed as cut) against 2.07 from random (Q not passed)"
            in page)
    refused = {"period_px": [None, None], "strength": [None, None], "score_random": 2.07, "passes_random": False,
               "window_refused": {"lag_difference": {"y": 0.64, "x": 0.68}, "most": 0.05}}
    plain = StackReport(id="M-4", material="</M4>", source="s.usda", status=StackStatus.NOT_PASSED,
                        resampled={"gan": {"layout": "random", "lattice": refused}})
    page = render_html(Report(sources=["s.usda"], stacks=[plain]))
    assert ("a random start, refined (the GAN tile&#x27;s feature scale was implausible); no window cut: the texture "
            "does not continue itself at any window&#x27;s lags (difference y 0.64, x 0.68; a cut is offered at 0.05 "
            "or less)") in page
    quilt = {**refused, "cut": "quilt", "tile": [512, 512], "q_passed": False, "passes": False, "score": 1.17,
             "chosen": True, "cells": [2, 2], "join_worst": 0.0559, "join_mean": 0.0412, "difference_worst": 0.0559}
    made = StackReport(id="M-5", material="</M5>", source="s.usda", status=StackStatus.NOT_PASSED,
                       resampled={"gan": {"layout": "quilt", "lattice": quilt}})
    page = render_html(Report(sources=["s.usda"], stacks=[made]))
    assert "large source blocks quilted on a torus, joined along minimum-error cuts" in page
    assert ("quilt 512x512 px of 2x2 blocks (worst difference along a cut 0.056) scored 1.17 (Q not passed) "
            "against 2.07 from random (Q not passed)") in page
    kept = {**quilt, "chosen": False, "passes": True, "quilt_refused": {"difference_worst": 0.1033, "most": 0.05}}
    made = StackReport(id="M-6", material="</M6>", source="s.usda", status=StackStatus.NOT_PASSED,
                       resampled={"gan": {"layout": "random", "lattice": kept}})
    page = render_html(Report(sources=["s.usda"], stacks=[made]))
    assert ("quilt not written: the verdict passes it, but its blocks differ along a cut by 0.10 (its joins hide at "
            "0.05 or less)") in page
    one_axis = {"period_px": [None, 17.06], "strength": [None, 0.44], "cut": "lattice", "tile": [448, 506],
                "q_passed": False, "passes": False, "score": 0.95, "chosen": False, "score_random": 0.81,
                "passes_random": False, "band": [64, 4], "difference": {"x": 0.09, "y": 0.2076}, "open_axes": ["y"],
                "difference_worst": 0.2076, "lattice_refused": {"difference_worst": 0.2076, "most": 0.05}}
    made = StackReport(id="M-8", material="</M8>", source="s.usda", status=StackStatus.NOT_PASSED,
                       resampled={"gan": {"layout": "random", "lattice": one_axis}})
    page = render_html(Report(sources=["s.usda"], stacks=[made]))
    assert ("lattice cut not written: the verdict passes it, but its wrap across the axis that does not repeat joins "
            "places that differ by 0.21 (its joins hide at 0.05 or less)") in page
    assert "lattice cut 506x448 px (no repeat along y: difference along that wrap&#x27;s cut 0.208) scored 0.95" in page
    # not passed with a seam: the box says what to do where the joins cannot hide (refined, or the quilt's
    # blocks differ along a cut), and not where the quilt's joins hide
    seam = {"axis": "x", "position": 68, "start": 66, "end": 112, "figure": 0.28, "map": "stack"}
    judged = {"passed": False, "seamless": False, "faithful": True, "size": [512, 512], "seams": [seam]}
    for layout, lattice, told in (("random", kept, True), ("quilt", {**quilt, "difference_worst": 0.03}, False)):
        made = StackReport(id="M-7", material="</M7>", source="s.usda", status=StackStatus.NOT_PASSED, verdict=judged,
                           resampled={"gan": {"layout": layout, "lattice": lattice}})
        page = render_html(Report(sources=["s.usda"], stacks=[made]))
        assert "Not passed" in page and ("<b>What to do</b>: the texture neither repeats nor continues itself (its "
                                         "window lags differ by y 0.64, x 0.68" in page) == told


def test_run_details_show_each_synthesis_stage_as_a_picture():
    m = _map("/M/C", "diffuseColor")
    ramp = np.linspace(-1, 1, 24 * 24 * 3, dtype=np.float32).reshape(24, 24, 3)
    stages = [("GAN layout, 24 x 24 px (working resolution)", ramp),
              ("refinement level 48 x 48 px, carried (no search)", np.zeros((48, 48, 3), np.float32))]
    p = stack_previews([m], [np.zeros((32, 32, 3))], [np.zeros((32, 32, 3))], (1.0, 1.0), levels=stages)
    assert [c for c, _ in p.levels] == [c for c, _ in stages]
    assert p.levels[0][1].dtype == np.uint8 and p.levels[0][1].shape == (24, 24, 3)
    assert p.levels[0][1][0, 0, 0] == 0 and p.levels[0][1][-1, -1, -1] == 255  # -1..1 shown as 0..255
    stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED, previews=p)
    page = render_html(Report(sources=["s.usda"], stacks=[stack]))
    details = page[page.index("run details"):]
    assert "stage by stage" in details and details.count("<figure>") >= 2
    assert "refinement level 48 x 48 px, carried (no search)" in details
    bare = StackReport(id="M-2", material="</M2>", source="s.usda", status=StackStatus.PASSED)
    assert "stage by stage" not in render_html(Report(sources=["s.usda"], stacks=[bare]))


def test_left_alone_and_failed_stacks_say_why():
    left = StackReport(id="D-1", material="</Decal>", source="s.usda", status=StackStatus.LEFT_ALONE,
                       intent="uv-atlas", intent_reason="UVs 0.11-0.89, 37 islands")
    failed = StackReport(id="B-1", material="</Broken>", source="s.usda", status=StackStatus.FAILED,
                         message="@a.png@: unreadable")
    page = render_html(Report(sources=["s.usda"], stacks=[left, failed]))
    assert "<b>Left alone</b>: uv-atlas: UVs 0.11-0.89, 37 islands" in page
    assert 'class="badge left-alone"' in page and "@a.png@: unreadable" in page


def test_data_maps_without_albedo_are_shown_as_they_are():
    m = _map("/M/H", "displacement", "r", "raw")
    p = stack_previews([m], [np.zeros((32, 32, 1))], [np.zeros((32, 32, 1))], (1.0, 1.0), max_px=96)
    assert p.lit_tile is None and p.lit_source is None and "shown as they are" in p.lit_note
    assert p.tile_view["/M/H"].shape == (96, 96, 3) and p.thumbnail is not None


def test_stack_previews_keeps_its_positional_signature():
    m = _map("/M/C", "diffuseColor")
    disc = np.zeros((16, 16, 3), np.uint8)
    p = stack_previews([m], [np.zeros((32, 32, 3))], [np.zeros((32, 32, 3))], (1.0, 1.0), disc)
    assert p.discriminator is not None and p.lit_tile.shape == p.tile_view["/M/C"].shape


# --------------------------------------------------------------------------------------------
# Weight and self-containment
# --------------------------------------------------------------------------------------------


def _self_contained(page: str) -> None:
    refs = re.findall(r'(?:src|href)="([^"]*)"', page)
    external = [r for r in refs if not (r.startswith("data:") or r.startswith("#"))]
    assert external == [], f"the page refers to outside files: {external[:3]}"
    assert "<script src" not in page and "@import" not in page and "url(http" not in page


def test_a_three_map_512px_page_is_one_file_under_2_mb(brick_512, tmp_path):
    assert len(brick_512.maps) == 3 and brick_512.working_size == (512, 512)
    path = write_html(Report(sources=[brick_512.source], stacks=[brick_512]), tmp_path / "report.html")
    page = path.read_text()
    size = path.stat().st_size
    print(f"3-map 512 px page: {size / MB:.2f} MB")
    assert size < 2 * MB
    _self_contained(page)
    uris = re.findall(r'src="data:(image/[a-z]+);base64,([^"]+)"', page)
    assert len(uris) == 2 * 4  # source and tile of 3 maps and the lit material
    assert {mime for mime, _ in uris} <= {"image/webp", "image/jpeg"}
    for mime, data in uris:
        raw = base64.b64decode(data)
        assert raw[:4] == b"RIFF" and raw[8:12] == b"WEBP" if mime == "image/webp" else raw[:2] == b"\xff\xd8"


def test_the_jpeg_fallback_also_stays_under_2_mb(brick_512, tmp_path, monkeypatch):
    from seamless_usd.report import webimage

    monkeypatch.setenv("SEAMLESS_USD_REPORT_FORMAT", "jpeg")
    webimage.web_format.cache_clear()
    try:
        page = render_html(Report(sources=[brick_512.source], stacks=[brick_512]))
    finally:
        monkeypatch.delenv("SEAMLESS_USD_REPORT_FORMAT")
        webimage.web_format.cache_clear()
    print(f"3-map 512 px page, JPEG: {len(page.encode()) / MB:.2f} MB")
    assert len(page.encode()) < 2 * MB and page.count("data:image/jpeg;base64,") == 8


# --------------------------------------------------------------------------------------------
# Library index
# --------------------------------------------------------------------------------------------


def test_library_index_has_a_card_per_stack_filterable_by_status(brick_512, tmp_path):
    left = StackReport(id="D-1", material="</Decal>", source="b.usda", status=StackStatus.LEFT_ALONE,
                       intent="uv-atlas", intent_reason="UVs 0.11-0.89, 37 islands")
    failed = StackReport(id="X-1", material="</Broken>", source="b.usda", status=StackStatus.FAILED, message="unreadable")
    report = Report(sources=[brick_512.source, "b.usda"], stacks=[brick_512, left, failed])
    index_path = write_library_html(report, tmp_path / "library.html")
    index = index_path.read_text()
    _self_contained(re.sub(r'href="library\.files/[^"]+"', 'href="#"', index))
    cards = re.findall(r'<div class="card s-([a-z-]+)" data-status="\1">', index)
    assert sorted(cards) == sorted([brick_512.status.value, "left-alone", "failed"])
    assert cards[0] == "failed"  # what needs a look first, though its file comes second
    assert index.count('type="radio"') == 1 + 3  # all + the statuses present
    assert "#f-left-alone:checked ~ .cards .card:not(.s-left-alone){display:none}" in index
    assert "uv-atlas: UVs 0.11-0.89, 37 islands" in index and "unreadable" in index
    assert index.count("data:image/") == 1  # one thumbnail: the processed stack; the others have none
    assert f'href="library.files/0001-scene.html#{brick_512.id}"' in index  # the card: the stack on its page
    assert len(re.findall(r'href="library\.files/[^"#]+"', index)) == 2  # the files table: one link per file
    pages = sorted((tmp_path / "library.files").glob("*.html"))
    assert len(pages) == 2 and f'id="{brick_512.id}"' in pages[0].read_text()


def test_a_high_seam_ratio_is_a_figure_not_a_verdict():
    """A cut tile with a mortar joint at its wrap reads a seam ratio of 1.53; the seam detector, not that
    figure, decides: the page shows the figure with no target and no "seam visible" words."""
    m = MapReport(node="/M/R", asset="r.png", output=None, roles=["roughness"], channels="r", color_space="raw",
                  metrics={"scale_ratio": 1.03, "patch_distance": 0.89, "seam_ratio_x": 1.53, "seam_ratio_y": 0.83,
                           "centre_seam_x": 1.06, "centre_seam_y": 0.92})
    for layout in ("lattice", "window", "gan", "random", None):
        stack = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED, maps=[m],
                            resampled={"gan": {"layout": layout} if layout else {}},
                            verdict={"passed": True, "seamless": True, "faithful": True, "seams": [], "size": [64, 64]})
        page = render_html(Report(sources=["s.usda"], stacks=[stack]))
        assert "seam visible" not in page and "strong line" not in page and 'class="v bad"' not in page
        assert "<td>1.53</td>" in page and "Passed: seamless and faithful." in page


def test_a_library_of_scene_usda_files_names_each_by_its_folder_and_keeps_each_files_findings(tmp_path):
    """Every file of a library was a 'scene.usda' on its card and page title, and a file's page listed another file's
    findings about a material of the same path (every </World/Looks/Brick>), calling a file that passed 'needs a
    look'. Each finding now names the file it was found in."""
    from seamless_usd.findings import Finding, Severity

    good, bad = str(tmp_path / "brick" / "scene.usda"), str(tmp_path / "missing" / "scene.usda")
    stacks = [StackReport(id="B-1", material="</World/Looks/Brick>", source=good, status=StackStatus.PASSED),
              StackReport(id="B-2", material="</World/Looks/Brick>", source=bad, status=StackStatus.FAILED,
                          message="nope.png is missing")]
    missing = Finding(Severity.SKIPPED, "missing-file", "@../textures/nope.png@", "file not found",
                      material="</World/Looks/Brick>", source=bad)
    report = Report(sources=[good, bad], stacks=stacks, findings=[missing])
    index = write_library_html(report, tmp_path / "library.html").read_text()
    # each card names its file (the failed stack's card first)
    assert re.findall(r'<div class="file">([^<]+)</div>', index) == ["missing/scene.usda", "brick/scene.usda"]
    pages = {p.read_text().split("<title>")[1].split("</title>")[0]: p.read_text()
             for p in (tmp_path / "library.files").glob("*.html")}
    assert set(pages) == {"seamless-usd: brick/scene.usda", "seamless-usd: missing/scene.usda"}
    assert "nope.png" not in pages["seamless-usd: brick/scene.usda"]
    assert "nope.png" in pages["seamless-usd: missing/scene.usda"]
    files = re.findall(r"<tr><td><a [^>]+>([^<]+)</a></td>.*?<td>([a-z ]+)</td></tr>", index)
    assert dict(files) == {good: "ok", bad: "needs a look"}


def test_a_passed_card_lists_no_figure_its_own_tolerance_holds():
    """A passed stack whose feature scale (0.8995) sat within its own tolerance (0.899-1.1) but outside the fixed
    targets: the library's card said "magnified or blurred (0.9)" beside "passed"."""
    from seamless_usd.report.html import failing_figures
    from seamless_usd.report.model import MapReport, StackReport, StackStatus

    albedo = MapReport(node="</M/Albedo>", asset="wood.png", output="/t/wood.tile.png", roles=["diffuseColor"],
                       channels="rgb", color_space="sRGB", metrics={"scale_ratio": 0.8995})
    passed = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.PASSED, maps=[albedo],
                         verdict={"passed": True, "tolerances": {"wood.png": {"scale_ratio": [0.899, 1.1]}}})
    assert failing_figures(passed) == []
    not_passed = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.NOT_PASSED,
                             maps=[albedo], verdict={"passed": False}, failing=["diffuseColor: scale_ratio 0.62"])
    assert failing_figures(not_passed) == ["diffuseColor: feature scale vs source — magnified or blurred (0.62)"]


def test_a_seam_just_over_the_margin_is_not_said_to_be_zero_and_a_page_of_stacks_left_alone_claims_no_pass():
    """A seam 0.002 over the margin read "+0.00 above the seam threshold"; a library's page for a file whose one
    stack was left alone said "all stacks passed (exit code 0)" while nothing there was made."""
    from seamless_usd.report.html import render_html
    from seamless_usd.report.model import Report, StackReport, StackStatus
    from seamless_usd.verdict.lines import Seam, figure_text

    assert figure_text(0.002) == "+0.002" and figure_text(0.4567) == "+0.46" and figure_text(-0.3) == "-0.30"
    assert Seam("x", 64, 0, 127, 0.002).above == "+0.002"
    alone = StackReport(id="M-1", material="</M>", source="s.usda", status=StackStatus.LEFT_ALONE)
    page = render_html(Report(sources=["s.usda"], stacks=[alone]))
    assert "no stack made" in page and "all stacks" not in page
    passed = StackReport(id="M-2", material="</N>", source="s.usda", status=StackStatus.PASSED)
    assert "all stacks made passed" in render_html(Report(sources=["s.usda"], stacks=[alone, passed]))


def test_a_library_reports_its_pages_as_they_are_written(tmp_path):
    """A library's report took tens of seconds after the last stack (a page a source) with nothing on the screen."""
    from seamless_usd.report.index import write_library_html

    sources = [str(tmp_path / f"asset{n}" / "asset.usda") for n in range(3)]
    seen = []
    write_library_html(Report(sources=sources, stacks=[]), tmp_path / "lib.html",
                       progress=lambda done, total: seen.append((done, total)))
    assert seen == [(1, 3), (2, 3), (3, 3)] and len(list((tmp_path / "lib.files").glob("*.html"))) == 3


def test_a_library_page_the_same_as_the_one_there_is_not_drawn_again(tmp_path):
    """A warm run of a 200-file library spent 40 s drawing every page again from pictures that had not changed."""
    import time

    from safetensors.numpy import save_file

    from seamless_usd.report.index import write_library_html
    from seamless_usd.report.stored import previews_to_arrays, stored_previews

    arrays, info = previews_to_arrays(Previews(thumbnail=np.zeros((8, 8, 3), np.uint8), view={}))
    save_file(arrays, str(tmp_path / "pictures.safetensors"))
    sources = [str(tmp_path / f"asset{n}" / "asset.usda") for n in range(2)]

    def library(message: str) -> Report:
        return Report(sources=sources, stacks=[
            StackReport(id=f"s{n}", material=f"</M{n}>", source=s, status=StackStatus.PASSED,
                        message=message if n == 1 else "",
                        previews=stored_previews(str(tmp_path / "pictures.safetensors"), info))
            for n, s in enumerate(sources)])

    write_library_html(library("first"), tmp_path / "lib.html")
    pages = sorted((tmp_path / "lib.files").glob("*.html"))
    drawn = [p.stat().st_mtime_ns for p in pages]
    time.sleep(0.01)
    write_library_html(library("first"), tmp_path / "lib.html")
    assert [p.stat().st_mtime_ns for p in pages] == drawn  # nothing changed: nothing drawn again
    write_library_html(library("second"), tmp_path / "lib.html")
    again = [p.stat().st_mtime_ns for p in pages]
    assert again[0] == drawn[0] and again[1] != drawn[1] and "second" in pages[1].read_text(encoding="utf-8")


def test_an_interrupted_run_says_which_layers_it_wrote():
    """Stopped while stages were edited, the page said 'no stage edited' over the list of layers it had written."""
    stopped = Report(sources=["a.usda", "b.usda"], interrupted=True, layers_written=["/lib/a.seamless.usda"])
    assert "interrupted (Ctrl-C or SIGTERM): 1 layer(s) or document(s) written" in render_html(stopped)
    assert "no stage edited" not in render_html(stopped)
    assert "interrupted (Ctrl-C or SIGTERM): no stage edited" in render_html(Report(sources=["a.usda"], interrupted=True))
