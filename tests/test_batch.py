"""Batch fixing of a material library: folders, de-duplication, cache, resume, executors."""
from __future__ import annotations

import json
import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest
from fswatch import wait_until
from runchecks import PLUMBING, assert_all_written as _assert_all_written
from pxr import Usd, UsdShade

from seamless_usd.errors import UsageError
from seamless_usd.pipeline.executors import (
    DaskExecutor,
    InProcessExecutor,
    ProcessPoolExecutor,
    make_executor,
)
from seamless_usd.pipeline.inputs import expand_inputs
from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"

TWO_MATERIALS = """#usda 1.0
(
    defaultPrim = "World"
)

def Xform "World"
{
    def Scope "Looks"
    {
        def Material "Brick"
        {
            token outputs:surface.connect = </World/Looks/Brick/Surface.outputs:surface>
            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/Brick/Albedo.outputs:rgb>
                token outputs:surface
            }
            def Shader "St"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }
            def Shader "Albedo"
            {
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/brick_albedo.png@
                float2 inputs:st.connect = </World/Looks/Brick/St.outputs:result>
                float3 outputs:rgb
            }
        }
        def Material "Wood"
        {
            token outputs:surface.connect = </World/Looks/Wood/Surface.outputs:surface>
            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </World/Looks/Wood/Albedo.outputs:rgb>
                token outputs:surface
            }
            def Shader "St"
            {
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }
            def Shader "Albedo"
            {
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @../textures/wood_color.png@
                float2 inputs:st.connect = </World/Looks/Wood/St.outputs:result>
                float3 outputs:rgb
            }
        }
    }
}
"""


@pytest.fixture()
def cache(model_cache) -> Path:
    """The session's model cache (tests that count trained stacks use a cold folder of their own)."""
    return model_cache


def _library(root: Path, copies: int = 3) -> Path:
    """A library: the brick scene in ``copies`` folders (one stack, duplicated) plus a two-material layer."""
    lib = root / "library"
    shutil.copytree(SAMPLES / "textures", lib / "textures")
    for n in range(copies):
        (lib / f"brick{n}").mkdir()
        shutil.copy(SAMPLES / "brick" / "scene.usda", lib / f"brick{n}" / "scene.usda")
    (lib / "looks").mkdir()
    (lib / "looks" / "two.usda").write_text(TWO_MATERIALS)
    return lib


RUN = (*PLUMBING, "--max-size", "128")


def _run(*args: str, capsys) -> tuple[int, dict]:
    code = main(["process", *RUN, "--json", *args])
    return code, json.loads(capsys.readouterr().out)


def _tiles(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.rglob("*.tile.*"))}


@pytest.fixture(scope="module")
def two_stacks(tmp_path_factory) -> dict:
    """``looks/two.usda`` (brick and wood albedo) processed in this process on a cold cache, once for the
    module: the reference tiles and statuses the worker, resumed and warm runs must reproduce, and a
    cache holding both stacks. Tests copy what they change."""
    import contextlib
    import io

    root = tmp_path_factory.mktemp("two-stacks")
    lib, cache = _library(root, copies=0), root / "cache"
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        code = main(["process", *RUN, "--json", "--cache-dir", str(cache), str(lib / "looks" / "two.usda")])
    payload = json.loads(out.getvalue())
    _assert_all_written(code, payload)
    assert payload["counts"]["trained"] == 2 and len(payload["stacks"]) == 2
    tiles = _tiles(lib / "looks" / "tileable")
    assert len(tiles) == 2, tiles.keys()
    statuses = {s["material"]: s["status"] for s in payload["stacks"]}
    return dict(lib=lib, cache=cache, tiles=tiles, statuses=statuses, code=code)




def test_expand_inputs_walks_folders_and_globs_and_leaves_outputs_out(tmp_path):
    lib = _library(tmp_path, copies=2)
    (lib / "brick0" / "scene.seamless.usda").write_text("#usda 1.0\n")
    (lib / "brick0" / "scene.usda.bak").write_text("#usda 1.0\n")
    found = [p.relative_to(lib).as_posix() for p in expand_inputs([lib])]
    assert found == ["brick0/scene.usda", "brick1/scene.usda", "looks/two.usda"]
    globbed = [p.relative_to(lib).as_posix() for p in expand_inputs([str(lib / "brick*" / "*.usda")])]
    assert globbed == ["brick0/scene.usda", "brick1/scene.usda"]
    assert expand_inputs([lib / "brick0" / "scene.usda", lib / "brick0" / "scene.usda"]) == [lib / "brick0" / "scene.usda"]
    # a pattern that matches nothing is given back as it is, for the caller to report as an input it cannot read
    assert expand_inputs([str(lib / "nothing*" / "*.usda")]) == [lib / "nothing*" / "*.usda"]


def test_a_folder_walk_takes_the_stages_and_not_the_layers_they_compose(tmp_path, capsys):
    """A payload, a look layer, a geometry layer and the .mtlx document a stage composes are processed through it,
    not as scenes of their own: alone they bind no geometry, and their UV atlas would be tiled into the asset."""
    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("chess", "prop", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    assert [p.relative_to(tmp_path).as_posix() for p in expand_inputs([tmp_path])] == ["chess/piece.usda",
                                                                                     "prop/prop.usda"]
    assert main(["process", str(tmp_path), "--dry-run", "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    assert {Path(s).name for s in payload["sources"]} == {"piece.usda", "prop.usda"}
    atlases = [s for s in payload["stacks"] if s["material"] in ("</Piece/Materials/M_piece>", "</Prop/Materials/M_body>")]
    assert atlases and all(s["status"] == "left-alone" for s in atlases)


def test_a_broken_layer_another_stage_references_is_still_reported_unreadable(tmp_path, capsys):
    """A layer that does not parse was reported unreadable (exit 2) alone in the folder, but passed over once another
    stage referenced it (taken for a layer that stage composes), and the run then exited 0 on the stage's warning."""
    lib = _library(tmp_path, copies=1)
    (lib / "broken").mkdir()
    (lib / "broken" / "bad.usda").write_text('#usda 1.0\ndef Xform "World" {\n  this is not usd\n')
    (lib / "shot").mkdir()
    (lib / "shot" / "shot.usda").write_text('#usda 1.0\ndef Xform "World" (\n    references = @../broken/bad.usda@\n)\n{\n}\n')
    assert "broken/bad.usda" in [p.relative_to(lib).as_posix() for p in expand_inputs([lib])]
    code = main(["process", str(lib), "--dry-run", "--json"])
    payload = json.loads(capsys.readouterr().out)
    assert code == 2 and any(Path(u).name == "bad.usda" for u in payload["unreadable"]), payload["unreadable"]


def test_make_executor_validates_names():
    assert isinstance(make_executor(None), InProcessExecutor)
    assert isinstance(make_executor("inprocess", 1), InProcessExecutor)
    pool = make_executor(None, 2)
    assert isinstance(pool, ProcessPoolExecutor) and pool.workers == 2
    local = make_executor("local:3")
    assert isinstance(local, DaskExecutor) and (local.address, local.workers) == ("local", 3)
    remote = make_executor("tcp://127.0.0.1:8786")
    assert isinstance(remote, DaskExecutor) and remote.address == "tcp://127.0.0.1:8786"
    expected = {"local:x": "whole number", "local:0": "at least 1", "ssh://farm": "local:N, tcp://host:port",
                "kubernetes": "unknown scheduler", "localhost:8786": "tcp://localhost:8786"}
    for bad, why in expected.items():
        with pytest.raises(UsageError, match=re.escape(why)):
            make_executor(bad)
    with pytest.raises(UsageError, match="at least 1"):
        make_executor(None, 0)
    # --jobs beside --scheduler: accepted where they agree, refused where each would set the workers differently
    assert make_executor("local", 2).workers == 2 and make_executor("local:2", 2).workers == 2
    with pytest.raises(UsageError, match=re.escape("--jobs 3 and --scheduler local:2 each set the workers")):
        make_executor("local:2", 3)
    with pytest.raises(UsageError, match="leave --jobs out"):
        make_executor("tcp://127.0.0.1:8786", 2)


def test_duplicated_stacks_train_once_and_a_warm_cache_trains_nothing(tmp_path, cache, capsys, monkeypatch):
    lib = _library(tmp_path)
    report = tmp_path / "out" / "library.html"
    _, planned = _run(str(lib), "--dry-run", "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    code, first = _run(str(lib), "--cache-dir", str(tmp_path / "cold"), "--report", str(report), capsys=capsys)
    _assert_all_written(code, first)

    def outputs(payload):
        return {(s["source"], s["id"]): [m.get("output") for m in s["maps"]] for s in payload["stacks"]}

    assert outputs(planned) == outputs(first)  # the dry run plans the very files the run writes
    assert all(line.startswith("make tiles of") for line in planned["plan"] if "tiles" in line)
    # after the run, a dry run with its cache plans what the run would do: write the cached tiles, at their scale
    again_code, again = _run(str(lib), "--dry-run", "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    assert again_code == code, (again_code, code)  # what the run says, where the cache knows it
    made = {(s["source"], s["id"]): s for s in first["stacks"]}
    for s in again["stacks"]:
        assert s["status"] == "planned" and s["uv_scale"] == made[(s["source"], s["id"])]["uv_scale"]
        assert s["origin"] == "cache" and s["message"].startswith("from the cache: ")
    fresh = [s for s in again["stacks"] if not s["duplicate_of"]]
    # every tile is on disk as the run wrote it, so the run keeps them (writes nothing): the plan says so
    kept = [line for line in again["plan"] if line.startswith("keep the tiles an earlier run wrote")]
    assert len(kept) == len(fresh) and not any("from the cache" in line for line in again["plan"]), again["plan"]
    assert not any(line.startswith("make tiles of") for line in again["plan"])
    assert not any("provenance" in line for line in again["plan"])  # the run's edits are there already
    # one tile gone: that stack's tiles are written again from the cache and judged again
    edited = Path(first["stacks"][0]["maps"][0]["output"])
    kept_bytes = edited.read_bytes()
    edited.unlink()
    _, touched = _run(str(lib), "--dry-run", "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    rewritten = [line for line in touched["plan"] if "from the cache" in line]
    assert len(rewritten) == 1 and "judged again once written" in rewritten[0], touched["plan"]
    assert len([line for line in touched["plan"] if line.startswith("keep the tiles")]) == len(fresh) - 1
    # one tile edited by hand: the run leaves it as it is and fails that stack, and the dry run says so
    edited.write_bytes(kept_bytes + b"\0")
    touched_code, touched = _run(str(lib), "--dry-run", "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    [failed] = [s for s in touched["stacks"] if s["status"] == "failed"]
    assert touched_code == 1 and "was changed since this tool wrote it" in failed["message"]
    assert len([line for line in touched["plan"] if line.startswith("keep the tiles")]) == len(fresh) - 1
    edited.write_bytes(kept_bytes)  # as the run wrote it: the runs below find the library as it was
    # a copy of the library (another folder, the same cache): its tiles are written anew and judged again, and the
    # verdict they got when written before is known, so the dry run's exit code and words are the run's
    shutil.copytree(lib, tmp_path / "copy", ignore=shutil.ignore_patterns("tileable", "*.seamless.usda"))
    copy_code, copied = _run(str(tmp_path / "copy"), "--dry-run", "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    assert copy_code == code, (copy_code, code)
    for s in copied["stacks"]:
        if not s["duplicate_of"]:
            assert s["verdict"]["passed"] == made[(s["source"].replace("/copy/", "/library/"), s["id"])]["verdict"]["passed"]
    anew = [line for line in copied["plan"] if "from the cache" in line]
    assert len(anew) == len(fresh) and all("written into another folder before, they were" in x for x in anew), anew
    # an entry of another shape is planned as new, as the run makes it again
    shutil.copytree(tmp_path / "cold", tmp_path / "broken")
    for manifest in (tmp_path / "broken").glob("??/*/manifest.json"):
        manifest.write_text(json.dumps({"files": {}, "meta": {"uv_scale": [1, 1], "crop_size": [1, 1],
                                                             "straightened": 5}}))
    _, broken = _run(str(lib), "--dry-run", "--cache-dir", str(tmp_path / "broken"), capsys=capsys)
    assert all(line.startswith("make tiles of") for line in broken["plan"] if "tiles" in line)
    jsonschema.validate(first, json_schema("report"))
    assert len(first["sources"]) == 4
    # brick x3 (one unique stack) + brick and wood albedo in two.usda: the brick albedo alone is another
    # stack (one map, not three), so three unique stacks train.
    assert first["counts"]["trained"] == 3
    # two stacks reuse a result: 'reused' where it passed, 'not-passed' (naming why) where it did not
    duplicates = [s for s in first["stacks"] if s["origin"] == "duplicate"]
    assert len(duplicates) == 2 and all(s["duplicate_of"] for s in duplicates)
    assert all((s["status"] == "reused") == s["verdict"]["passed"] for s in duplicates)
    assert all("its result is reused" in s["message"] for s in duplicates)
    for n in range(3):  # every file gets its own outputs and edits
        layer = lib / f"brick{n}" / "scene.seamless.usda"
        stage = Usd.Stage.Open(str(layer))
        tex = UsdShade.Shader(stage.GetPrimAtPath("/World/Looks/Brick/Albedo"))
        resolved = Path(tex.GetInput("file").Get().resolvedPath)
        assert resolved.parent == lib / f"brick{n}" / "tileable" and resolved.is_file()
    index = report.read_text()
    linked = set(re.findall(r'href="library\.files/([^"#]+\.html)', index))
    pages = sorted((report.parent / "library.files").glob("*.html"))
    assert len(pages) == 4 and {page.name for page in pages} == linked  # one page per file, each linked
    assert all('href="../library.html"' in page.read_text(encoding="utf-8") for page in pages)  # and back
    assert "Layers and documents written (4)" in index and all(Path(p).name in index for p in first["layers_written"])
    assert index.index("<h2>Files</h2>") < index.index('class="cards"')  # the files first, then every stack
    code, second = _run(str(lib), "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    _assert_all_written(code, second)
    assert second["counts"]["trained"] == 0
    assert second["counts"]["from_cache"] == 3
    # entries made by code that made other tiles from the same inputs are not reused
    from seamless_usd.pipeline import cache as cache_module

    monkeypatch.setattr(cache_module, "TILE_REVISION", cache_module.TILE_REVISION + 1)
    code, third = _run(str(lib), "--cache-dir", str(tmp_path / "cold"), capsys=capsys)
    _assert_all_written(code, third)
    assert third["counts"]["trained"] == 3 and third["counts"]["from_cache"] == 0


def test_two_stacks_editing_one_layer_in_place_both_land(tmp_path, two_stacks, capsys):
    lib = _library(tmp_path, copies=0)
    layer = lib / "looks" / "two.usda"
    code, payload = _run(str(layer), "--in-place", "--cache-dir", str(two_stacks["cache"]), capsys=capsys)
    _assert_all_written(code, payload)
    assert len(payload["stacks"]) == 2 and payload["counts"]["from_cache"] == 2
    assert _tiles(lib / "looks" / "tileable") == two_stacks["tiles"]
    stage = Usd.Stage.Open(str(layer))
    for material in ("Brick", "Wood"):
        tex = UsdShade.Shader(stage.GetPrimAtPath(f"/World/Looks/{material}/Albedo"))
        assert "tileable" in tex.GetInput("file").Get().path
        assert tex.GetInput("wrapS").Get() == "repeat"
    assert (lib / "looks" / "two.usda.bak").read_text() == TWO_MATERIALS


def test_worker_processes_process_two_stacks(tmp_path, two_stacks, capsys):
    """``--jobs 2``: both stacks made in worker processes, byte for byte the tiles made in process. (Dask's workers
    are held to the same in ``test_dask_e2e``, on a tcp:// scheduler; a local cluster runs the same executor.)"""
    lib = _library(tmp_path, copies=0)
    code, payload = _run(str(lib / "looks" / "two.usda"), "--cache-dir", str(tmp_path / "c"), "--jobs", "2",
                         capsys=capsys)
    _assert_all_written(code, payload)
    assert {s["material"]: s["status"] for s in payload["stacks"]} == two_stacks["statuses"]
    assert code == two_stacks["code"] and payload["counts"]["trained"] == 2
    assert _tiles(lib / "looks" / "tileable") == two_stacks["tiles"]  # trained in the workers, byte for byte
    # each stack's tiles were written by a worker and the client's layer points at them
    stage = Usd.Stage.Open(str(lib / "looks" / "two.seamless.usda"))
    outputs = set()
    for s in payload["stacks"]:
        material = s["material"].strip("<>")
        tex = UsdShade.Shader(stage.GetPrimAtPath(f"{material}/Albedo"))
        resolved = Path(tex.GetInput("file").Get().resolvedPath)
        assert resolved.is_file() and resolved.parent == lib / "looks" / "tileable"
        assert str(resolved) in [m["output"] for m in s["maps"]]
        outputs.add(resolved)
    assert len(outputs) == 2


def test_a_warm_rerun_on_a_local_cluster_starts_no_cluster(tmp_path, two_stacks, capsys, monkeypatch):
    import distributed

    lib = _library(tmp_path, copies=0)
    cache = tmp_path / "c"
    shutil.copytree(two_stacks["cache"], cache)  # the cache a cold run of these two stacks left

    started = []

    class NoCluster:
        def __init__(self, *args, **kwargs):
            started.append(kwargs)
            raise RuntimeError("a warm rerun must not start a cluster")

    monkeypatch.setattr(distributed, "LocalCluster", NoCluster)
    monkeypatch.setattr(distributed, "Client", NoCluster)
    code, warm = _run(str(lib / "looks" / "two.usda"), "--cache-dir", str(cache), "--scheduler", "local:2",
                      capsys=capsys)
    _assert_all_written(code, warm)
    assert started == []
    assert warm["counts"]["trained"] == 0 and warm["counts"]["from_cache"] == 2
    assert _tiles(lib / "looks" / "tileable") == two_stacks["tiles"]
    # a changed texture is work again: only then is a cluster asked for
    shutil.copy(SAMPLES / "textures" / "cloth.png", lib / "looks" / "cloth_copy.png")
    (lib / "looks" / "two.usda").write_text(TWO_MATERIALS.replace("../textures/wood_color.png", "./cloth_copy.png"))
    main(["process", *RUN, "--cache-dir", str(cache), "--scheduler", "local:2", str(lib / "looks" / "two.usda")])
    assert len(started) == 1, "the changed stack needs work: the cluster is asked for"


def test_a_run_killed_after_the_first_stack_resumes_to_the_same_outputs(tmp_path, two_stacks):
    cmd = [sys.executable, "-m", "seamless_usd_cli.main", "process", *RUN, "--json"]
    expected = two_stacks["tiles"]  # an uninterrupted run's
    # killed the moment the first stack's tile is in place (a file-system event), then run again
    lib = _library(tmp_path / "run", copies=0)
    cache = tmp_path / "run-cache"
    proc = subprocess.Popen([*cmd, "--cache-dir", str(cache), str(lib / "looks")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    tiles = lib / "looks" / "tileable"
    reached = wait_until(lambda: bool(list(tiles.glob("*.tile.png"))), [lib], timeout=300,
                         stop=lambda: proc.poll() is not None)
    if reached and proc.poll() is None:
        proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    assert reached and proc.returncode == -signal.SIGKILL, "the run ended before its first tile was written"
    assert len(_tiles(tiles)) == 1, "killed after the first stack, before the second"
    assert not (lib / "looks" / "two.seamless.usda").exists(), "killed before the layer was written"
    done = subprocess.run([*cmd, "--cache-dir", str(cache), str(lib / "looks")], capture_output=True, timeout=600)
    payload = json.loads(done.stdout)
    _assert_all_written(done.returncode, payload)
    assert sorted(s["origin"] for s in payload["stacks"]) == ["cache", "trained"]  # the first stack is resumed
    assert _tiles(tiles) == expected
    assert (lib / "looks" / "two.seamless.usda").is_file()


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_a_run_stopped_with_ctrl_c_says_as_json_how_far_each_stack_got(tmp_path, two_stacks, signum):
    """Ctrl-C while tiles are made: the JSON report is still printed (exit code 130, ``interrupted``), and each stack's
    row says how far it got and agrees with the disk (tiles written, no layer). SIGTERM (``kill``, a farm's
    scheduler) stops it the same way: it ended the process at once, with no report and worker processes left
    running."""
    cmd = [sys.executable, "-m", "seamless_usd_cli.main", "process", *RUN, "--json"]
    lib = _library(tmp_path / "run", copies=0)
    cache = tmp_path / "run-cache"
    tiles = lib / "looks" / "tileable"
    tiles.mkdir()
    for name, data in two_stacks["tiles"].items():  # an earlier run's tiles, of the same names: not this run's
        (tiles / name).write_bytes(data)
        os.utime(tiles / name, (1e9, 1e9))
    proc = subprocess.Popen([*cmd, "--cache-dir", str(cache), str(lib / "looks")], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE,  # Ctrl-C as a terminal sends it, whatever this runner ignores
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    reached = wait_until(lambda: any(p.stat().st_mtime > 1e9 for p in tiles.glob("*.tile.png")), [lib], timeout=300,
                         stop=lambda: proc.poll() is not None)
    if reached and proc.poll() is None:
        proc.send_signal(signum)
    out, err = proc.communicate(timeout=120)
    assert reached and proc.returncode == 130, err.decode()[-2000:]
    payload = json.loads(out)
    jsonschema.validate(payload, json_schema("report"))
    assert payload["interrupted"] and payload["exit_code"] == 130 and b"interrupted" in err
    assert [s["status"] for s in payload["stacks"]] == ["failed", "failed"]
    assert not (lib / "looks" / "two.seamless.usda").exists()  # no stage edited
    written = {p.name for p in tiles.glob("*.tile.*") if p.stat().st_mtime > 1e9}
    said = {Path(m["output"]).name for s in payload["stacks"] for m in s["maps"] if m.get("output")}
    assert said == written and len(written) == 1  # the report names exactly the tiles this run wrote
    assert all(s["message"].startswith("interrupted") for s in payload["stacks"])
    # a run again resumes from the cache, as after a kill (test_a_run_killed_after_the_first_stack_resumes_...)


def _stopped_at(monkeypatch, module, name: str, call: int) -> None:
    """Ctrl-C as it arrives at the ``call``-th call of ``module.name`` (1 is the first): the call raises
    KeyboardInterrupt, as Python raises it wherever the run is when the signal comes."""
    real, calls = getattr(module, name), []

    def stopping(*args, **kwargs):
        calls.append(1)
        if len(calls) == call:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, stopping)


def test_ctrl_c_while_the_library_is_scanned_says_what_was_found_and_writes_nothing(tmp_path, cache, capsys,
                                                                                    monkeypatch):
    import seamless_usd.pipeline.process as process

    lib = _library(tmp_path, copies=1)
    _stopped_at(monkeypatch, process, "_scan_source", 2)  # while the second source is read
    code, payload = _run(str(lib / "brick0" / "scene.usda"), str(lib / "looks" / "two.usda"), "--cache-dir",
                         str(cache), capsys=capsys)
    assert code == 130 and payload["interrupted"] and payload["exit_code"] == 130
    jsonschema.validate(payload, json_schema("report"))
    [row] = payload["stacks"]  # the first source's stack, found and not made
    assert row["status"] == "failed" and row["message"].startswith("interrupted before its tiles were made")
    assert not list(lib.rglob("tileable")) and not list(lib.rglob("*.seamless.usda"))


def test_ctrl_c_while_the_stages_are_edited_keeps_the_edits_made_and_names_the_rest(tmp_path, cache, capsys,
                                                                                   monkeypatch):
    """The first stage's layer is written and its row says how its stack did; the second stage, stopped while its
    edits were written, has its tiles on disk, no layer, and rows that say to run again."""
    from seamless_usd import authoring

    lib = _library(tmp_path, copies=1)
    first, second = lib / "brick0" / "scene.usda", lib / "looks" / "two.usda"
    _stopped_at(monkeypatch, authoring, "author_usd", 2)
    code, payload = _run(str(first), str(second), "--cache-dir", str(cache), capsys=capsys)
    assert code == 130 and payload["interrupted"]
    jsonschema.validate(payload, json_schema("report"))
    by_source = {}
    for row in payload["stacks"]:
        by_source.setdefault(Path(row["source"]).name, []).append(row)
    assert [r["status"] for r in by_source["scene.usda"]] in (["passed"], ["not-passed"])
    assert first.with_name("scene.seamless.usda").is_file()
    assert [r["status"] for r in by_source["two.usda"]] == ["failed", "failed"]
    assert all(r["message"].startswith("interrupted before the stage was edited") for r in by_source["two.usda"])
    assert not second.with_name("two.seamless.usda").exists()
    said = {Path(m["output"]).name for r in by_source["two.usda"] for m in r["maps"]}
    assert said == {p.name for p in (lib / "looks" / "tileable").glob("*.tile.*")} and len(said) == 2
    findings = [json.dumps(f, sort_keys=True) for f in payload["findings"]]
    assert len(findings) == len(set(findings)), "a finding said twice"


def test_a_missing_texture_blocks_only_the_file_that_lacks_it(tmp_path, cache, capsys):
    lib = _library(tmp_path, copies=2)
    scene = lib / "brick1" / "scene.usda"
    scene.write_text(scene.read_text().replace("brick_roughness.png", "gone_roughness.png"))
    code, payload = _run(str(lib / "brick0"), str(lib / "brick1"), "--cache-dir", str(cache), capsys=capsys)
    assert code == 1
    status = {Path(s["source"]).parent.name: s for s in payload["stacks"]}
    assert status["brick0"]["status"] == "not-passed"  # written (the pure GAN tile of a tiny run does not pass)
    assert status["brick1"]["status"] == "failed"
    assert "gone_roughness.png" in status["brick1"]["message"]
    assert not (lib / "brick1" / "scene.seamless.usda").exists()


def test_one_output_layer_for_several_stages_is_a_usage_error(tmp_path, cache, capsys):
    lib = _library(tmp_path, copies=2)
    code = main(["process", "--preset", "tiny", str(lib), "-o", str(tmp_path / "one.usda"), "--cache-dir", str(cache)])
    assert code == 2
    assert "several inputs were given" in capsys.readouterr().err


def test_an_unusable_cache_folder_is_a_usage_error_before_any_work(tmp_path, capsys):
    """A cache folder that is a file: one usage error (exit 2) before any work, not every stack failed (exit 1, which
    reads like a texture that did not pass)."""
    lib = _library(tmp_path, copies=1)
    not_a_folder = tmp_path / "cache-file"
    not_a_folder.write_text("a file where the cache folder should be")
    assert main(["process", *RUN, str(lib / "brick0"), "--cache-dir", str(not_a_folder)]) == 2
    err = capsys.readouterr().err
    assert "--cache-dir" in err and "is a file" in err
    assert not (lib / "brick0" / "tileable").exists() and not_a_folder.read_text().startswith("a file")


def test_materials_patterns_select_by_path_or_name(tmp_path, cache, capsys):
    lib = _library(tmp_path, copies=0)
    layer = str(lib / "looks" / "two.usda")
    _, by_name = _run(layer, "--dry-run", "--materials", "Wood", capsys=capsys)
    assert [s["material"] for s in by_name["stacks"]] == ["</World/Looks/Wood>"]
    _, by_path = _run(layer, "--dry-run", "--materials", "/World/Looks/B*", capsys=capsys)
    assert [s["material"] for s in by_path["stacks"]] == ["</World/Looks/Brick>"]
    _, both = _run(layer, "--dry-run", "--materials", "Wood", "--materials", "Brick", capsys=capsys)
    assert len(both["stacks"]) == 2
    # a pattern that matches nothing (case counts): refused when none matches, named when some other one does
    assert main(["process", *RUN, layer, "--dry-run", "--materials", "wood"]) == 2
    assert "--materials wood matches no material" in capsys.readouterr().err
    _, partly = _run(layer, "--dry-run", "--materials", "Wood", "--materials", "Stone", capsys=capsys)
    assert [s["material"] for s in partly["stacks"]] == ["</World/Looks/Wood>"]
    assert [f["code"] for f in partly["findings"] if "Stone" in f["message"]] == ["pattern-unmatched"]


def test_two_stages_whose_materials_share_a_path_and_a_file_name_get_tiles_of_their_own(tmp_path, capsys):
    """a.usda reads x/albedo.png, b.usda y/albedo.png, both as </World/Looks/Brick>, both writing into one
    tileable/ folder: the tiles' names carry their source's digest, so neither overwrites the other's."""
    for name, texture in (("a", "brick_albedo.png"), ("b", "wood_color.png")):
        (tmp_path / "tex" / name).mkdir(parents=True)
        shutil.copy(SAMPLES / "textures" / texture, tmp_path / "tex" / name / "albedo.png")
        text = (SAMPLES / "brick" / "scene.usda").read_text()
        text = text.replace("@../textures/brick_albedo.png@", f"@./tex/{name}/albedo.png@")
        (tmp_path / f"{name}.usda").write_text(text.replace("@../textures/", "@./tex/a/../../textures/"))
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    outputs = {}
    for name in ("a", "b"):
        assert main(["process", str(tmp_path / f"{name}.usda"), "--dry-run", "--json"]) in (0, 1)
        [stack] = json.loads(capsys.readouterr().out)["stacks"]
        outputs[name] = {m["asset"]: m["output"] for m in stack["maps"]}
    assert outputs["a"]["./tex/a/albedo.png"] != outputs["b"]["./tex/b/albedo.png"]
    assert Path(outputs["a"]["./tex/a/albedo.png"]).parent == Path(outputs["b"]["./tex/b/albedo.png"]).parent


def test_a_scheduler_that_cannot_be_reached_is_a_usage_error(tmp_path, capsys, monkeypatch):
    """A --scheduler address nothing answers at ends the run with exit 2 naming the address, not an internal
    error; nothing is written. (A fresh cache: with every result cached no scheduler is contacted.)"""
    import seamless_usd.pipeline.executors as executors

    monkeypatch.setattr(executors, "CONNECT_TIMEOUT_S", 1)
    lib = _library(tmp_path, copies=1)
    code = main(["process", *RUN, str(lib / "brick0"), "--cache-dir", str(tmp_path / "fresh"), "--scheduler",
                 "tcp://127.0.0.1:1"])
    assert code == 2 and "cannot reach the Dask scheduler" in capsys.readouterr().err
    assert not (lib / "brick0" / "scene.seamless.usda").exists()
    # a cached stack beside one that needs the scheduler: the scheduler is reached before the cached stack's tiles are
    # written (else they would be left with no layer naming them)
    warm = tmp_path / "warm"
    assert main(["process", *RUN, str(lib / "brick0"), "--cache-dir", str(warm)]) in (0, 1)
    shutil.rmtree(lib / "brick0" / "tileable")
    (lib / "brick0" / "scene.seamless.usda").unlink()
    code = main(["process", *RUN, str(lib / "brick0"), str(lib / "looks"), "--cache-dir", str(warm), "--scheduler",
                 "tcp://127.0.0.1:1"])
    assert code == 2 and "cannot reach the Dask scheduler" in capsys.readouterr().err
    assert not (lib / "brick0" / "tileable").exists() and not (lib / "brick0" / "scene.seamless.usda").exists()


def test_a_cache_whose_locks_cannot_be_taken_still_gives_its_results(tmp_path, capsys):
    """A shared cache this process cannot write (here: each entry's lock is a folder, so no lock can be taken, as in
    a read-only cache) still gives its finished results; nothing in it is needed to be written."""
    lib = _library(tmp_path, copies=1)
    cache = tmp_path / "shared-cache"
    code, first = _run(str(lib / "brick0"), "--cache-dir", str(cache), capsys=capsys)
    for lock in cache.rglob("*.lock"):
        lock.unlink()
        lock.mkdir()
    shutil.rmtree(lib / "brick0" / "tileable")
    (lib / "brick0" / "scene.seamless.usda").unlink()
    again_code, again = _run(str(lib / "brick0"), "--cache-dir", str(cache), capsys=capsys)
    assert again_code == code and [s["status"] for s in again["stacks"]] == [s["status"] for s in first["stacks"]]
    assert again["stacks"][0]["origin"] == "cache" and (lib / "brick0" / "scene.seamless.usda").is_file()


def test_a_stage_in_a_folder_of_the_users_named_tileable_is_walked(tmp_path):
    """This tool writes tiles, never stages, into tileable/ folders: a stage there is the user's, and a folder walk
    takes it (it was skipped silently)."""
    from seamless_usd.pipeline.inputs import expand_inputs

    lib = _library(tmp_path, copies=1)
    (lib / "tileable").mkdir()
    shutil.copy(SAMPLES / "brick" / "scene.usda", lib / "tileable" / "floor.usda")
    (lib / "brick0" / "tileable").mkdir()
    (lib / "brick0" / "scene.seamless.usda").write_text("#usda 1.0\n")
    found = {str(p.relative_to(lib)) for p in expand_inputs([lib])}
    assert found == {"brick0/scene.usda", "looks/two.usda", "tileable/floor.usda"}


def test_a_glob_leaves_out_the_layers_its_stages_compose_as_a_folder_walk_does(tmp_path):
    """``process 'prop/*.usda'``: the prop's payload and materials layers go through the prop, not again on their
    own (with no geometry bound, its UV atlas read as tiling and was tiled)."""
    shutil.copytree(SAMPLES / "prop", tmp_path / "prop")
    assert expand_inputs([str(tmp_path / "prop" / "*.usda")]) == expand_inputs([tmp_path / "prop"])
    assert [p.name for p in expand_inputs([str(tmp_path / "prop" / "*.usda")])] == ["prop.usda"]
    assert [p.name for p in expand_inputs([tmp_path / "prop" / "prop_mtl.usda"])] == ["prop_mtl.usda"]  # named


def test_a_dry_run_plans_the_tiles_a_duplicate_in_the_same_folder_reuses(tmp_path, capsys):
    """Two materials of one stage reading the same maps: the run writes the first's tiles once and points both at
    them; the dry run planned tiles of the second's own, which the run never writes."""
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    text = scene.read_text()
    start = text.index('        def Material "Brick"')
    end = text.index("\n        }\n", text.index('def Shader "Roughness"')) + len("\n        }\n")
    twin = text[start:end].replace('"Brick"', '"Twin"').replace("/World/Looks/Brick/", "/World/Looks/Twin/")
    scene.write_text(text[:end] + twin + text[end:])
    args = (str(scene), "--max-size", "128", "--cache-dir", str(tmp_path / "cache"))
    _, planned = _run(*args, "--dry-run", capsys=capsys)
    _, done = _run(*args, capsys=capsys)
    assert len(done["stacks"]) == 2 and {s["origin"] for s in done["stacks"]} >= {"duplicate"}

    def outputs(payload):
        return {s["id"]: sorted(m.get("output") for m in s["maps"]) for s in payload["stacks"]}

    assert outputs(planned) == outputs(done)


def test_a_finished_job_counts_only_while_its_own_cache_entry_is_there(tmp_path):
    """The index names each finished job's cache entry. Stacks made by cuts alone all have an empty model hash, so by
    the model hash alone a job whose entry was deleted still read as finished while any other cut-only entry was
    there, and the warm path then ran it cold, in the client."""
    from seamless_usd.pipeline.cache import MANIFEST, JobIndex

    kept, gone = "ab" + "0" * 62, "cd" + "1" * 62
    folder = tmp_path / kept[:2] / kept
    folder.mkdir(parents=True)
    (folder / MANIFEST).write_text(json.dumps({"meta": {"model_hash": ""}}))
    index = JobIndex(tmp_path)
    index.record("f" * 64, "", kept)
    index.record("e" * 64, "", gone)
    index.record("d" * 64, "")  # a record of an older run, naming no entry: read by its model hash
    assert index.finished("f" * 64) and index.entry("f" * 64) == folder
    assert not index.finished("e" * 64) and index.entry("e" * 64) is None
    assert index.finished("d" * 64) and index.entry("d" * 64) is None
    assert not JobIndex(tmp_path).finished("0" * 64)


def test_a_materialx_dry_run_after_a_run_plans_the_cached_scale(tmp_path, capsys):
    """A tiledimage's uvtiling: before any run the dry run can only say it is multiplied by the tile's UV scale;
    after a run it plans what the run does, from the cache, with the scale known."""
    for name in ("mtlx", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    doc, cache = str(tmp_path / "mtlx" / "tiled.mtlx"), str(tmp_path / "cache")
    _, before = _run(doc, "--dry-run", "--cache-dir", cache, "--refine", "on", capsys=capsys)  # a source-sized tile
    assert any("x the tile's UV scale" in line for line in before["plan"])
    _, run = _run(doc, "--cache-dir", cache, capsys=capsys)
    _, after = _run(doc, "--dry-run", "--cache-dir", cache, capsys=capsys)
    assert [s["uv_scale"] for s in after["stacks"]] == [s["uv_scale"] for s in run["stacks"]]
    assert any(line.startswith("keep the tiles an earlier run wrote") for line in after["plan"]), after["plan"]
    assert not any("x the tile's UV scale" in line for line in after["plan"])


def test_worker_processes_stop_at_once_when_the_run_stops(tmp_path):
    """Ctrl-C ends the worker processes' jobs at once: the pool waited for every job still running (a stack's whole
    training, about 50 s) and, on a second Ctrl-C, left its workers orphaned, still writing tiles the report said
    were not made."""
    import multiprocessing
    import os
    import threading
    import time

    from seamless_usd.discover import scan_paths
    from seamless_usd.pipeline.options import Options
    from seamless_usd.pipeline.stackjob import JobSettings, StackJob

    lib = _library(tmp_path, copies=0)
    stacks = scan_paths([lib / "looks" / "two.usda"]).stacks
    options = Options(preset="draft", iterations=20000, max_size=128, cache_dir=tmp_path / "cache", refine="gan")
    executor = ProcessPoolExecutor(1)  # one worker, running the first job with the second queued
    settings = JobSettings.from_options(options, executor.threads_per_job)
    running = executor.run([StackJob(stack=s, settings=settings, output_dir=tmp_path / "out") for s in stacks],
                           lambda job, kind, detail: None)
    before = set(multiprocessing.active_children())
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)  # as in a terminal
    ctrl_c = threading.Timer(4.0, lambda: os.kill(os.getpid(), signal.SIGINT))
    try:
        ctrl_c.start()
        started = time.perf_counter()
        with pytest.raises(KeyboardInterrupt):
            next(running)  # the first job's end: long after the Ctrl-C
        stopped = time.perf_counter() - started
    finally:
        ctrl_c.cancel()
        signal.signal(signal.SIGINT, previous)
    assert stopped < 25, stopped
    workers = set(multiprocessing.active_children()) - before
    for w in workers:  # ended, not waited for: each exits within moments (on a busy machine, after this line ran;
        w.join(20)  # a worker left running would train on for minutes: 20000 iterations)
    alive = [(w.name, w.pid) for w in workers if w.is_alive()]
    assert not alive, alive
    assert not list((tmp_path / "out").glob("*.tile.*"))  # stopped before any tile: none written after


def test_materials_leaves_out_the_findings_about_materials_it_does_not_select(tmp_path, capsys):
    """``--materials Brick``: a missing texture of another material is not this run's to report (it was listed,
    with its prim, among the run's findings); a finding about the run itself still is."""
    from test_reliability_inputs import write_scene

    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    layer = write_scene(tmp_path / "looks" / "two.usda",
                        {"Brick": "../textures/brick_albedo.png", "Other": "../textures/not_there.png"})
    _, everything = _run(str(layer), "--dry-run", capsys=capsys)
    assert any("not_there.png" in f["where"] for f in everything["findings"])
    _, brick = _run(str(layer), "--dry-run", "--materials", "Brick", capsys=capsys)
    assert not any("not_there.png" in f["where"] + f["message"] for f in brick["findings"]), brick["findings"]
    assert [s["material"] for s in brick["stacks"]] == ["</Root/Looks/Brick>"]


def test_two_stages_of_one_name_and_two_formats_in_one_folder_get_a_layer_each(tmp_path, capsys):
    """``scene.usda`` and ``scene.usdc`` side by side both wrote ``scene.seamless.usda``, the second replacing the
    first's edits, while the run said both were written (exit 0). Each now keeps its extension in its layer's name,
    and a run again writes nothing."""
    from pxr import Sdf

    lib = _library(tmp_path, copies=1)
    folder = lib / "brick0"
    layer = Sdf.Layer.CreateNew(str(folder / "scene.usdc"))  # another look, its textures as near (../textures)
    layer.ImportFromString(Sdf.Layer.FindOrOpen(str(lib / "looks" / "two.usda")).ExportToString())
    layer.Save()
    code, payload = _run(str(folder), "--cache-dir", str(tmp_path / "cache"), capsys=capsys)
    written = sorted(Path(p).name for p in payload["layers_written"])
    assert written == ["scene.usda.seamless.usda", "scene.usdc.seamless.usda"], written
    for name in ("scene.usda", "scene.usdc"):
        assert Sdf.Layer.FindOrOpen(str(folder / f"{name}.seamless.usda")).subLayerPaths == [f"./{name}"]
    again, repeat = _run(str(folder), "--cache-dir", str(tmp_path / "cache"), capsys=capsys)
    assert again == code and not repeat["layers_written"]


def test_ctrl_c_while_scan_runs_says_what_was_scanned(tmp_path, capsys, monkeypatch):
    """``scan --json`` stopped by Ctrl-C printed nothing, where ``process --json`` and ``check --json`` print what
    they had done: the stages scanned by then, ``interrupted``, exit code 130."""
    from seamless_usd.discover import scan as scan_module

    lib = _library(tmp_path, copies=1)
    first, second = lib / "brick0" / "scene.usda", lib / "looks" / "two.usda"
    _stopped_at(monkeypatch, scan_module, "open_stage", 2)
    assert main(["scan", str(first), str(second), "--json"]) == 130
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("scan"))
    assert payload["interrupted"] and payload["sources"] == [str(first.resolve())] and len(payload["stacks"]) == 1
