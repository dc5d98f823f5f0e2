"""End to end: ``seamless-usd process`` on real sample scenes (tiny preset, shared cache)."""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import re
import shutil
from pathlib import Path

import jsonschema
import OpenImageIO as oiio
import pytest
from runchecks import assert_all_written as _assert_all_written
from pxr import Sdf, Usd, UsdShade

from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _hashes(root: Path) -> dict[str, str]:
    return {
        str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(root.rglob("*"))
        if p.is_file()
    }


@pytest.fixture()
def assets(tmp_path) -> Path:
    dst = tmp_path / "assets"
    shutil.copytree(SAMPLES, dst)
    return dst


def _process(*args: str, cache: Path) -> int:
    return main(["process", "--preset", "tiny", "--cache-dir", str(cache), *args])




def _texture_files(stage: Usd.Stage) -> dict[str, Path]:
    """Texture prim path -> resolved file of its ``inputs:file``."""
    out = {}
    for prim in stage.Traverse():
        shader = UsdShade.Shader(prim)
        if not shader or shader.GetIdAttr().Get() != "UsdUVTexture":
            continue
        inp = shader.GetInput("file")
        sources = inp.GetValueProducingAttributes()
        attr = sources[0] if sources else inp.GetAttr()
        value = attr.Get()
        out[str(prim.GetPath())] = Path(value.resolvedPath) if value and value.resolvedPath else None
    return out


@pytest.fixture(scope="module")
def processed(tmp_path_factory, model_cache):
    """The brick sample processed into a new layer, with an HTML + JSON report, once for the module.
    Tests that change what it wrote work on a copy (:func:`processed_copy`)."""
    assets = tmp_path_factory.mktemp("processed") / "assets"
    shutil.copytree(SAMPLES, assets)
    scene = assets / "brick" / "scene.usda"
    before = _hashes(assets)
    report = assets / "out" / "report.html"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = _process(str(scene), "--report", str(report), "--json", cache=model_cache)
    payload = json.loads(out.getvalue())
    return dict(assets=assets, scene=scene, before=before, code=code, report=report, payload=payload)


@pytest.fixture()
def processed_copy(processed, tmp_path):
    """A private copy of the processed assets (the relative asset paths still resolve)."""
    assets = tmp_path / "assets"
    shutil.copytree(processed["assets"], assets)
    return dict(processed, assets=assets, scene=assets / "brick" / "scene.usda")


def test_new_layer_edits_resolve_to_written_tiles(processed):
    payload = processed["payload"]
    assert processed["code"] == payload["exit_code"]
    assert not [f for f in payload["findings"] if f["code"] == "coarser-tile"]  # at the source's texel density
    _assert_all_written(processed["code"], payload)
    [stack] = payload["stacks"]
    assert stack["status"] in ("passed", "not-passed")
    assert (processed["code"] == 0) == (stack["status"] == "passed")
    layer = processed["scene"].with_name("scene.seamless.usda")
    assert str(layer) in payload["layers_written"]
    stage = Usd.Stage.Open(str(layer))
    assert stage is not None
    files = _texture_files(stage)
    assert set(files) == {"/World/Looks/Brick/Albedo", "/World/Looks/Brick/Normal", "/World/Looks/Brick/Roughness"}
    tile_h, tile_w = stack["tile_size"]
    for prim_path, path in files.items():
        assert path is not None and path.is_file(), prim_path
        assert path.parent == processed["scene"].parent / "tileable"
        spec = oiio.ImageInput.open(str(path)).spec()
        assert (spec.height, spec.width) == (tile_h, tile_w)
        assert spec.format == oiio.UINT8 and path.suffix == ".png"  # 8-bit sources stay 8-bit PNG
        texture = UsdShade.Shader(stage.GetPrimAtPath(prim_path))
        assert texture.GetInput("wrapS").Get() == "repeat"
        assert texture.GetInput("wrapT").Get() == "repeat"
    # channel layout kept: roughness stays one channel, albedo and normal three
    rough = oiio.ImageInput.open(str(files["/World/Looks/Brick/Roughness"])).spec()
    assert rough.nchannels == 1


def test_uv_transform_keeps_texel_scale(processed):
    [stack] = processed["payload"]["stacks"]
    W, H = stack["resampled"]["working_size"]  # the texture's pixel grid, which spans the UV unit square
    tile_h, tile_w = stack["tile_size"]
    gan = stack["resampled"]["gan"]
    # the bundled brick repeats on a lattice: the tile is cut to whole periods of it, smaller than the texture
    assert gan["layout"] == "lattice", gan
    assert [tile_h, tile_w] == gan["lattice"]["tile"] and tile_h < H and tile_w < W
    for side, period in zip((tile_h, tile_w), gan["lattice"]["period_px"]):
        assert round(side / period) >= 1 and side / period == pytest.approx(round(side / period), abs=0.1)
    assert stack["uv_scale"] == pytest.approx([W / tile_w, H / tile_h])  # ... and the texel density is kept
    stage = Usd.Stage.Open(str(processed["scene"].with_name("scene.seamless.usda")))
    albedo = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/Brick/Albedo"))
    [src] = albedo.GetInput("st").GetConnectedSources()[0]
    transform = UsdShade.Shader(src.source.GetPrim())
    assert transform.GetIdAttr().Get() == "UsdTransform2d"
    assert tuple(transform.GetInput("scale").Get()) == pytest.approx(stack["uv_scale"])


def test_sources_are_untouched_and_report_is_valid(processed):
    after = _hashes(processed["assets"])
    for rel, digest in processed["before"].items():
        assert after[rel] == digest, f"{rel} was modified"
    jsonschema.validate(processed["payload"], json_schema("report"))
    on_disk = json.loads(processed["report"].with_suffix(".json").read_text())
    jsonschema.validate(on_disk, json_schema("report"))
    html = processed["report"].read_text()
    pictures = re.findall(r"data:image/(?:png|webp|jpeg);base64,", html)
    assert len(pictures) >= 6  # 3 maps x (source, tile)
    assert "Brick" in html
    # the brick's lattice cut passes before any training: the run details say no GAN was trained
    assert "SeamlessGAN not trained: the tile cut from the source passed as it was cut" in html
    [stack] = on_disk["stacks"]
    assert stack["resampled"]["gan"]["layout"] == "lattice" and stack["q"] == {} and stack["model_hash"] == ""
    for stack in on_disk["stacks"]:
        for m in stack["maps"]:  # what lies inside the tile: joins between copies and the structure figure
            assert m["metrics"]["structure"] is not None and 0 < m["metrics"]["coherence"] <= 1
            assert m["metrics"]["bad_joins"] is not None
            # the fidelity figures the report shows are the ones the status was decided on
            decided = stack["verdict"]["figures"][m["asset"]]
            assert {k: m["metrics"][k] for k in decided} == decided


def test_the_reports_figures_of_a_large_map_are_read_at_most_1024_px_a_side(monkeypatch):
    """Read at full resolution, the report's figures took about 40 s a 2K map and 8 minutes a 4K stack (the verdict,
    which decides the status, reads the maps at full resolution on its own)."""
    import numpy as np

    from seamless_usd import metrics
    from seamless_usd.pipeline import stackjob

    read: list[tuple[int, ...]] = []
    real = metrics.map_metrics

    def recording(tile, source=None, is_normal=False, **kwargs):
        read.append(tile.shape)
        return real(tile, source, is_normal, **kwargs)

    monkeypatch.setattr(metrics, "map_metrics", recording)
    rng = np.random.default_rng(0)
    source = rng.uniform(-1, 1, (2100, 1300, 3)).astype(np.float32)
    normal = source / np.linalg.norm(source, axis=-1, keepdims=True)
    figures = stackjob._report_figures(np.roll(normal, 700, axis=0), normal, True)
    assert set(figures) == {"metrics", "source_metrics"} and figures["metrics"]["ssim"] is not None
    assert read == [(525, 325, 3), (525, 325, 3)]


def test_second_run_on_the_output_is_clean(processed_copy, model_cache, capsys):
    """Processing the output again (forced: the tile is already tileable) makes the stack again from the source
    its tiles record, not from the tiles: the node gets the new tile (made with other settings, so named anew and
    the first left as it was) and the one SeamlessUV node its UV scale against that source (not one composed with
    the first), instead of another node being added."""
    layer = processed_copy["scene"].with_name("scene.seamless.usda")
    first_stage = Usd.Stage.Open(str(layer))
    first_albedo = UsdShade.Shader(first_stage.GetPrimAtPath("/World/Looks/Brick/Albedo"))
    first_file = first_albedo.GetInput("file").Get().resolvedPath
    del first_stage
    before = layer.read_bytes()
    code = _process(str(layer), "--in-place", "--force", "--max-size", "128", "--refine", "off", "--json", cache=model_cache)
    payload = json.loads(capsys.readouterr().out)
    _assert_all_written(code, payload)
    [stack] = payload["stacks"]
    assert layer.with_name("scene.seamless.usda.bak").read_bytes() == before
    assert layer.read_bytes() != before, "the re-run wrote its edits"
    stage = Usd.Stage.Open(str(layer))
    transforms = [
        p for p in stage.Traverse()
        if UsdShade.Shader(p) and UsdShade.Shader(p).GetIdAttr().Get() == "UsdTransform2d"
    ]
    assert len(transforms) == 1, [str(p.GetPath()) for p in transforms]
    scale = UsdShade.Shader(transforms[0]).GetInput("scale").Get()
    assert tuple(scale) == pytest.approx(stack["uv_scale"], rel=1e-5)
    assert {Path(m["asset"]).name for m in stack["maps"]} == {"brick_albedo.png", "brick_normal.png", "brick_roughness.png"}
    albedo = stage.GetPrimAtPath("/World/Looks/Brick/Albedo")
    new_file = UsdShade.Shader(albedo).GetInput("file").Get().resolvedPath
    # the same stack (its id kept), made with other settings (--refine off): a tile of its own, the first one kept
    assert Path(new_file).name.split(".")[1] == Path(first_file).name.split(".")[1] and new_file != first_file
    assert Path(new_file).is_file() and Path(first_file).is_file()
    source = albedo.GetAttribute("seamless:sourceAsset").Get()
    assert Path(source.resolvedPath).name == "brick_albedo.png"  # provenance keeps the original


def test_an_internal_error_exits_3_and_names_a_log_file(assets, model_cache, capsys, monkeypatch):
    from seamless_usd.pipeline import process as pipeline

    def broken(*args, **kwargs):
        raise RuntimeError("planted fault")

    monkeypatch.setattr(pipeline, "finish_run", broken)
    code = _process(str(assets / "brick" / "scene.usda"), "--dry-run", cache=model_cache)
    err = capsys.readouterr().err
    assert code == 3
    assert "Traceback" not in err and "internal error" in err
    [log] = re.findall(r"(\S+seamless-usd-crash-\S+\.log)", err)
    assert "planted fault" in Path(log).read_text()
    Path(log).unlink()


def test_in_place_keeps_backups_equal_to_the_originals(assets, model_cache, capsys):
    scene = assets / "brick" / "scene.usda"
    original = scene.read_bytes()
    textures = _hashes(assets / "textures")
    code = _process(str(scene), "--in-place", "--json", cache=model_cache)
    _assert_all_written(code, json.loads(capsys.readouterr().out))
    assert scene.with_name("scene.usda.bak").read_bytes() == original
    assert scene.read_bytes() != original
    assert _hashes(assets / "textures") == textures
    stage = Usd.Stage.Open(str(scene))
    for path in _texture_files(stage).values():
        assert path.is_file() and path.parent.name == "tileable"


def test_in_place_leaves_a_layer_marked_read_only_alone(assets, model_cache, capsys):
    """A layer with no write permission is read-only on purpose, also to a super-user who could replace it."""
    scene = assets / "brick" / "scene.usda"
    original = scene.read_bytes()
    scene.chmod(0o444)
    try:
        planned = _process(str(scene), "--in-place", "--dry-run", "--json", cache=model_cache)  # says so too
        [plan] = json.loads(capsys.readouterr().out)["stacks"]
        code = _process(str(scene), "--in-place", "--json", cache=model_cache)
    finally:
        scene.chmod(0o644)
    payload = json.loads(capsys.readouterr().out)
    assert code == 1 and scene.read_bytes() == original and not scene.with_name("scene.usda.bak").exists()
    [stack] = payload["stacks"]
    assert stack["status"] == "failed" and "marked read-only" in stack["message"]
    assert planned == 1 and plan["status"] == "failed" and plan["message"] == stack["message"]
    assert not (scene.parent / "tileable").exists()  # no tile that no layer would reference


def test_dry_run_writes_nothing(assets, tmp_path, capsys):
    before = _hashes(assets)
    cache = tmp_path / "cache"  # nor in the cache: the triage's figures are read from it, not added to it
    code = _process(str(assets / "brick" / "scene.usda"), "--dry-run", "--json", cache=cache)
    payload = json.loads(capsys.readouterr().out)
    assert code == 0
    assert _hashes(assets) == before
    assert not [p for p in cache.rglob("*") if p.is_file()]
    assert [s["status"] for s in payload["stacks"]] == ["planned"]
    assert payload["plan"], "a dry run lists the edits it would make"


def test_unreadable_input_exits_2_and_names_the_file(assets, model_cache, capsys):
    broken = assets / "broken.usda"
    broken.write_text("#usda 1.0\ndef Xform \"A\" {\n")
    code = _process(str(broken), str(assets / "missing.usda"), cache=model_cache)
    err = capsys.readouterr().err
    assert code == 2
    assert "broken.usda" in err and "missing.usda" in err
    assert "Traceback" not in err
    _process(str(broken), "--json", cache=model_cache)  # the finding names the file once, as its place
    [finding] = json.loads(capsys.readouterr().out)["findings"]
    assert finding["where"] == "@" + str(broken) + "@" and "broken.usda" not in finding["message"], finding


def test_a_broken_texture_fails_its_stack_and_the_rest_is_written(assets, model_cache, capsys):
    (assets / "textures" / "wood_roughness.png").write_bytes(b"\x89PNG\r\n\x1a\n not really a png")
    brick, wood = assets / "brick" / "scene.usda", assets / "referenced" / "scene.usda"
    code = _process(str(brick), str(wood), "--json", cache=model_cache)
    payload = json.loads(capsys.readouterr().out)
    assert code == 1
    by_source = {Path(s["source"]).parent.name: s for s in payload["stacks"]}
    assert by_source["referenced"]["status"] == "failed"
    assert "wood_roughness.png" in by_source["referenced"]["message"]
    assert by_source["brick"]["status"] in ("passed", "not-passed")
    assert brick.with_name("scene.seamless.usda").is_file()


def test_every_sample_asset_processes(assets, model_cache, capsys):
    layers = re.compile(r"_(geo|mtl|look|payload)\.usda$")  # layers of the structured assets: their roots only
    scenes = sorted(str(p) for p in assets.rglob("*.usda") if "library" not in p.parts and not layers.search(p.name)) + sorted(
        str(p) for p in assets.rglob("*.mtlx")
    )
    # the intents and statuses of every sample: plumbing, small and without refinement is enough
    code = _process(*scenes, "--max-size", "128", "--refine", "off", "--json", cache=model_cache)
    payload = json.loads(capsys.readouterr().out)
    _assert_all_written(code, payload)
    assert payload["stacks"], "the samples have stacks"
    by_material = {}
    for s in payload["stacks"]:
        by_material.setdefault(s["material"], set()).add((s["intent"], s["status"]))
    # the structured samples: atlases and the decal are left alone, the tiling ones processed
    assert by_material["</Prop/Materials/M_body>"] == {("uv-atlas", "left-alone")}
    assert by_material["</Prop/Materials/M_label>"] == {("other", "left-alone")}
    assert by_material["</Piece/Materials/M_piece>"] == {("uv-atlas", "left-alone")}
    assert by_material["<M_wood_tiled>"] == {("already-tileable", "left-alone")}
    processed = [s for s in payload["stacks"] if s["status"] != "left-alone"]
    assert processed and all(s["intent"] == "tiling" for s in processed)
    # read at 128 px, each tile is coarser on the asset than its source, and the run says so (once per stack made;
    # a duplicate reuses its first stack's tile)
    coarser = [f["material"] for f in payload["findings"] if f["code"] == "coarser-tile"]
    bigger = [s["material"] for s in processed if s["origin"] != "duplicate"
              and max(max(m["original_size"]) for m in s["resampled"]["maps"]) > 135]
    assert bigger and sorted(coarser) == sorted(bigger), (coarser, bigger)
    jsonschema.validate(payload, json_schema("report"))


def test_process_stage_on_an_open_in_memory_stage(assets, model_cache, tmp_path):
    import seamless_usd

    stage = Usd.Stage.Open(str(assets / "brick" / "scene.usda"))
    session = stage.GetSessionLayer()
    stage.SetEditTarget(Usd.EditTarget(session))
    options = seamless_usd.Options(preset="tiny", cache_dir=model_cache, output_dir=tmp_path / "tiles")
    report = seamless_usd.process_stage(stage, options)
    _assert_all_written(report.exit_code, report.to_dict())
    assert not (assets / "brick" / "scene.seamless.usda").exists()
    albedo = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/Brick/Albedo"))
    value = albedo.GetInput("file").Get()
    assert Path(value.resolvedPath).parent == tmp_path / "tiles"
    assert session.GetPrimAtPath("/World/Looks/Brick/Albedo") is not None
    assert Sdf.Layer.FindOrOpen(str(assets / "brick" / "scene.usda")).dirty is False


def test_dry_run_of_in_place_lists_source_layer_edits_and_writes_nothing(assets, model_cache, capsys):
    before = _hashes(assets)
    code = _process(str(assets / "brick" / "scene.usda"), "--dry-run", "--in-place", "--json", cache=model_cache)
    payload = json.loads(capsys.readouterr().out)
    assert code == 0
    assert _hashes(assets) == before
    assert payload["options"]["plan_mode"] == "in-place"
    assert any("scene.usda" in line and "seamless" not in line.split(" in ")[-1] for line in payload["plan"])


def test_max_pixels_refuses_large_images_before_decoding(assets, model_cache, capsys):
    code = _process(str(assets / "brick" / "scene.usda"), "--max-pixels", "10000", "--json", cache=model_cache)
    payload = json.loads(capsys.readouterr().out)
    assert code == 1
    [stack] = payload["stacks"]
    assert stack["status"] == "failed"
    assert "brick_" in stack["message"] and "10000" in stack["message"].replace(",", "")


@pytest.mark.parametrize("device", ["gpu", "mps"] + ([] if __import__("torch").cuda.is_available() else ["cuda", "cuda:0"]))
def test_an_unusable_device_is_a_usage_error_before_any_work(assets, model_cache, capsys, device):
    code = _process(str(assets / "brick" / "scene.usda"), "--device", device, cache=model_cache)
    err = capsys.readouterr().err
    assert code == 2 and "--device" in err and "Traceback" not in err
    assert not (assets / "brick" / "tileable").exists()


def test_a_wood_whose_joins_cannot_hide_is_told_what_to_do(assets, model_cache, capsys):
    """The bundled wood neither repeats nor continues itself: it is written, not passed, and the message (the
    report's, the table's) says why its joins show and what to do, beside the seams the verdict names. At
    192 px: at its full 256 px the wood's mend passes once its light is levelled."""
    code = _process(str(assets / "library" / "materials" / "wood.usda"), "--json", "--max-size", "192",
                    cache=model_cache)
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert code == 1 and stack["status"] == "not-passed"
    assert stack["message"].startswith("seam in ")
    assert "neither repeats nor continues itself" in stack["message"] and "a larger photo of the same surface" in stack["message"]
    assert "by hand" not in stack["message"]


def test_paths_and_messages_with_brackets_are_printed_as_they_are(tmp_path, capsys):
    """A folder named ``lib[v2]`` (brackets are markup to the console library): the table and the error lines name
    the real path, not one with ``[v2]`` dropped."""
    lib = tmp_path / "lib[v2]"
    shutil.copytree(SAMPLES / "textures", lib / "tex[v2]")
    (lib / "brick").mkdir()
    scene = (SAMPLES / "brick" / "scene.usda").read_text().replace("../textures/", "../tex[v2]/")
    (lib / "brick" / "scene.usda").write_text(scene)
    (lib / "tex[v2]" / "brick_roughness.png").write_bytes(b"\x89PNG\r\n\x1a\n not really a png")
    code = _process(str(lib / "brick" / "scene.usda"), "--dry-run", cache=tmp_path / "cache")
    err = "".join(capsys.readouterr().err.split())  # the table folds long cells: compared without spaces
    assert code == 1 and "@../tex[v2]/brick_roughness.png@" in err, err[-2000:]


def test_an_output_layer_usd_cannot_write_is_refused_before_any_work(assets, tmp_path, capsys):
    scene = assets / "brick" / "scene.usda"
    for name in ("over.usdz", "over.txt"):
        assert _process(str(scene), "-o", str(tmp_path / name), cache=tmp_path / "cache") == 2
        assert ".usda, .usdc or .usd" in capsys.readouterr().err
    assert not (scene.parent / "tileable").exists() and not list(tmp_path.glob("over.*"))


def test_an_output_layer_that_is_the_input_or_a_file_of_the_users_is_refused_before_any_work(assets, tmp_path, capsys):
    """-o naming the input, another stage, or a document the scene references: refused with exit 2 before any tile
    is made (such a file was replaced without a backup, or the run failed after its work); a layer this tool wrote
    is written again."""
    scene = assets / "brick" / "scene.usda"
    for other in (scene, assets / "chess" / "piece.usda", assets / "mtlx" / "tiled.mtlx"):
        before = other.read_bytes()
        extra = [str(assets / "mtlx" / "prefixed.mtlx")] if other.suffix == ".mtlx" else [str(scene)]
        assert _process(*extra, "-o", str(other), cache=tmp_path / "cache") == 2
        err = capsys.readouterr().err
        assert "-o/--output-layer" in err and ("is the input itself" in err or "is not replaced" in err), err
        assert other.read_bytes() == before
    assert not (assets / "brick" / "tileable").exists() and not (assets / "mtlx" / "tileable").exists()
    out = tmp_path / "over.usda"
    assert _process(str(scene), "--max-size", "128", "-o", str(out), cache=tmp_path / "cache") == 0
    assert _process(str(scene), "--max-size", "128", "-o", str(out), cache=tmp_path / "cache") == 0  # ours: again
    # the new layer this tool wrote over another stage: that shot's overrides were replaced without a word
    theirs = assets / "chess" / "piece.usda"
    assert _process(str(theirs), "--max-size", "128", "-o", str(out), cache=tmp_path / "cache") == 2
    assert "is the new layer this tool wrote over another stage" in capsys.readouterr().err
    assert "brick/scene.usda@" in out.read_text()


def test_a_file_of_the_users_at_the_new_layers_default_path_is_never_replaced(assets, tmp_path, capsys):
    """``process scene.usda`` replaced a ``scene.seamless.usda`` the user had written (a sublayer and a note of their
    own) without a backup or a word, where ``-o`` naming the same file is refused: its stacks fail, naming it."""
    scene = assets / "brick" / "scene.usda"
    theirs = scene.with_name("scene.seamless.usda")
    theirs.write_text('#usda 1.0\n(\n    subLayers = [@./scene.usda@]\n)\n\nover "World"\n{\n'
                      '    custom string userNote = "hand work"\n}\n')
    before = theirs.read_bytes()
    assert _process(str(scene), "--json", cache=tmp_path / "cache") == 1
    [row] = json.loads(capsys.readouterr().out)["stacks"]
    assert row["status"] == "failed" and "is not a layer or document this tool wrote" in row["message"]
    assert theirs.read_bytes() == before and not (scene.parent / "tileable").exists()


def test_a_tile_painted_over_since_it_was_written_is_never_replaced(assets, tmp_path, capsys):
    """A tile a TD touched up by hand (a square painted over, the file's record kept) went back to the cached tile on
    the next run, without a word: its stack now fails, naming it, and the painted file stays as it is."""
    scene = assets / "brick" / "scene.usda"
    assert _process(str(scene), "--max-size", "128", cache=tmp_path / "cache") == 0
    capsys.readouterr()
    [tile] = sorted((scene.parent / "tileable").glob("brick_albedo.*.tile.png"))
    painted = oiio.ImageBuf(str(tile))
    pixels = painted.get_pixels(oiio.UINT8)
    pixels[4:20, 4:20] = 0
    painted.set_pixels(painted.roi, pixels)
    assert painted.write(str(tile))
    before = tile.read_bytes()
    assert _process(str(scene), "--max-size", "128", "--json", cache=tmp_path / "cache") == 1
    [row] = json.loads(capsys.readouterr().out)["stacks"]
    assert row["status"] == "failed" and "was changed since this tool wrote it" in row["message"]
    assert tile.name in row["message"] and tile.read_bytes() == before
