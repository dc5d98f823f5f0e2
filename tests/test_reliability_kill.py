"""Reliability: ``seamless-usd process`` killed with SIGKILL at several points, then run again.

The command runs in a subprocess on a small library (two scenes; for the kills, the second is a twin of
the first, so each run trains and judges one stack but writes two scenes' tiles and layers). The test
watches the file system and kills the process the moment a checkpoint appears in the cache
(training), a tile appears in an output folder (writing maps) and an override layer appears
(saving layers), each at two moments. After every kill: every output image and layer present opens and is complete,
the originals are byte-identical, every finished cache entry verifies. The next run resumes
training from the checkpoint the killed one left (the checkpoints it writes continue from that
step) and the last run completes. Two runs at once on the same library and cache both finish,
with each stack trained once and one complete layer per scene.
"""
from __future__ import annotations

import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from pxr import Sdf, Usd, UsdShade
from safetensors import safe_open

from fswatch import wait_until
from runchecks import PLUMBING
from test_reliability_inputs import hashes, image_size

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
ITERATIONS = 12  # tiny preset checkpoints every 2 iterations: a kill at the first checkpoint is mid-training, with
#               ten iterations to spare (at 6 a busy machine finished training before the kill landed)
ARGS = (*PLUMBING, "--iterations", str(ITERATIONS), "--max-size", "112")


def _copy(root: Path, folders: dict[str, str]) -> Path:
    """A library of sample folders (copy name -> sample name) beside the shared textures."""
    lib = root / "lib with space"
    for copy, name in {**folders, "textures": "textures"}.items():
        shutil.copytree(SAMPLES / name, lib / copy)
    return lib


@pytest.fixture()
def library(tmp_path) -> Path:
    """Two scenes, two different stacks (brick, and packed ORM maps)."""
    return _copy(tmp_path, {"brick": "brick", "orm": "orm"})


@pytest.fixture()
def twins(tmp_path) -> Path:
    """Two scenes with one stack: the second scene's is identical, so one training and one verdict per run
    while each scene still gets its own tiles and its own layer."""
    return _copy(tmp_path, {"brick": "brick", "brick twin": "brick"})


def _scenes(lib: Path) -> list[Path]:
    return sorted(lib.glob("*/scene.usda"))


def _start(lib: Path, cache: Path, *extra: str) -> subprocess.Popen:
    env = dict(os.environ, OMP_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    cmd = [sys.executable, "-m", "seamless_usd_cli.main", "process", *ARGS, "--cache-dir", str(cache),
           *extra, *map(str, _scenes(lib))]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env, cwd=lib)


def _kill_when(proc: subprocess.Popen, ready, watch: Path, timeout: float = 120.0, on_poll=None) -> bool:
    """SIGKILL ``proc`` as soon as ``ready()``; False when it ended before that. ``ready`` is checked on
    every file-system event under ``watch`` (library and cache), not by polling."""
    def check() -> bool:
        if on_poll is not None:
            on_poll()
        return ready()

    try:
        reached = wait_until(check, [watch], timeout, stop=lambda: proc.poll() is not None)
    except TimeoutError:
        proc.kill()
        proc.wait()
        raise AssertionError("the kill point was not reached in time") from None
    if not reached or proc.poll() is not None:
        return False
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    return True


def _checkpoints(cache: Path) -> list[Path]:
    return list(cache.glob("*/*/checkpoints/checkpoint.safetensors"))


def _step(path: Path) -> int | None:
    try:
        with safe_open(str(path), "np") as f:
            return int(json.loads(f.metadata()["meta"])["step"])
    except Exception:  # noqa: BLE001 - replaced under our feet: try again at the next poll
        return None


def _tiles(lib: Path, with_temp: bool = True) -> list[Path]:
    return [p for p in lib.glob("*/tileable/*") if p.is_file() and (with_temp or not p.name.startswith("."))]


def _layers(lib: Path) -> list[Path]:
    return [p for p in lib.glob("*/*seamless*") if p.is_file()]


def check_integrity(lib: Path, cache: Path, originals: dict[str, str]) -> dict[str, int]:
    """Everything a killed run may have left: complete or absent, never corrupt."""
    counts = {"tiles": 0, "layers": 0, "entries": 0, "corrupt": 0, "temp": 0}
    now = hashes(lib)
    assert {k: now.get(k) for k in originals} == originals, "an original file changed"
    for tile in _tiles(lib):
        if ".tmp" in tile.name:
            counts["temp"] += 1  # an unfinished temporary file (never renamed into place)
            continue
        w, h = image_size(tile)  # opens and decodes completely, or fails the test
        assert w > 0 and h > 0
        counts["tiles"] += 1
    for layer in _layers(lib):
        if ".tmp" in layer.name:
            counts["temp"] += 1
            continue
        assert Sdf.Layer.OpenAsAnonymous(str(layer)), f"{layer} does not open"
        assert Usd.Stage.Open(str(layer)), f"{layer} does not compose"
        counts["layers"] += 1
    for manifest in cache.glob("*/*/manifest.json"):
        data = json.loads(manifest.read_text())
        for name, digest in data["files"].items():
            assert hashlib.sha256((manifest.parent / name).read_bytes()).hexdigest() == digest
        counts["entries"] += 1
    return counts


def _finish(proc: subprocess.Popen) -> tuple[int, dict]:
    """The run's exit code and report; everything should work: no error finding, no failed
    stack, and exit 0 unless a stack's quality function did not pass (then 1)."""
    out, err = proc.communicate(timeout=300)
    assert proc.returncode in (0, 1), err.decode(errors="replace")[-3000:]
    report = json.loads(out)
    errors = [f for f in report["findings"] if f["severity"] == "error"]
    assert not errors, errors
    statuses = [s["status"] for s in report["stacks"]]
    assert "failed" not in statuses, report["stacks"]
    assert proc.returncode == (1 if "not-passed" in statuses else 0), (proc.returncode, statuses)
    return proc.returncode, report


def check_final(lib: Path, report: dict) -> None:
    """After a completed run: every stack done, every edited texture resolves to a complete tile."""
    assert {s["status"] for s in report["stacks"]} <= {"passed", "not-passed", "reused"}, report["stacks"]
    for stack in report["stacks"]:
        for m in stack["maps"]:
            assert image_size(Path(m["output"])) == tuple(stack["tile_size"][::-1])
    for scene in _scenes(lib):
        layer = scene.with_name("scene.seamless.usda")
        stage = Usd.Stage.Open(str(layer))
        edited = 0
        for prim in stage.Traverse():
            shader = UsdShade.Shader(prim)
            if shader and shader.GetIdAttr().Get() == "UsdUVTexture":
                value = shader.GetInput("file").Get()
                assert value.resolvedPath and Path(value.resolvedPath).is_file()
                edited += "tileable" in value.resolvedPath
        assert edited, f"{layer} edits no texture"


def _rerun_completes(library: Path, cache: Path, originals: dict[str, str], kills: list[str]) -> None:
    """A run after the killed ones completes, and nothing of the interrupted runs is lost or corrupt."""
    code, report = _finish(_start(library, cache, "--json"))
    counts = check_integrity(library, cache, originals)
    check_final(library, report)
    assert counts["layers"] == 2 and counts["entries"] == 1 and counts["tiles"] == 6  # 3 maps in each scene
    assert counts["temp"] == 0, "the re-run removes the temporary files the killed runs left"
    assert [s["origin"] for s in report["stacks"]] == ["cache", "duplicate"]
    print(f"\nkill points tested: {len(kills)} ({', '.join(kills)}); files lost or corrupted: 0; "
          "temporary files left: 0")


def test_sigkill_during_training_writing_maps_and_saving_layers(twins, tmp_path):
    library = twins
    cache = tmp_path / "cache"
    originals = hashes(library)
    kills: list[str] = []

    # 1. during training: the moment the first checkpoint lands in the cache
    proc = _start(library, cache, "--json")
    assert _kill_when(proc, watch=tmp_path, ready=lambda: bool(_checkpoints(cache)))
    kills.append("training")
    [ckpt] = _checkpoints(cache)
    killed_at = _step(ckpt)
    assert killed_at is not None and 0 < killed_at < ITERATIONS
    check_integrity(library, cache, originals)

    # 2. while writing maps; meanwhile, the checkpoints this run writes continue from killed_at
    restarted = time.time_ns()
    seen_steps: set[int] = set()

    def watch_checkpoint() -> None:
        if ckpt.exists() and ckpt.stat().st_mtime_ns > restarted:
            step = _step(ckpt)
            if step is not None:
                seen_steps.add(step)

    proc = _start(library, cache, "--json")
    assert _kill_when(proc, watch=tmp_path, ready=lambda: bool(_tiles(library)), on_poll=watch_checkpoint)
    kills.append("writing maps")
    assert seen_steps and min(seen_steps) > killed_at, (killed_at, sorted(seen_steps))
    check_integrity(library, cache, originals)

    # 3. again while writing maps, later: once a tile is complete (renamed into place)
    proc = _start(library, cache, "--json")
    assert _kill_when(proc, watch=tmp_path, ready=lambda: bool(_tiles(library, with_temp=False)))
    kills.append("writing maps (a tile complete)")
    check_integrity(library, cache, originals)

    # 4. while saving layers (after every stack is done, before every scene has its layer)
    proc = _start(library, cache, "--json")
    assert _kill_when(proc, watch=tmp_path, ready=lambda: bool(_layers(library)))
    kills.append("saving layers")
    check_integrity(library, cache, originals)

    # 5. again while saving layers, later: once one layer is complete, before the other
    for layer in _layers(library):
        layer.unlink()
    proc = _start(library, cache, "--json")
    assert _kill_when(proc, watch=tmp_path, ready=lambda: any(".tmp" not in p.name for p in _layers(library)))
    kills.append("saving layers (one layer complete)")
    check_integrity(library, cache, originals)
    _rerun_completes(library, cache, originals, kills)


def test_two_runs_at_once_share_library_and_cache(library, tmp_path):
    cache = tmp_path / "cache"
    originals = hashes(library)
    first = _start(library, cache, "--json", "--iterations", "4")
    second = _start(library, cache, "--json", "--iterations", "4")
    (code1, report1), (code2, report2) = _finish(first), _finish(second)
    counts = check_integrity(library, cache, originals)
    assert counts["temp"] == 0 and counts["layers"] == 2 and counts["entries"] == 2
    for report in (report1, report2):
        check_final(library, report)
    # the entry lock: each stack trained by one of the two runs, taken from the cache by the other
    origins: dict[str, list[str]] = {}
    for report in (report1, report2):
        for stack in report["stacks"]:
            origins.setdefault(stack["material"], []).append(stack["origin"])
    assert all(sorted(o) == ["cache", "trained"] for o in origins.values()), origins


def test_two_in_place_runs_at_once_keep_the_originals_in_their_backups(twins, tmp_path):
    library = twins
    cache = tmp_path / "cache"
    originals = {scene: scene.read_bytes() for scene in _scenes(library)}
    runs = [_start(library, cache, "--json", "--in-place", "--iterations", "6") for _ in range(2)]
    reports = [_finish(run)[1] for run in runs]
    for scene, original in originals.items():
        backup = scene.with_name(scene.name + ".bak")
        assert backup.read_bytes() == original, "the backup must hold the original, not the other run's edit"
        stage = Usd.Stage.Open(str(scene))
        for prim in stage.Traverse():
            shader = UsdShade.Shader(prim)
            if shader and shader.GetIdAttr().Get() == "UsdUVTexture":
                assert "tileable" in shader.GetInput("file").Get().path
        transforms = [p for p in stage.Traverse()
                      if UsdShade.Shader(p) and UsdShade.Shader(p).GetIdAttr().Get() == "UsdTransform2d"]
        textures = [p for p in stage.Traverse()
                    if UsdShade.Shader(p) and UsdShade.Shader(p).GetIdAttr().Get() == "UsdUVTexture"]
        assert len(transforms) <= len(textures), "a UV transform was added twice"
    assert not [p for p in library.rglob("*") if ".tmp" in p.name]
    assert all(r["exit_code"] in (0, 1) for r in reports)


WRITER = """
import sys
from pathlib import Path
from pxr import Sdf
from seamless_usd.authoring.files import check_layer, write_atomically
target, who, prims = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3])
for round in range(int(sys.argv[4])):
    layer = Sdf.Layer.CreateAnonymous(".usda")
    layer.customLayerData = {"writer": who, "round": round}
    for i in range(prims):
        Sdf.CreatePrimInLayer(layer, f"/P{i}").specifier = Sdf.SpecifierDef
    write_atomically(target, lambda tmp: layer.Export(str(tmp)), check=check_layer)
"""


def test_concurrent_layer_writers_leave_one_complete_layer(tmp_path):
    target = tmp_path / "scene.seamless.usda"
    prims, rounds = 400, 25
    writers = [subprocess.Popen([sys.executable, "-c", WRITER, str(target), str(k), str(prims), str(rounds)])
               for k in range(3)]
    seen = 0
    while any(w.poll() is None for w in writers):
        if target.exists():
            layer = Sdf.Layer.OpenAsAnonymous(str(target))
            assert layer and len(layer.rootPrims) == prims, "a reader saw a partial layer"
            seen += 1
        time.sleep(0.005)
    assert all(w.returncode == 0 for w in writers)
    layer = Sdf.Layer.OpenAsAnonymous(str(target))
    assert len(layer.rootPrims) == prims and layer.customLayerData["round"] == rounds - 1
    assert seen > 0
    assert [p.name for p in tmp_path.iterdir()] == [target.name]
