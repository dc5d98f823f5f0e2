"""The Python API and the hooks refuse what the command line refuses, before any work: option values no run can use,
a single path given as a string, materials matching nothing; an open stage whose material is inside an instance is
failed before a tile is written, as ``process_paths`` fails it."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from pxr import Usd

import seamless_usd
from seamless_usd.errors import UsageError

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


@pytest.mark.parametrize("values", [{"seed": -7}, {"seed": 1 << 40}, {"seeds": 0}, {"iterations": -5},
                                    {"max_pixels": 0}])
def test_option_values_no_run_can_use_are_refused(values):
    with pytest.raises(UsageError):
        seamless_usd.Options(preset="tiny", **values)


def test_one_path_or_pattern_given_as_a_string_is_one(tmp_path):
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    options = seamless_usd.Options(preset="tiny", mode=seamless_usd.WriteMode.DRY_RUN, materials="/World/Looks/Brick")
    assert options.materials == ("/World/Looks/Brick",)
    report = seamless_usd.process_paths(str(tmp_path / "brick" / "scene.usda"), options)
    assert report.sources == [str((tmp_path / "brick" / "scene.usda"))] and len(report.stacks) == 1


def test_an_open_stage_refuses_unmatched_materials_and_instanced_stacks_before_any_tile(tmp_path):
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    stage = Usd.Stage.Open(str(tmp_path / "brick" / "scene.usda"))
    with pytest.raises(UsageError, match="matches no material"):
        seamless_usd.process_stage(stage, seamless_usd.Options(preset="tiny", materials=("/World/Looks/Brik*",)))
    shot = Usd.Stage.CreateNew(str(tmp_path / "brick" / "shot.usda"))
    prim = shot.DefinePrim("/Inst")
    prim.GetReferences().AddReference("./scene.usda", "/World")
    prim.SetInstanceable(True)
    report = seamless_usd.process_stage(shot, seamless_usd.Options(preset="tiny", seeds=1))
    assert [s.status.value for s in report.stacks] == ["failed"]
    assert "inside an instance" in report.stacks[0].message and not (tmp_path / "brick" / "tileable").exists()


def test_an_open_stage_keeps_none_of_a_stacks_edits_when_one_of_its_maps_cannot_be_composed(tmp_path):
    """The edit target is a sublayer and the root layer holds a stronger file value for the colour map: that map's
    edit is not composed, so none of the stack's edits are kept (its normal and roughness tiles with a UV scale the
    colour map does not get would no longer line up), and the stack fails saying so."""
    from pxr import Sdf

    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    root = Sdf.Layer.CreateNew(str(tmp_path / "brick" / "root.usda"))
    root.subLayerPaths.append("./scene.usda")
    root.Save()
    stage = Usd.Stage.Open(root)
    stage.GetPrimAtPath("/World/Looks/Brick/Albedo").GetAttribute("inputs:file").Set(
        Sdf.AssetPath("../textures/brick_albedo.png"))
    sub = Sdf.Layer.Find(str(scene))
    before = sub.ExportToString()
    stage.SetEditTarget(Usd.EditTarget(sub))
    report = seamless_usd.process_stage(stage, seamless_usd.Options(preset="tiny", seeds=1, max_size=128))
    [stack] = report.stacks
    assert stack.status.value == "failed" and "stronger value" in stack.message
    assert sub.ExportToString() == before  # none of its edits kept
    assert not stage.GetPrimAtPath("/World/Looks/Brick/SeamlessUV")


def _answers(payload: dict) -> list[tuple]:
    return [(i["name"], i["passed"], i["verdict"].get("strongest"), i["error"], i["note"]) for i in payload["items"]]


def test_check_in_python_gives_the_command_lines_answer_and_refuses_what_is_not_a_path(tmp_path, capsys):
    import json

    from seamless_usd_cli.main import main

    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene, picture = tmp_path / "brick" / "scene.usda", tmp_path / "textures" / "wood_tileable.jpg"
    report = seamless_usd.check([scene, str(picture)])
    code = main(["check", "--json", str(scene), str(picture)])
    payload = json.loads(capsys.readouterr().out)
    assert report.exit_code == code == payload["exit_code"]
    assert _answers(report.to_dict()) == _answers(payload) and len(report.items) == 2
    assert [i.passed for i in report.items] == [False, True]  # the brick photo does not tile; the wood made to does
    one = seamless_usd.check(str(picture))  # one path given as a string is one path
    assert [i.name for i in one.items] == [report.items[1].name]
    for bad in (None, 3, [scene, None]):
        with pytest.raises(UsageError, match="takes a path"):
            seamless_usd.check(bad)
    with pytest.raises(UsageError, match="at least 1"):
        seamless_usd.check(scene, jobs=0)
    for bad in (None, 3):
        with pytest.raises(UsageError, match="takes an open Usd.Stage"):
            seamless_usd.scan(bad)


def test_an_open_stage_with_its_payloads_unloaded_says_so(tmp_path):
    """A hook's stage opened with LoadNone: the materials inside its payloads are not composed, and the scan and
    the run say so instead of finding nothing without a word."""
    import shutil

    from pxr import Usd

    import seamless_usd

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("prop", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    stage = Usd.Stage.Open(str(tmp_path / "prop" / "prop.usda"), Usd.Stage.LoadNone)
    scan = seamless_usd.scan(stage)
    [found] = [f for f in scan.findings if f.code == "unloaded-payload"]
    assert "payload not loaded" in found.message and "stage.Load()" in found.message
    stage.Load()
    assert not [f for f in seamless_usd.scan(stage).findings if f.code == "unloaded-payload"]
    assert seamless_usd.scan(stage).stacks


def test_an_open_stage_referencing_a_materialx_document_gets_its_edits(tmp_path):
    """process_stage on a stage whose material comes from a referenced .mtlx: the document gets a new document
    beside the edit layer, and the reference is pointed at it there (nothing was authored, and the run said
    passed); saved, the stage shows the tiles and check agrees."""
    from pxr import Usd

    import seamless_usd

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("mtlx", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    stage = Usd.Stage.Open(str(tmp_path / "mtlx" / "scene.usda"))
    report = seamless_usd.process_stage(stage, seamless_usd.Options(preset="tiny", max_size=128,
                                                                    cache_dir=tmp_path / "cache"))
    [stack] = report.stacks
    assert str(tmp_path / "mtlx" / "tiled.seamless.mtlx") in map(str, report.layers_written)
    assert "./tiled.seamless.mtlx" in stage.GetRootLayer().ExportToString()
    stage.GetRootLayer().Save()
    checked = seamless_usd.check([tmp_path / "mtlx" / "scene.usda"])
    [item] = checked.items
    assert not item.note and item.passed == (stack.status.value == "passed") and item.maps[0].startswith("tileable/")


def test_a_relative_output_dir_of_an_open_stage_is_the_stage_folders(tmp_path, monkeypatch):
    """A DCC's working folder is anywhere: process_stage takes a relative output_dir from the stage's root layer
    folder, as the hooks do (it wrote into the working folder and authored ../ paths to it)."""
    from pxr import Usd

    import seamless_usd

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    stage = Usd.Stage.Open(str(tmp_path / "brick" / "scene.usda"))
    report = seamless_usd.process_stage(stage, seamless_usd.Options(preset="tiny", max_size=128, output_dir="tiles",
                                                                    cache_dir=tmp_path / "cache"))
    [stack] = report.stacks
    assert all(Path(m.output).parent == tmp_path / "brick" / "tiles" for m in stack.maps)
    assert not list((tmp_path / "elsewhere").iterdir())


def test_a_file_with_unsaved_changes_in_this_process_is_not_read_as_if_on_disk(tmp_path):
    """process_stage authored into a stage and did not save it: process_paths and check on that file name the
    unsaved changes instead of reading the edited layer held in memory as if it were the file."""
    from pxr import Usd

    import seamless_usd

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    stage = Usd.Stage.Open(str(scene))
    options = seamless_usd.Options(preset="tiny", max_size=128, cache_dir=tmp_path / "cache")
    seamless_usd.process_stage(stage, options)
    assert stage.GetRootLayer().dirty
    report = seamless_usd.process_paths([scene], options)
    assert report.exit_code == 2 and "unsaved changes" in report.findings[-1].message
    checked = seamless_usd.check([scene])
    assert checked.exit_code != 0 and "unsaved changes" in (checked.items[0].error if checked.items else
                                                              str(checked.to_dict()))
    stage.GetRootLayer().Save()
    assert seamless_usd.check([scene]).exit_code == 0


def test_options_of_the_wrong_type_an_empty_setting_and_no_paths_are_said_plainly(tmp_path, monkeypatch):
    """``Options(output_dir=5)`` and ``Options(materials=(5,))`` raised raw TypeErrors part-way; ``cache_dir=""`` (a
    hook's empty field) put the cache in the working folder; ``check([])`` and ``process_paths([])`` returned exit
    code 0 having judged nothing (the command takes at least one path)."""
    for values in ({"output_dir": 5}, {"materials": (5,)}, {"report": 1.5}):
        with pytest.raises(UsageError):
            seamless_usd.Options(preset="tiny", **values)
    assert seamless_usd.Options(preset="tiny", cache_dir="").cache_dir is None
    assert seamless_usd.Options(preset="tiny", materials=["*Brick"]).materials == ("*Brick",)
    with pytest.raises(UsageError):
        seamless_usd.check([])
    with pytest.raises(UsageError):
        seamless_usd.process_paths([], seamless_usd.Options(preset="tiny"))


def test_a_stage_that_is_not_there_is_reported_not_raised_and_named_once(tmp_path):
    """``process_paths`` on a library goes on past a file it cannot read (one failing input never stops a batch): the
    report says so with exit code 2, naming the file once (it read '@x@: @x@ does not exist')."""
    report = seamless_usd.process_paths([tmp_path / "nope.usda"], seamless_usd.Options(preset="tiny"))
    [finding] = report.findings
    assert report.exit_code == 2 and finding.code == "unreadable-input"
    assert finding.where.endswith("nope.usda@") and "nope.usda" not in finding.message
