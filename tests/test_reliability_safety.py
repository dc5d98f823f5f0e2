"""Reliability: what the cache and checkpoints load, and where outputs may go.

* A pickle planted where a checkpoint is expected is refused (never unpickled), removed, and the
  stack is trained again.
* A finished cache entry whose tile file no longer matches its recorded SHA-256 is not used: the
  stack is trained and sampled again.
* Output paths stay inside the output folder: ``..``, absolute parts and symbolic links that lead
  out are refused.
"""
from __future__ import annotations

import hashlib
import json
import pickle
from pathlib import Path

import pytest

from seamless_usd.errors import InputError
from seamless_usd.fileio import confine
from seamless_usd.naming import tile_filename
from seamless_usd.pipeline.rerun import JUDGED
from seamless_usd.synthesis.gan.checkpoint import CHECKPOINT_NAME, load_checkpoint

from seamless_usd_cli.main import main

from test_reliability_inputs import image_size, run_cli, texture, write_image, write_scene


class _Payload:
    """Unpickling this runs code: it writes the file named by ``marker``."""

    def __init__(self, marker: Path):
        self.marker = str(marker)

    def __reduce__(self):
        return (exec, (f"open({self.marker!r}, 'w').write('unpickled')",))


def _scene(tmp_path: Path) -> Path:
    write_image(tmp_path / "lib" / "tex" / "a.png", texture(31))
    return write_scene(tmp_path / "lib" / "scene.usda", {"A": "./tex/a.png"})


def _entry(cache: Path) -> Path:
    [manifest] = cache.glob("*/*/manifest.json")
    return manifest.parent


def test_planted_pickle_checkpoint_is_refused_and_the_stack_retrained(tmp_path, capsys):
    marker = tmp_path / "marker.txt"
    payload = pickle.dumps({"G.weight": _Payload(marker)})
    pickle.loads(payload)  # the payload is live: loading it with pickle runs code
    assert marker.exists()
    marker.unlink()

    scene, cache = _scene(tmp_path), tmp_path / "cache"
    code, report, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    assert code in (0, 1)
    entry = _entry(cache)
    for name in ("manifest.json", "tiles.safetensors"):  # an unfinished entry: training resumes
        (entry / name).unlink()
    checkpoint = entry / "checkpoints" / CHECKPOINT_NAME
    for planted in (payload, b"PK\x03\x04" + payload):  # raw pickle, and a torch.save-like zip header
        checkpoint.write_bytes(planted)
        with pytest.raises(ValueError, match="refusing to load"):
            load_checkpoint(checkpoint)
        code, report, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
        assert code in (0, 1), report
        [stack] = report["stacks"]
        assert stack["status"] in ("passed", "not-passed") and stack["origin"] == "trained"
        assert not marker.exists(), "the planted checkpoint was unpickled"
        tensors, meta = load_checkpoint(checkpoint)  # replaced by a real checkpoint of this stack
        assert meta["step"] > 0 and tensors
        (entry / "manifest.json").unlink()


def test_every_seeds_checkpoint_is_checked_and_a_planted_one_removed(tmp_path, capsys):
    marker = tmp_path / "marker.txt"
    scene, cache = _scene(tmp_path), tmp_path / "cache"
    code, report, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache), "--seeds", "2")
    assert code in (0, 1), report
    [stack] = report["stacks"]
    seeds = stack["resampled"]["gan"]["seeds"]
    assert [s["seed"] for s in seeds] == [0, 1] and sum(s["chosen"] for s in seeds) == 1
    entry = _entry(cache)
    second = entry / "checkpoints" / "seed-1" / CHECKPOINT_NAME
    assert load_checkpoint(second)[1]["step"] > 0
    for name in ("manifest.json", "tiles.safetensors"):
        (entry / name).unlink()
    second.write_bytes(pickle.dumps({"G.weight": _Payload(marker)}))
    code, report, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache), "--seeds", "2")
    assert code in (0, 1), report
    assert report["stacks"][0]["origin"] == "trained"
    assert not marker.exists(), "the planted checkpoint was unpickled"
    assert load_checkpoint(second)[1]["step"] > 0  # the second seed trained again from scratch


@pytest.mark.parametrize("value", ["0", "-1", "two"])
def test_seeds_and_iterations_must_be_positive_whole_numbers(tmp_path, capsys, value):
    scene = _scene(tmp_path)
    for option in ("--seeds", "--iterations"):
        try:
            code = main(["process", str(scene), option, value])
        except SystemExit as exit_:  # argparse's usage error
            code = exit_.code
        assert code == 2
        err = capsys.readouterr().err
        assert option in err and "Traceback" not in err
    assert not (scene.parent / "tileable").exists()  # refused before anything was written


def test_corrupt_cached_tile_is_not_used(tmp_path, capsys):
    scene, cache = _scene(tmp_path), tmp_path / "cache"
    code, first, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    assert first["stacks"][0]["origin"] == "trained"
    code, second, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    assert second["stacks"][0]["origin"] == "cache"

    tiles = _entry(cache) / "tiles.safetensors"
    data = bytearray(tiles.read_bytes())
    data[-100] ^= 0xFF  # one flipped byte inside the pixel data: still a valid safetensors file
    tiles.write_bytes(bytes(data))
    code, third, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    [stack] = third["stacks"]
    assert stack["origin"] == "trained", "a tile that fails its hash must not be used"
    assert stack["status"] in ("passed", "not-passed")
    for m in stack["maps"]:
        assert image_size(Path(m["output"])) == tuple(stack["tile_size"][::-1])
    manifest = json.loads((_entry(cache) / "manifest.json").read_text())
    assert hashlib.sha256(tiles.read_bytes()).hexdigest() == manifest["files"]["tiles.safetensors"]


@pytest.mark.parametrize("name", ["../../escape.png", "/etc/passwd", "a/../../b.png", "..", "sub/../../x.png"])
def test_confine_refuses_paths_leading_out(tmp_path, name):
    out = tmp_path / "out"
    out.mkdir()
    with pytest.raises(InputError, match=r"@.*@: refusing to write outside the output folder"):
        confine(out / name if not name.startswith("/") else name, out)


def test_confine_refuses_symlinks_leading_out(tmp_path):
    out, elsewhere = tmp_path / "out", tmp_path / "elsewhere"
    out.mkdir()
    elsewhere.mkdir()
    (out / "link").symlink_to(elsewhere, target_is_directory=True)
    (out / "tile.png").symlink_to(elsewhere / "tile.png")
    for name in ("link/tile.png", "tile.png"):
        with pytest.raises(InputError, match="outside the output folder"):
            confine(out / name, out)
    assert confine(out / "fine.png", out) == (out / "fine.png").resolve()


@pytest.mark.parametrize("asset", ["../../../../etc/passwd", "/abs/../../x.png", "..\\..\\win.png", "..", "a/.png",
                                   "bríck ñ 木.png", "x" * 500 + ".png"])
@pytest.mark.parametrize("stack_id", ["World_Looks_Brick-e1", "../../..", "/etc", "a/b\\c"])
def test_tile_names_from_hostile_assets_stay_inside(tmp_path, asset, stack_id):
    out = tmp_path / "out"
    out.mkdir()
    name = tile_filename(asset, stack_id, ".png")
    assert "/" not in name and "\\" not in name and not name.startswith(".")
    assert confine(out / name, out).parent == out.resolve()


def test_cache_records_of_another_shape_are_made_again_not_internal_errors(tmp_path, capsys):
    """A manifest or a judged record that is valid JSON of another shape (hand-edited, another tool's) is discarded and
    the stack made again, as a truncated one is: never an internal error on every later run."""
    scene, cache = _scene(tmp_path), tmp_path / "cache"
    code, first, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    assert first["stacks"][0]["origin"] == "trained"
    manifest = _entry(cache) / "manifest.json"
    for text in ('{"format": 1, "files": [], "meta": null}', '{"files": {}, "meta": {}}', "[]"):
        manifest.write_text(text)
        code, again, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
        [stack] = again["stacks"]
        assert stack["origin"] == "trained" and "internal error" not in stack["message"], stack
        assert stack["status"] in ("passed", "not-passed")
    records = list(_entry(cache).glob(f"{JUDGED}/*.json"))
    assert records
    for judged in records:
        judged.write_text("[]")
    code, last, _ = run_cli(capsys, str(scene), "--cache-dir", str(cache))
    assert last["stacks"][0]["origin"] == "cache" and "internal error" not in last["stacks"][0]["message"]

