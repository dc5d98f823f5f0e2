"""Levelling a photo's light before its copies are joined, the verdict's broad tone steps that make it needed,
the thin joints that gate a mend, and ``process`` end to end on an unevenly lit photo."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from pxr import Usd, UsdShade

from seamless_usd.imaging.level import LEVEL_MIN, level_maps
from seamless_usd.synthesis import MapInput
from seamless_usd.synthesis.candidates import check_cut, check_levelled, cut_candidates
from seamless_usd.synthesis.lattice.cut import find_lattice
from seamless_usd.synthesis.lattice.lines import has_thin_lines, thin_line_share
from seamless_usd.synthesis.lattice.mend import best_mend
from seamless_usd.synthesis.lattice.quilt import line_mask, line_sigma
from seamless_usd.verdict import judge
from seamless_usd_cli.main import main
from scenes import ground_scene

SKIMAGE = Path(__import__("skimage").__file__).parent / "data"


def _photo(name: str, size: int) -> np.ndarray:
    """A scikit-image photo (grey, CC0) as an sRGB colour map, ``size`` px square, network domain."""
    with Image.open(SKIMAGE / name) as im:
        im = im.convert("RGB").resize((size, size), Image.Resampling.LANCZOS)
    return np.asarray(im, dtype=np.float32) / 127.5 - 1.0


def _lit(px: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``px`` lit unevenly: brighter from left (``lo``) to right (``hi``), as a wall in raking light."""
    ramp = np.linspace(lo, hi, px.shape[1], dtype=np.float32)[None, :, None]
    return (np.clip((px + 1) / 2 * ramp, 0, 1) * 2 - 1).astype(np.float32)


def test_levelling_evens_the_light_and_leaves_texels_in_place():
    gravel = _photo("gravel.png", 192)
    lit = _lit(gravel, 0.7, 1.2)
    normal = np.dstack([np.zeros((192, 192, 2), np.float32), np.ones((192, 192, 1), np.float32)])
    (even, normal_after), facts = level_maps([lit, normal], [False, True])
    column = lambda a: a.mean(axis=(0, 2))  # noqa: E731
    ends = lambda a: abs(column(a)[:32].mean() - column(a)[-32:].mean())  # noqa: E731
    assert ends(lit) > 0.25 and ends(even) < 0.06, (ends(lit), ends(even))
    assert facts["moved"] > 0.2 and 0 < facts["moved_mean"] < facts["moved"]
    assert normal_after is normal or np.array_equal(normal_after, normal)  # light is not in a normal map
    # texel for texel the photo before it was lit: a gain, no shift, no blur
    corr = lambda a: np.corrcoef(a[..., 0].ravel(), gravel[..., 0].ravel())[0, 1]  # noqa: E731
    assert corr(even) > 0.97 and corr(even) > corr(lit), (corr(even), corr(lit))
    assert even.min() >= lit.min() - 1e-6 and even.max() <= lit.max() + 1e-6
    # a picture whose light is even (white noise: its broad tone varies by well under LEVEL_MIN) is given back
    # as it is; the gravel photo's own light varies by more, and is levelled
    even_light = np.random.default_rng(0).uniform(-0.5, 0.5, (192, 192, 3)).astype(np.float32)
    (same,), same_facts = level_maps([even_light], [False])
    assert same_facts["moved"] == 0.0 and np.array_equal(same, even_light)
    assert level_maps([gravel], [False])[1]["moved"] >= LEVEL_MIN
    # a grey map with alpha: the grey is levelled as the colour map's tone is, the alpha is left as it is
    alpha = np.random.default_rng(1).choice([-1.0, 1.0], (192, 192, 1)).astype(np.float32)
    (grey_alpha,), _ = level_maps([np.dstack([lit[..., :1], alpha])], [False])
    assert np.array_equal(grey_alpha[..., 1:], alpha)
    assert ends(grey_alpha[..., :1]) < 0.06 and np.allclose(grey_alpha[..., :1], even[..., :1], atol=0.02)


def test_a_mend_of_an_unevenly_lit_photo_shows_a_step_of_tone_and_the_levelled_one_passes():
    gravel = _photo("gravel.png", 192)
    lit = _lit(gravel, 0.8, 1.2)
    field, _ = best_mend([lit], 3)
    verdict = judge([lit[field[..., 0], field[..., 1]]], [lit], [False], ["colour"])
    assert not verdict.passed
    tone = [s for s in verdict.seams if s.kind == "tone"]
    # the step where the photo's dark left edge meets its bright right edge: the mend's band, in the middle
    assert tone and tone[0].axis == "x" and abs(tone[0].position - 96) <= 24, verdict.seams
    field, _ = best_mend([gravel], 3)
    assert judge([gravel[field[..., 0], field[..., 1]]], [gravel], [False], ["colour"]).passed
    plain = check_cut([MapInput("colour", lit)], True)
    assert not plain.passes
    levelled = check_levelled([MapInput("colour", lit)])
    assert levelled is not None and levelled[0].passes and levelled[1]["moved"] > 0.15


def _slabs(size: int) -> np.ndarray:
    """Stone slabs of uneven lengths in courses, each its own shade of a real gravel photo's grain, with joints one
    texel wide (as a marble floor's photo at 512 px shows them)."""
    rng = np.random.default_rng(0)
    out = _photo("gravel.png", size) * 0.25 + 0.3
    for y0 in range(0, size, 96):
        x0 = -int(rng.integers(0, 120))
        while x0 < size:
            width = int(rng.integers(100, 180))
            out[y0: y0 + 96, max(0, x0): x0 + width] += rng.uniform(-0.08, 0.08)
            if x0 >= 0:
                out[y0: y0 + 96, x0] = -0.4
            x0 += width
        out[y0] = -0.4
    return out.astype(np.float32)


def test_joints_one_texel_wide_are_long_lines_and_grain_is_not():
    for size in (256, 512):
        slabs = _slabs(size)
        assert line_mask([slabs], line_sigma((round(0.06 * size),) * 2)) is None  # the broad mask erases them
        assert has_thin_lines([slabs]), thin_line_share([slabs])
    for name in ("gravel.png", "grass.png"):
        assert thin_line_share([_photo(name, 384)]) < 0.2
    # a mend of the slabs is one of a texture with lines: it passes only where its joins hide
    maps = [MapInput("colour", _slabs(256))]
    lattice = find_lattice([m.pixels for m in maps])
    made = {kind: figures for kind, _, figures in cut_candidates(maps, lattice, 256, 256, {}, 0)}
    assert made["mend"]["lines"] is True


def _lit_scene(folder: Path) -> Path:
    """A ground plane whose UsdPreviewSurface reads a gravel photo lit unevenly (8-bit sRGB PNG)."""
    lit = _lit(_photo("gravel.png", 192), 0.75, 1.25)
    return ground_scene(folder, (lit + 1) / 2, "gravel_lit.png", "Gravel")


def test_process_levels_an_unevenly_lit_photo_records_it_and_check_agrees(tmp_path, capsys, model_cache):
    scene = _lit_scene(tmp_path)
    code = main(["process", str(scene), "--preset", "tiny", "--cache-dir", str(model_cache), "--json",
                 "--report", str(tmp_path / "report.html")])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    assert stack["status"] == "passed" and code == 0, stack.get("message")
    facts = stack["resampled"]["levelled"]
    assert facts["moved"] > 0.15
    assert stack["resampled"]["gan"]["layout"] in ("mend", "quilt", "window")  # a cut: no GAN trained
    layer = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    prim = layer.GetPrimAtPath("/World/Looks/Gravel/diffuseColorTex")
    assert prim.GetAttribute("seamless:levelled").Get() == pytest.approx(facts["moved"])
    assert "light was levelled before the cut" in (tmp_path / "report.html").read_text()
    tile_path = Path(UsdShade.Shader(prim).GetInput("file").Get().resolvedPath)
    assert tile_path.is_file() and (tmp_path / "gravel_lit.png").is_file()  # the source is left as it was
    # check judges the tile against its source levelled the same way: one answer
    main(["check", str(tmp_path / "scene.seamless.usda"), "--json"])
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert item["verdict"]["passed"]
    # the cached tile written to another folder is judged against the levelled source again: passed again
    code = main(["process", str(scene), "--preset", "tiny", "--cache-dir", str(model_cache), "--json",
                 "--output-dir", str(tmp_path / "again"), "-o", str(tmp_path / "again.usda")])
    [again] = json.loads(capsys.readouterr().out)["stacks"]
    assert code == 0 and again["status"] == "passed" and again["resampled"]["levelled"] == facts
