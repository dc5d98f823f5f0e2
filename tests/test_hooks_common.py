"""The DCC-independent part of the export hooks, without any DCC."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from seamless_usd.errors import InputError, UsageError
from seamless_usd.findings import Finding, Severity
from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookError, HookSettings, Level


# --- settings ----------------------------------------------------------------------------------


def test_defaults_mean_library_defaults():
    s = HookSettings()
    assert (s.enabled, s.preset, s.materials, s.output_dir, s.dry_run, s.strict) == (
        True, "default", (), "", False, False
    )


@pytest.mark.parametrize(
    "value, expected",
    [(True, True), (False, False), (1, True), (0, False), ("1", True), ("On", True), ("yes", True),
     ("false", False), ("0", False), ("", False)],
)
def test_parse_bool(value, expected):
    assert common.parse_bool(value) is expected


def test_parse_bool_rejects_other_text():
    with pytest.raises(UsageError, match="yes/no"):
        common.parse_bool("maybe")


@pytest.mark.parametrize(
    "value, expected",
    [
        ("", ()),
        (None, ()),
        ("/root/_materials/Brick*", ("/root/_materials/Brick*",)),
        ("/a*, /b ;/c  /d", ("/a*", "/b", "/c", "/d")),
        (["/a", " /b "], ("/a", "/b")),
    ],
)
def test_parse_patterns(value, expected):
    assert common.parse_patterns(value) == expected


def test_settings_from_maya_chaser_args_all_strings():
    s = common.settings_from_mapping(
        {"preset": "draft", "materials": "/Looks/Brick*,/Looks/Wood", "seed": "7", "dry_run": "1",
         "max_size": "128", "iterations": "", "strict": "true", "enabled": "on", "straighten": "1"}
    )
    assert s == HookSettings(preset="draft", materials=("/Looks/Brick*", "/Looks/Wood"), seed=7, dry_run=True,
                             max_size=128, iterations=0, strict=True, enabled=True, straighten=True)


def test_settings_from_houdini_parms_strip_prefix_and_ignore_other_parms():
    s = common.settings_from_mapping(
        {"seamlessusd_enabled": 1, "seamlessusd_preset": "", "seamlessusd_seed": 3, "lopoutput": "$HIP/x.usd"},
        prefix="seamlessusd_",
    )
    assert s == HookSettings(enabled=True, preset="default", seed=3)


def test_unknown_setting_names_the_valid_ones():
    with pytest.raises(UsageError, match="unknown seamless-usd hook setting 'presett'.*preset"):
        common.settings_from_mapping({"presett": "draft"})


def test_bad_value_names_the_setting():
    with pytest.raises(UsageError, match="'seed'.*whole number"):
        common.settings_from_mapping({"seed": "three"})


def test_settings_from_attributes_reads_preferences_like_objects():
    prefs = SimpleNamespace(enabled=False, preset="paper", materials="/M/*", seed=2, site_packages="/opt/sp")
    s = common.settings_from_attributes(prefs)
    assert s == HookSettings(enabled=False, preset="paper", materials=("/M/*",), seed=2)


def test_chaser_args_round_trip():
    s = HookSettings(preset="draft", materials=("/a*", "/b"), seed=4, dry_run=True, max_size=64)
    args = common.settings_to_chaser_args("seamless_usd", s)
    assert all(a[0] == "seamless_usd" for a in args)
    assert common.settings_from_mapping({name: value for _, name, value in args}) == s
    assert common.settings_to_chaser_args("seamless_usd", HookSettings()) == []


# --- output folder ------------------------------------------------------------------------------


def test_output_dir_blank_on_disk_is_library_default(tmp_path):
    assert common.resolve_output_dir("", layer_dir=tmp_path) is None


def test_output_dir_blank_in_memory_uses_export_path(tmp_path):
    out = common.resolve_output_dir("", layer_dir=None, export_path=tmp_path / "scene.usdz")
    assert out == tmp_path / "tileable"


def test_output_dir_blank_in_memory_without_export_path_is_a_usage_error():
    with pytest.raises(UsageError, match="in memory"):
        common.resolve_output_dir("", layer_dir=None)


def test_output_dir_relative_is_from_the_exported_layer(tmp_path):
    # For a .usdz export the layer is in the DCC's staging folder: maps land there and get packaged.
    staging = tmp_path / "staging"
    out = common.resolve_output_dir("maps/tiles", layer_dir=staging, export_path=tmp_path / "scene.usdz")
    assert out == staging / "maps" / "tiles"


def test_output_dir_relative_in_memory_needs_export_path(tmp_path):
    assert common.resolve_output_dir("maps", layer_dir=None, export_path=tmp_path / "a.usd") == tmp_path / "maps"
    with pytest.raises(UsageError, match="relative"):
        common.resolve_output_dir("maps", layer_dir=None)


def test_output_dir_absolute_and_expanded(tmp_path, monkeypatch):
    monkeypatch.setenv("SEAMLESS_TEST_ROOT", str(tmp_path))
    assert common.resolve_output_dir("$SEAMLESS_TEST_ROOT/out", layer_dir=None) == tmp_path / "out"
    assert common.resolve_output_dir(str(tmp_path / "abs"), layer_dir=Path("/elsewhere")) == tmp_path / "abs"


# --- options (the real seamless_usd.Options) ------------------------------------------------------


def _real_options():
    import seamless_usd

    return seamless_usd.Options, seamless_usd.WriteMode


def _stage_on_disk(tmp_path: Path):
    from pxr import Usd

    return Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))


def test_options_for_stage_maps_every_setting(tmp_path):
    Options, WriteMode = _real_options()
    stage = _stage_on_disk(tmp_path)
    s = HookSettings(preset="draft", materials=("/M/*",), output_dir="maps", device="cpu", seed=5, dry_run=True,
                     report="report.html", cache_dir=str(tmp_path / "cache"), max_size=64, iterations=10, seeds=2,
                     straighten=True)
    o = common.options_for_stage(s, stage)
    assert isinstance(o, Options)
    assert o.straighten and not o.write_straight  # at export the asset keeps its look: the UVs turn the tile back
    assert (o.preset, o.materials, o.device, o.seed, o.max_size, o.iterations, o.seeds) == (
        "draft", ("/M/*",), "cpu", 5, 64, 10, 2)
    assert o.output_dir == tmp_path.resolve() / "maps"
    assert o.report == tmp_path.resolve() / "report.html"
    assert o.cache_dir == tmp_path / "cache"
    assert o.mode == WriteMode.DRY_RUN


def test_options_for_stage_leaves_defaults_alone(tmp_path):
    Options, _ = _real_options()
    o = common.options_for_stage(HookSettings(), _stage_on_disk(tmp_path))
    d = Options()
    assert (o.output_dir, o.device, o.report, o.cache_dir, o.max_size, o.iterations, o.seeds, o.mode,
            o.straighten) == (d.output_dir, d.device, d.report, d.cache_dir, d.max_size, d.iterations, d.seeds, d.mode,
                              d.straighten)


def test_options_for_in_memory_stage_need_a_folder(tmp_path):
    _real_options()
    from pxr import Usd

    stage = Usd.Stage.CreateInMemory()
    with pytest.raises(UsageError):
        common.options_for_stage(HookSettings(), stage)
    o = common.options_for_stage(HookSettings(), stage, export_path=tmp_path / "x.usdz")
    assert o.output_dir == tmp_path / "tileable"


# --- report to log lines -------------------------------------------------------------------------


def _fake_report(statuses=("passed",), findings=(), exit_code=0):
    stacks = [
        SimpleNamespace(
            status=SimpleNamespace(value=st), material=f"/root/_materials/M{i}", message="" if st == "passed" else "why",
            uv_scale=(2.0, 2.0),
            maps=[SimpleNamespace(asset="./textures/a.png", output=f"/out/tileable/a{i}.png")],
        )
        for i, st in enumerate(statuses)
    ]
    return SimpleNamespace(stacks=stacks, findings=list(findings), exit_code=exit_code, unreadable=[])


def test_report_lines_levels_and_usd_notation():
    finding = Finding(Severity.SKIPPED, "udim", "<@/M/T>", "UDIM tiles are not processed")
    lines = common.report_lines(_fake_report(("passed", "not-passed", "failed"), [finding], exit_code=1))
    assert lines[0].level is Level.WARNING and "3 stack(s)" in lines[0].text and "exit code 1" in lines[0].text
    by_text = {ln.text: ln.level for ln in lines}
    assert by_text["seamless-usd: passed: </root/_materials/M0> uv scale (2, 2)"] is Level.INFO
    assert by_text["seamless-usd: not-passed: </root/_materials/M1> uv scale (2, 2): why"] is Level.WARNING
    assert by_text["seamless-usd: failed: </root/_materials/M2> uv scale (2, 2): why"] is Level.ERROR
    assert "seamless-usd:   @./textures/a.png@ -> @/out/tileable/a0.png@" in by_text
    assert by_text[f"seamless-usd: {finding}"] is Level.INFO


def test_report_lines_with_the_real_report_model():
    from seamless_usd.report import model
    report = model.Report(
        stacks=[model.StackReport(id="s", material="/M", source="scene.usda", status=model.StackStatus.PASSED)],
        findings=[Finding(Severity.ERROR, "read", "@x.png@", "cannot read")],
    )
    lines = common.report_lines(report)
    assert lines[0].text.startswith("seamless-usd: 1 stack(s): 1 passed")
    assert lines[-1].level is Level.ERROR
    assert str(lines[-1]) == "error: seamless-usd: @x.png@: cannot read"


def test_progress_logger_logs_stack_start_long_stages_and_end_only():
    got = []
    progress = common.progress_logger(got.append)
    progress(SimpleNamespace(kind="stack-start", stack_id="brick", index=0, total=2))
    progress(SimpleNamespace(kind="stage", stack_id="brick", index=0, total=2, detail="writing the maps"))
    progress(SimpleNamespace(kind="train", stack_id="brick", index=0, total=2))
    progress(SimpleNamespace(kind="stack-done", stack_id="brick", index=0, total=2,
                             detail=SimpleNamespace(passed=True)))  # the job's outcome
    progress(SimpleNamespace(kind="stack-done", stack_id="wood", index=1, total=2, detail=ValueError("broken")))
    assert [ln.text for ln in got] == ["seamless-usd: stack 1/2: brick", "seamless-usd: stack 1/2: writing the maps",
                                       "seamless-usd: stack 1/2 passed", "seamless-usd: stack 2/2 failed"]


def test_progress_logger_forwards_every_event():
    seen = []
    progress = common.progress_logger(lambda _: None, seen.append)
    events = [SimpleNamespace(kind=k, stack_id="s", index=0, total=1) for k in ("stack-start", "train", "sample")]
    for e in events:
        progress(e)
    assert seen == events


# --- run_hook --------------------------------------------------------------------------------------


class _Recorder:
    def __init__(self, result=None, error=None):
        self.calls = []
        self.result = result if result is not None else _fake_report()
        self.error = error

    def __call__(self, stage, options):
        self.calls.append((stage, options))
        if self.error:
            raise self.error
        return self.result


def test_run_hook_passes_the_stage_and_logs_the_report(tmp_path):
    _real_options()
    stage = _stage_on_disk(tmp_path)
    rec, lines = _Recorder(), []
    run = common.run_hook(stage, HookSettings(preset="draft"), emit=lines.append, process=rec)
    assert run.ok and run.report is rec.result
    assert rec.calls[0][0] is stage and rec.calls[0][1].preset == "draft"
    assert callable(rec.calls[0][1].progress)
    assert lines == run.lines and lines[0].text.startswith("seamless-usd: 1 stack(s)")


def test_run_hook_disabled_does_nothing(tmp_path):
    rec = _Recorder()
    run = common.run_hook(object(), HookSettings(enabled=False), emit=lambda _: None, process=rec)
    assert rec.calls == [] and run.report is None and run.ok


def test_run_hook_expected_error_is_one_line_and_the_export_goes_on(tmp_path):
    _real_options()
    rec, lines = _Recorder(error=InputError("@x.png@ cannot be read")), []
    run = common.run_hook(_stage_on_disk(tmp_path), HookSettings(), emit=lines.append, process=rec)
    assert not run.ok and run.report is None
    assert [ln.text for ln in lines] == ["seamless-usd: @x.png@ cannot be read"]


def test_run_hook_unexpected_error_logs_traceback(tmp_path):
    _real_options()
    lines = []
    run = common.run_hook(_stage_on_disk(tmp_path), HookSettings(), emit=lines.append,
                          process=_Recorder(error=ZeroDivisionError("boom")))
    assert not run.ok and lines[-1].level is Level.ERROR and "ZeroDivisionError: boom" in lines[-1].text


def test_run_hook_strict_raises_after_logging(tmp_path):
    _real_options()
    lines = []
    stage = _stage_on_disk(tmp_path)
    with pytest.raises(HookError, match="boom"):
        common.run_hook(stage, HookSettings(strict=True), emit=lines.append,
                        process=_Recorder(error=RuntimeError("boom")))
    assert lines and lines[-1].level is Level.ERROR
    with pytest.raises(HookError, match="failed"):
        common.run_hook(stage, HookSettings(strict=True), emit=lambda _: None,
                        process=_Recorder(result=_fake_report(("failed",), exit_code=1)))


def test_run_hook_not_passed_is_not_a_failure_even_strict(tmp_path):
    _real_options()
    run = common.run_hook(_stage_on_disk(tmp_path), HookSettings(strict=True), emit=lambda _: None,
                          process=_Recorder(result=_fake_report(("not-passed",), exit_code=1)))
    assert run.ok


def test_run_hook_usage_error_for_in_memory_stage_without_folder():
    _real_options()
    from pxr import Usd

    rec, lines = _Recorder(), []
    run = common.run_hook(Usd.Stage.CreateInMemory(), HookSettings(), emit=lines.append, process=rec)
    assert rec.calls == [] and not run.ok and "in memory" in lines[0].text


# --- process_layer (Houdini output processors get layers, not stages) -----------------------------


def _texture_layer(asset: str):
    from pxr import Sdf, Usd, UsdShade

    stage = Usd.Stage.CreateInMemory()
    shader = UsdShade.Shader.Define(stage, "/Looks/M/Tex")
    shader.CreateIdAttr("UsdUVTexture")
    shader.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(asset)
    return stage, stage.GetRootLayer()  # the stage keeps the anonymous layer alive


def test_process_layer_anchors_an_anonymous_layer_at_its_save_path(tmp_path):
    _real_options()
    from pxr import Sdf, UsdShade

    _keep, layer = _texture_layer("./textures/a.png")
    seen = {}

    def process(stage, options):
        root = stage.GetRootLayer()
        seen["identifier"], seen["output_dir"] = root.identifier, options.output_dir
        seen["resolved"] = Sdf.ComputeAssetPathRelativeToLayer(root, "./textures/a.png")
        UsdShade.Shader(stage.GetPrimAtPath("/Looks/M/Tex")).GetInput("file").Set("./tileable/a.png")
        return _fake_report()

    save = tmp_path / "out" / "scene.usda"
    run = common.process_layer(layer, save, HookSettings(), emit=lambda _: None, process=process)
    assert run.ok and run.report is not None
    assert seen["identifier"] == str(save.resolve())
    assert Path(seen["resolved"]) == save.resolve().parent / "textures" / "a.png"
    assert seen["output_dir"] is None  # library default: <save dir>/tileable
    assert layer.GetAttributeAtPath("/Looks/M/Tex.inputs:file").default.path == "./tileable/a.png"
    assert not save.exists()  # nothing saved: the DCC saves the layer
    # a layer of that name open already (a node loading the last save): relative paths still resolve from its
    # folder (they resolved from nowhere, and every map was missing)
    save.parent.mkdir()
    save.write_text("#usda 1.0\n")
    held = Sdf.Layer.FindOrOpen(str(save))
    _keep2, layer2 = _texture_layer("./textures/a.png")
    run = common.process_layer(layer2, save, HookSettings(), emit=lambda _: None, process=process)
    assert run.ok and held and Path(seen["identifier"]).parent == save.resolve().parent
    assert Path(seen["resolved"]) == save.resolve().parent / "textures" / "a.png"
    assert layer2.GetAttributeAtPath("/Looks/M/Tex.inputs:file").default.path == "./tileable/a.png"
    assert [p.name for p in save.parent.iterdir()] == ["scene.usda"]  # the scratch layer is never saved


def test_a_layer_on_disk_saved_elsewhere_is_processed_where_it_is_and_says_so(tmp_path):
    """Its relative paths, the tiles' among them, are meant from its own folder: saved elsewhere without the DCC
    rewriting them, they point at nothing there. It said nothing and reported the export fine."""
    _real_options()
    from pxr import Sdf

    stage, _ = _texture_layer("./textures/a.png")
    stage.GetRootLayer().Export(str(tmp_path / "scene.usda"))
    layer = Sdf.Layer.FindOrOpen(str(tmp_path / "scene.usda"))
    rec, lines = _Recorder(), []
    run = common.process_layer(layer, tmp_path / "out" / "scene.usda", HookSettings(), emit=lines.append, process=rec)
    [(processed, _)] = rec.calls
    assert processed.GetRootLayer() is layer  # processed where it is: its sources resolve from its own folder
    [moved] = [line for line in run.lines if "saved to" in line.text]
    assert moved.level.value == "warning" and moved in lines and str(tmp_path / "out" / "scene.usda") in moved.text
    run = common.process_layer(layer, tmp_path / "scene.usda", HookSettings(), emit=lines.append, process=rec)
    assert not [line for line in run.lines if "saved to" in line.text]  # saved where it is: nothing to say


def test_process_layer_skips_layers_without_textures(tmp_path):
    from pxr import Sdf

    rec = _Recorder()
    run = common.process_layer(Sdf.Layer.CreateAnonymous(), tmp_path / "a.usda", HookSettings(), process=rec)
    assert rec.calls == [] and run.report is None and run.ok


def test_process_layer_recognises_materialx_image_nodes(tmp_path):
    _real_options()
    from pxr import Usd, UsdShade

    stage = Usd.Stage.CreateInMemory()
    UsdShade.Shader.Define(stage, "/Looks/M/img").CreateIdAttr("ND_image_color3")
    rec = _Recorder()
    common.process_layer(stage.GetRootLayer(), tmp_path / "a.usda", HookSettings(), emit=lambda _: None, process=rec)
    assert len(rec.calls) == 1


# --- import weight ----------------------------------------------------------------------------------


def test_importing_the_hooks_pulls_in_no_dcc_pxr_or_torch():
    code = (
        "import sys, seamless_usd.hooks.common, seamless_usd.hooks.houdini; "
        "bad = [m for m in ('bpy', 'hou', 'maya', 'mayaUsd', 'pxr', 'torch') if m in sys.modules]; "
        "print(bad); sys.exit(1 if bad else 0)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_a_stack_that_failed_is_logged_once_not_again_as_its_finding(tmp_path):
    """A material left alone because one of its files cannot be read: its stack line says why, and the error finding
    saying the same of the same material is not logged a second time (the file's own finding still is)."""
    import shutil

    import seamless_usd

    samples = Path(__file__).resolve().parents[1] / "sample_assets"
    for name in ("brick", "textures"):
        shutil.copytree(samples / name, tmp_path / name)
    (tmp_path / "textures" / "brick_roughness.png").write_bytes(b"\x89PNG\r\n\x1a\n not really a png")
    report = seamless_usd.process_paths(tmp_path / "brick" / "scene.usda", seamless_usd.Options(
        preset="tiny", mode=seamless_usd.WriteMode.DRY_RUN, cache_dir=tmp_path / "cache"))
    [stack] = report.stacks
    assert stack.status.value == "failed" and any(f.message == stack.message for f in report.findings)
    lines = [ln.text for ln in common.report_lines(report)]
    assert sum(stack.message in text for text in lines) == 1, lines
    assert any("brick_roughness.png" in text and "cannot read the image header" in text for text in lines)


def test_a_failed_run_fails_the_export_only_when_strict(tmp_path):
    """Blender's ``on_export`` returned the run's own ``ok``, so a stack that did not pass failed Blender's export
    even without ``strict``, where Maya's chaser let it go on; both now answer through :func:`common.export_ok`."""
    _real_options()
    run = common.run_hook(_stage_on_disk(tmp_path), HookSettings(), emit=lambda _: None,
                          process=_Recorder(error=InputError("@x.png@ cannot be read")))
    assert not run.ok
    assert common.export_ok(run, HookSettings()) and not common.export_ok(run, HookSettings(strict=True))
    assert common.export_ok(common.HookRun(), HookSettings(strict=True))


def test_a_hook_step_that_fails_never_takes_the_export_down_unless_strict(tmp_path):
    """Blender's per-material step (writing the textures an export left unwritten) ran unguarded: a read-only export
    folder raised into Blender and failed the export, whatever ``strict`` said."""
    from seamless_usd.fileio import atomic_write_bytes

    blocked = tmp_path / "file"
    blocked.write_text("x")
    write = lambda: atomic_write_bytes(blocked / "albedo.png", b"png")  # a folder that is a file: cannot be written
    lines = []
    assert common.run_guarded(write, HookSettings(), "writing textures", emit=lines.append) is False
    [line] = lines
    assert line.level.value == "error" and "writing textures" in line.text and "albedo.png" in line.text
    assert "Traceback" not in line.text  # an expected error: one line
    crash = lambda: {}["missing"]
    assert common.run_guarded(crash, HookSettings(), "writing textures", emit=lines.append) is False
    assert "Traceback" in lines[-1].text  # an unexpected one: its traceback
    with pytest.raises(HookError, match="writing textures"):
        common.run_guarded(write, HookSettings(strict=True), "writing textures", emit=lines.append)
    assert common.run_guarded(lambda: None, HookSettings(), "writing textures", emit=lines.append) is True


def test_a_setting_no_run_can_use_is_named_as_the_hooks_setting(tmp_path):
    """A DCC user sets ``max_size`` in the exporter; the log said '--max-size 50 ...', a flag they never saw."""
    stage, _ = _texture_layer("./textures/a.png")
    lines = []
    run = common.run_hook(stage, HookSettings(preset="tiny", max_size=50, output_dir=str(tmp_path)), emit=lines.append)
    [line] = lines
    assert not run.ok and "the max_size setting 50" in line.text and "--max-size" not in line.text
    assert common.setting_words("--max-size 50; --no-such-flag; see --device") == (
        "the max_size setting 50; --no-such-flag; see the device setting")
