"""`seamless-usd scan`: table output, --json against the schema, exit codes."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import jsonschema
import pytest

from seamless_usd_cli.main import main
from seamless_usd_schemas import json_schema


def _validate(doc: dict) -> None:
    jsonschema.validate(doc, json_schema("scan"), cls=jsonschema.Draft202012Validator)


def test_schema_is_valid_json_schema():
    jsonschema.Draft202012Validator.check_schema(json_schema("scan"))


def test_table_lists_maps_roles_and_colour_spaces(samples_dir, capsys):
    assert main(["scan", str(samples_dir / "brick" / "scene.usda")]) == 0
    out = capsys.readouterr().out
    assert "</World/Looks/Brick>" in out
    for text in ("brick_albedo.png", "brick_normal.png", "brick_roughness.png", "diffuseColor (rgb)",
                 "roughness (r)", "256x256", "primvar st"):
        assert text in out


def test_json_validates_against_schema(samples_dir, capsys):
    assert main(["scan", "--json", str(samples_dir / "brick" / "scene.usda")]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc)
    assert len(doc["stacks"]) == 1 and len(doc["stacks"][0]["maps"]) == 3


def test_unreadable_stage_exits_2_naming_the_file(tmp_path, capsys):
    bad = tmp_path / "broken.usda"
    bad.write_text("#usda 1.0\ndef Xform \"A\" {\n  this is not usd\n")
    assert main(["scan", str(bad)]) == 2
    out, err = capsys.readouterr()
    assert "broken.usda" in err and len(err.strip().splitlines()) == 1
    assert not out.strip()  # nothing was read: no "scanned" line naming nothing, no table repeating the error


def test_a_picture_given_to_scan_or_process_is_pointed_to_check(tmp_path, samples_dir, capsys):
    picture = samples_dir / "textures" / "brick_albedo.png"
    for command in ("scan", "process"):
        assert main([command, str(picture)]) == 2
        err = capsys.readouterr().err
        assert "is a picture" in err and "seamless-usd check" in err and "Cannot determine file format" not in err
    other = tmp_path / "notes.txt"
    other.write_text("not a scene")
    assert main(["scan", str(other)]) == 2
    assert "neither a USD stage nor a MaterialX document" in capsys.readouterr().err


def test_missing_path_exits_2(tmp_path, capsys):
    assert main(["scan", str(tmp_path / "nope.usda")]) == 2
    assert "nope.usda" in capsys.readouterr().err


def test_parse_error_message_is_short(tmp_path, capsys):
    bad = tmp_path / "broken.usda"
    bad.write_text('#usda 1.0\ndef Xform "A" (\n  kind = \n) {}\n')
    assert main(["scan", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("seamless-usd: error: @") and "textParserHelpers" not in err


def test_skipped_items_still_exit_0_and_are_listed(tmp_path, samples_dir, capsys):
    scene = tmp_path / "s.usda"
    text = (samples_dir / "brick" / "scene.usda").read_text()
    text = text.replace("@../textures/brick_roughness.png@", "@./missing_roughness.png@")
    scene.write_text(text.replace("@../textures/", f"@{(samples_dir / 'textures').as_posix()}/"))
    assert main(["scan", str(scene)]) == 0
    out = capsys.readouterr().out
    assert "missing-file" in out and "missing_roughness.png" in out and "brick_albedo.png" in out
    assert main(["scan", "--json", str(scene)]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc)
    assert [f["code"] for f in doc["findings"]] == ["missing-file"]
    assert len(doc["stacks"][0]["maps"]) == 2


def test_several_paths_and_mtlx_documents_in_one_scan(samples_dir, capsys):
    paths = [str(samples_dir / "mtlx" / "tiled.mtlx"), str(samples_dir / "mtlx" / "prefixed.mtlx"),
             str(samples_dir / "transform2d" / "scene.usda")]
    assert main(["scan", "--json", *paths]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc)
    assert doc["materials"] == ["<M_wood>", "<M_brick>", "</World/Looks/Wood>"]
    assert main(["scan", *paths]) == 0
    out = capsys.readouterr().out
    assert "uvtiling scale 2,2" in out and "UsdTransform2d scale 3,3" in out


def test_unreadable_mtlx_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.mtlx"
    bad.write_text("<materialx")
    assert main(["scan", str(bad)]) == 2
    assert "bad.mtlx" in capsys.readouterr().err


def test_mtlx_reference_causes_no_usd_warning_noise(samples_dir, capfd):
    assert main(["scan", str(samples_dir / "mtlx" / "scene.usda")]) == 0
    captured = capfd.readouterr()
    assert "</World/Looks/Wood>" in captured.out and captured.err == ""


def test_scan_starts_without_torch():
    """``scan`` reads headers and a few pixels: torch (over a second to import) is not loaded for it, and the
    package sets OMP_WAIT_POLICY before any step first imports torch."""
    code = ("import os, sys; from seamless_usd_cli.main import main; "
            f"main(['scan', {str(Path(__file__).resolve().parents[1] / 'sample_assets' / 'brick' / 'scene.usda')!r}]); "
            "print('torch' in sys.modules, os.environ.get('OMP_WAIT_POLICY'))")
    env = {k: v for k, v in os.environ.items() if k != "OMP_WAIT_POLICY"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == "False PASSIVE"


def test_two_stages_whose_materials_share_a_path_are_scanned_apart(tmp_path, capsys):
    """``scan a/scene.usda b/scene.usda``: each stage's /World/Looks/Brick is a material and a stack of its own,
    named with its stage, as ``process`` takes them; neither stage's maps are lost or mixed into the other's."""
    import shutil

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    shutil.copytree(samples / "textures", tmp_path / "textures")
    scene = (samples / "brick" / "scene.usda").read_text()
    for name, text in (("a", scene), ("b", scene.replace("brick_albedo.png", "wood_color.png"))):
        (tmp_path / name).mkdir()
        (tmp_path / name / "scene.usda").write_text(text)
    paths = [str(tmp_path / "a" / "scene.usda"), str(tmp_path / "b" / "scene.usda")]
    assert main(["scan", *paths, "--json"]) == 0
    found = json.loads(capsys.readouterr().out)
    assert [s["source"] for s in found["stacks"]] == [str(Path(p).resolve()) for p in paths]
    albedo = [Path(s["maps"][0]["asset"]).name for s in found["stacks"]]
    assert albedo == ["brick_albedo.png", "wood_color.png"] and all(len(s["maps"]) == 3 for s in found["stacks"])
    assert len(found["materials"]) == 2
    assert main(["scan", *paths]) == 0
    out = capsys.readouterr().out
    assert "of a/scene.usda" in out and "of b/scene.usda" in out


def test_a_library_with_one_broken_stage_is_still_scanned_and_json_names_it(tmp_path, capsys):
    """One stage that cannot be opened in a folder: the others are scanned and --json still prints the scan, the
    broken one an error finding (nothing was printed at all), with exit code 2 and its one line on stderr."""
    import shutil

    from seamless_usd_cli.main import main

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "broken.usda").write_text("#usda 1.0\ndef broken {\n")
    assert main(["scan", "--json", str(tmp_path)]) == 2
    out, err = capsys.readouterr()
    result = json.loads(out)
    assert [s["material"] for s in result["stacks"]] == ["</World/Looks/Brick>"]
    [found] = [f for f in result["findings"] if f["code"] == "unreadable-input"]
    assert "broken.usda" in found["where"] and "broken.usda" in err


def test_a_texture_whose_pixels_do_not_decode_is_named_by_scan_and_fails_its_stack_in_process(tmp_path, model_cache,
                                                                                               capsys):
    """A truncated PNG reads its header, so it was classed ``tiling`` with the decode error only in the intent's reason:
    no finding, and a pipeline reading the codes sent it on. Now an ``unreadable-file`` finding names it, as for a file
    whose header does not read, and ``process`` fails its stack before any work, naming it."""
    import shutil

    from runchecks import PLUMBING
    from test_reliability_inputs import write_scene

    textures = tmp_path / "textures"
    textures.mkdir()
    whole = (Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "brick_albedo.png").read_bytes()
    (textures / "cut.png").write_bytes(whole[: len(whole) // 2])
    shutil.copy(Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "cloth.png", textures)
    scene = write_scene(tmp_path / "looks" / "scene.usda", {"Cut": "../textures/cut.png", "Cloth": "../textures/cloth.png"})
    assert main(["scan", str(scene), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    _validate(payload)
    [finding] = [f for f in payload["findings"] if "cut.png" in f["where"]]
    assert finding["code"] == "unreadable-file" and finding["severity"] == "skipped"
    assert "truncated or corrupt" in finding["message"]
    code = main(["process", *PLUMBING, "--max-size", "112", "--json", "--cache-dir", str(model_cache), str(scene)])
    rows = {s["material"]: s for s in json.loads(capsys.readouterr().out)["stacks"]}
    assert code == 1
    assert rows["</Root/Looks/Cut>"]["status"] == "failed" and "cut.png" in rows["</Root/Looks/Cut>"]["message"]
    assert rows["</Root/Looks/Cloth>"]["status"] in ("passed", "not-passed")


def test_scan_says_what_process_will_do_with_a_stack_inside_a_package(tmp_path, capsys):
    """A stack meant to tile whose maps are inside a .usdz: the scan said ``intent: tiling`` and nothing more, while
    process leaves it alone (its maps are not read from inside a package). The scan now says so."""
    from pxr import Sdf, Usd, UsdUtils

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    flat = tmp_path / "flat.usda"
    Usd.Stage.Open(str(samples / "brick" / "scene.usda")).Export(str(flat))
    package = tmp_path / "brick.usdz"
    assert UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath(str(flat)), str(package))
    assert main(["scan", str(package)]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "process: left alone:" in out and "inside a .usdz package" in out, out[-600:]
    assert "1 tiling; 1 that process will not make)" in out
    # the JSON said nothing of it: a pipeline reading it planned a stack that process then leaves alone
    assert main(["scan", str(package), "--json"]) == 0
    payload = json.loads(capsys.readouterr().out)
    jsonschema.validate(payload, json_schema("scan"))
    [stack] = payload["stacks"]
    assert stack["not_made"].startswith("left alone:") and "inside a .usdz package" in stack["not_made"]


def test_a_library_scan_lists_its_folder_and_each_copy_of_a_stack_in_one_line(tmp_path, capsys):
    """A library of 200 files listed every path before the first stack (65 lines) and printed each of 149 copies of a
    stack in full (11 lines each): the folder once, and a copy in one line naming the stack it copies."""
    import shutil

    from test_reliability_inputs import write_scene

    lib = tmp_path / "lib"
    (lib / "textures").mkdir(parents=True)
    shutil.copy(Path(__file__).resolve().parents[1] / "sample_assets" / "textures" / "cloth.png", lib / "textures")
    for n in range(6):  # six props, each with its own material reading the library's one cloth texture
        write_scene(lib / f"prop{n}" / "asset.usda", {f"Cloth{n}": "../textures/cloth.png"})
    assert main(["scan", str(lib)]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert lines[0] == f"scanned 6 files under {lib}"
    copies = [line for line in lines if "the same maps as </Root/Looks/Cloth0>" in line]
    assert len(copies) == 5 and out.count("@../textures/cloth.png@") == 1, out  # the first listed in full
