"""A run again over a stage or document whose new layer / document an earlier run wrote adds its edits to that
output. A texture whose file was set there by hand since (neither its source nor a tile of this tool's) is left as
it is, and its stack says why, instead of being replaced without a word; a tile of an earlier run is replaced."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def _run(path: Path, capsys, *extra: str) -> tuple[int, dict]:
    code = main(["process", str(path), "--preset", "tiny", "--max-size", "128", "--cache-dir",
                 str(path.parents[1] / "cache"), "--json", *extra])
    return code, json.loads(capsys.readouterr().out)


def _swap_first_tile(output: Path, folder: str, by: str) -> str:
    """The output with its first tile path (the albedo's) replaced by ``by``; returns the text written."""
    text = output.read_text()
    start = text.index(f"{folder}/brick_albedo")
    end = min(i for i in (text.find("@", start), text.find('"', start)) if i > 0)
    text = text[:start] + by + text[end:]
    output.write_text(text)
    return text


def test_a_texture_set_by_hand_in_the_new_layer_is_left_as_it_is(tmp_path, capsys):
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    code, first = _run(scene, capsys)
    assert first["stacks"][0]["status"] == "passed"
    layer = scene.with_name("scene.seamless.usda")
    # an earlier run's tiles are replaced: the same stage into another tile folder
    code, moved = _run(scene, capsys, "--output-dir", str(tmp_path / "brick" / "other"))
    assert code == 0 and moved["stacks"][0]["status"] == "passed" and "./other/brick_albedo" in layer.read_text()

    edited = _swap_first_tile(layer, "./other", "../textures/cloth.png")
    code, again = _run(scene, capsys, "--output-dir", str(tmp_path / "brick" / "other"))
    [stack] = again["stacks"]
    assert code == 1 and stack["status"] == "failed"
    assert "Albedo>: its file is set in @scene.seamless.usda@ to @../textures/cloth.png@" in stack["message"]
    assert "set by hand" in stack["message"] and "remove that value from the layer" in stack["message"]
    assert layer.read_text() == edited  # nothing of the stack replaced
    assert "already has these edits" not in json.dumps(again["findings"])


def test_a_texture_set_by_hand_in_the_new_document_is_left_as_it_is(tmp_path, capsys):
    for name in ("mtlx", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    document = tmp_path / "mtlx" / "prefixed.mtlx"
    code, first = _run(document, capsys)
    assert first["stacks"][0]["status"] == "passed"
    output = document.with_name("prefixed.seamless.mtlx")
    edited = _swap_first_tile(output, "tileable", "../textures/cloth.png")
    code, again = _run(document, capsys)
    [stack] = again["stacks"]
    assert code == 1 and stack["status"] == "failed"
    assert "its file is set in" in stack["message"] and "to @../textures/cloth.png@" in stack["message"]
    assert "remove that value from the document" in stack["message"]
    assert output.read_text() == edited


def test_a_hand_edit_in_one_variant_fails_that_variant_s_stack_only(tmp_path, capsys):
    """The prop's floor file is set inside each variant of ``finish``: a file set by hand in the new layer inside
    the cloth variant fails the cloth stack; the wood stack, the same texture node under another selection, keeps
    its status (a refusal was keyed by the node alone, and failed both)."""
    for name in ("prop", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "prop" / "prop.usda"
    code, first = _run(scene, capsys)
    floor = {s["variant"]: s["status"] for s in first["stacks"] if s["material"] == "</Prop/Materials/M_floor>"}
    assert "failed" not in floor.values() and len(floor) == 2
    layer = scene.with_name("prop.seamless.usda")
    text = layer.read_text()
    start = text.index("./tileable/cloth.")
    layer.write_text(text[:start] + "../textures/wood_tileable.jpg" + text[text.index("@", start):])
    code, again = _run(scene, capsys)
    now = {s["variant"]: s for s in again["stacks"] if s["material"] == "</Prop/Materials/M_floor>"}
    [cloth] = [s for v, s in now.items() if "cloth" in v]
    [wood] = [s for v, s in now.items() if "cloth" not in v]
    assert cloth["status"] == "failed" and "set by hand" in cloth["message"]
    assert wood["status"] == floor[wood["variant"]], wood["message"]
