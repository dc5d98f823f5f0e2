"""The Maya and Houdini adapters, run against stand-ins for their DCC modules.

The real ``mayaUsd.lib`` / ``hou`` / ``husd`` exist only inside the DCCs; these stand-ins have just
the names the adapters use, so the wiring (settings in, stage to ``process_stage``, result out) is
exercised here. The Blender hook runs for real in ``tests_blender/``.
"""
from __future__ import annotations

import importlib
import importlib.util
import sys
import types
from pathlib import Path
from types import SimpleNamespace

import pytest

import seamless_usd
from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookError, HookSettings


class _Recorder:
    def __init__(self):
        self.calls = []

    def __call__(self, stage, options):
        self.calls.append((stage, options))
        return SimpleNamespace(stacks=[], findings=[], exit_code=0, unreadable=[])


@pytest.fixture()
def recorder(monkeypatch):
    rec = _Recorder()
    monkeypatch.setattr(common, "_default_process", rec)
    return rec


# --- Maya ---------------------------------------------------------------------------------------


@pytest.fixture()
def maya_chaser(monkeypatch):
    registered = {}

    class ExportChaser:
        def __init__(self, factoryContext, *args, **kwargs):
            self.factory_context = factoryContext

        @staticmethod
        def Register(cls, name):
            registered[name] = cls

        @staticmethod
        def Unregister(cls, name):
            registered.pop(name, None)

    class JobContextRegistry:
        contexts = {}

        @staticmethod
        def RegisterExportJobContext(name, nice, description, enabler):
            JobContextRegistry.contexts[name] = enabler

    lib = types.ModuleType("mayaUsd.lib")
    lib.ExportChaser, lib.JobContextRegistry = ExportChaser, JobContextRegistry
    pkg = types.ModuleType("mayaUsd")
    pkg.lib = lib
    monkeypatch.setitem(sys.modules, "mayaUsd", pkg)
    monkeypatch.setitem(sys.modules, "mayaUsd.lib", lib)
    monkeypatch.delitem(sys.modules, "seamless_usd.hooks.maya_chaser", raising=False)
    module = importlib.import_module("seamless_usd.hooks.maya_chaser")
    yield module, registered, JobContextRegistry.contexts
    sys.modules.pop("seamless_usd.hooks.maya_chaser", None)


def _factory_context(stage, chaser_args):
    job_args = SimpleNamespace(allChaserArgs={"seamless_usd": chaser_args, "other": {"x": "1"}})
    return SimpleNamespace(GetStage=lambda: stage, GetJobArgs=lambda: job_args)


def test_maya_register_adds_chaser_and_export_dialog_context(maya_chaser):
    module, registered, contexts = maya_chaser
    module.register()
    assert registered["seamless_usd"] is module.SeamlessUsdChaser
    assert contexts["seamless_usd"]() == {"chaser": ["seamless_usd"]}
    module.unregister()
    assert "seamless_usd" not in registered


def test_maya_chaser_args_become_settings(maya_chaser):
    module, _, _ = maya_chaser
    job_args = SimpleNamespace(allChaserArgs={"seamless_usd": {"preset": "draft", "materials": "/Looks/B*"}})
    assert module.settings_from_job_args(job_args) == HookSettings(preset="draft", materials=("/Looks/B*",))
    assert module.settings_from_job_args(SimpleNamespace(allChaserArgs={})) == HookSettings()


def test_maya_post_export_processes_the_exported_stage(maya_chaser, recorder, tmp_path):
    from pxr import Usd

    module, _, _ = maya_chaser
    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    chaser = module.SeamlessUsdChaser(_factory_context(stage, {"preset": "draft", "seed": "2"}))
    assert chaser.ExportDefault() and chaser.ExportFrame(1.0)
    assert chaser.PostExport() is True
    (got_stage, options), = recorder.calls
    assert isinstance(options, seamless_usd.Options)  # the public API's options, built from the chaser args
    assert got_stage is stage and (options.preset, options.seed) == ("draft", 2)


def test_maya_disabled_by_chaser_arg(maya_chaser, recorder, tmp_path):
    from pxr import Usd

    module, _, _ = maya_chaser
    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    assert module.SeamlessUsdChaser(_factory_context(stage, {"enabled": "0"})).PostExport() is True
    assert recorder.calls == []


def test_maya_strict_post_export_returns_false_and_bad_arguments_do_not_stop_an_export(maya_chaser, monkeypatch,
                                                                                         tmp_path):
    """docs/maya.md: with strict, PostExport returns false when a stack fails (it raised); chaser arguments that
    cannot be used are said, and the export goes on unless strict (the chaser's constructor raised)."""
    from pxr import Usd

    module, _, _ = maya_chaser

    def failing(stage, options):
        return SimpleNamespace(stacks=[SimpleNamespace(status=SimpleNamespace(value="failed"), material="</M>",
                                                       message="boom", maps=[])], findings=[], exit_code=1,
                               unreadable=[])

    monkeypatch.setattr(common, "_default_process", failing)
    stage = Usd.Stage.CreateNew(str(tmp_path / "scene.usda"))
    assert module.SeamlessUsdChaser(_factory_context(stage, {"strict": "1"})).PostExport() is False
    assert module.SeamlessUsdChaser(_factory_context(stage, {"strict": "0"})).PostExport() is True
    for strict, goes_on in (("0", True), ("1", False)):
        chaser = module.SeamlessUsdChaser(_factory_context(stage, {"max_size": "128px", "strict": strict}))
        assert chaser.PostExport() is goes_on


# --- Houdini ------------------------------------------------------------------------------------


PROCESSOR_FILE = (
    Path(__file__).resolve().parents[1]
    / "seamless_usd/hooks/houdini/husdplugins/outputprocessors/seamless_usd_tileable.py"
)


@pytest.fixture()
def houdini_processor(monkeypatch):
    class _Template:
        def __init__(self, name, label, *args, **kwargs):
            self.name, self.label, self.args, self.kwargs = name, label, args, kwargs

    class ParmTemplateGroup:
        def __init__(self):
            self.templates = []

        def append(self, template):
            self.templates.append(template)

        def asDialogScript(self):
            return self.templates  # the real one returns text; the list is easier to check

    hou = types.ModuleType("hou")
    hou.ParmTemplateGroup = ParmTemplateGroup
    hou.ToggleParmTemplate = type("ToggleParmTemplate", (_Template,), {})
    hou.IntParmTemplate = type("IntParmTemplate", (_Template,), {})
    hou.StringParmTemplate = type("StringParmTemplate", (_Template,), {})
    hou.stringParmType = SimpleNamespace(FileReference="file", Regular="regular")
    hou.fileType = SimpleNamespace(Directory="directory")

    class OutputProcessor:
        def beginSave(self, config_node, config_overrides, lop_node, t, *args):
            self.begin_args = (config_node, config_overrides, lop_node, t, args)

        def evalConfig(self, name, config_node, config_overrides, t):
            if name in config_overrides:
                return config_overrides[name]
            return config_node.get(name)

    husd = types.ModuleType("husd")
    outputprocessor = types.ModuleType("husd.outputprocessor")
    outputprocessor.OutputProcessor = OutputProcessor
    husd.outputprocessor = outputprocessor
    monkeypatch.setitem(sys.modules, "hou", hou)
    monkeypatch.setitem(sys.modules, "husd", husd)
    monkeypatch.setitem(sys.modules, "husd.outputprocessor", outputprocessor)
    spec = importlib.util.spec_from_file_location("seamless_usd_tileable", PROCESSOR_FILE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_houdini_plugin_folder_layout():
    from seamless_usd.hooks import houdini

    assert (houdini.HOUDINI_PATH / "husdplugins" / "outputprocessors" / "seamless_usd_tileable.py") == PROCESSOR_FILE


def test_houdini_processor_declares_one_parm_per_setting(houdini_processor):
    from seamless_usd.hooks import houdini

    cls = houdini_processor.usdOutputProcessor()
    assert cls.name() == houdini.PROCESSOR_NAME and cls.displayName()
    templates = cls.parameters()
    assert [t.name for t in templates] == [f"seamlessusd_{name}" for name in (p.setting for p in houdini.PARMS)]
    kinds = {t.name: type(t).__name__ for t in templates}
    assert kinds["seamlessusd_enabled"] == "ToggleParmTemplate"
    assert kinds["seamlessusd_seed"] == "IntParmTemplate"
    assert kinds["seamlessusd_output_dir"] == "StringParmTemplate"


def test_houdini_settings_from_parms_ignore_missing():
    from seamless_usd.hooks import houdini

    values = {spec.name: None for spec in houdini.PARMS}
    values.update({"seamlessusd_preset": "draft", "seamlessusd_enabled": 1, "seamlessusd_materials": "/M/*"})
    assert houdini.settings_from_parms(values) == HookSettings(preset="draft", materials=("/M/*",))


def _texture_stage():
    from pxr import Sdf, Usd, UsdShade

    stage = Usd.Stage.CreateInMemory()
    shader = UsdShade.Shader.Define(stage, "/Looks/M/Tex")
    shader.CreateIdAttr("UsdUVTexture")
    shader.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("./textures/a.png")
    return stage


def test_houdini_process_layer_uses_the_save_path(houdini_processor, recorder, tmp_path):
    proc = houdini_processor.usdOutputProcessor()()
    rop = {"seamlessusd_enabled": 1, "seamlessusd_preset": "draft", "lopoutput": str(tmp_path / "rop.usd")}
    proc.beginSave(rop, {"seamlessusd_seed": 9}, None, 1.0, {})
    stage = _texture_stage()
    save = tmp_path / "sub" / "layer.usda"
    assert proc.processLayer(stage.GetRootLayer(), str(save)) is True
    (got_stage, options), = recorder.calls
    assert isinstance(options, seamless_usd.Options)
    assert got_stage.GetRootLayer().identifier == str(save.resolve())
    assert (options.preset, options.seed) == ("draft", 9)


def test_houdini_process_layer_old_signature_falls_back_to_rop_output(houdini_processor, recorder, tmp_path):
    proc = houdini_processor.usdOutputProcessor()()
    proc.beginSave({"seamlessusd_enabled": 1, "lopoutput": str(tmp_path / "rop.usd")}, {}, None, 1.0)
    stage = _texture_stage()
    proc.processLayer(stage.GetRootLayer())
    (got_stage, options), = recorder.calls
    assert isinstance(options, seamless_usd.Options) and options.preset == "default"  # no parm: the default
    assert got_stage.GetRootLayer().identifier == str((tmp_path / "rop.usd").resolve())


def test_houdini_disabled_or_no_textures_leaves_layer_alone(houdini_processor, recorder, tmp_path):
    from pxr import Sdf

    proc = houdini_processor.usdOutputProcessor()()
    proc.beginSave({"seamlessusd_enabled": 0}, {}, None, 1.0)
    stage = _texture_stage()
    assert proc.processLayer(stage.GetRootLayer(), str(tmp_path / "a.usda")) is False
    proc.beginSave({"seamlessusd_enabled": 1}, {}, None, 1.0)
    assert proc.processLayer(Sdf.Layer.CreateAnonymous(), str(tmp_path / "b.usda")) is False
    assert recorder.calls == []


def test_houdini_strict_failure_raises(houdini_processor, monkeypatch, tmp_path):

    def broken(stage, options):
        raise RuntimeError("boom")

    monkeypatch.setattr(common, "_default_process", broken)
    proc = houdini_processor.usdOutputProcessor()()
    proc.beginSave({"seamlessusd_enabled": 1, "seamlessusd_strict": 1}, {}, None, 1.0)
    stage = _texture_stage()
    with pytest.raises(HookError):
        proc.processLayer(stage.GetRootLayer(), str(tmp_path / "a.usda"))
