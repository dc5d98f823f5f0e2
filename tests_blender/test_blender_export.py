"""The Blender USD export hook, in Blender (the bpy package): add-on, export, exported stage."""
from __future__ import annotations

import os
import zipfile
from pathlib import Path
from types import SimpleNamespace

import bpy
import pytest

from conftest import ADDON, export_usd
from seamless_usd.hooks import common

MATERIAL = "/root/_materials/Brick"


def _stage(path: Path):
    from pxr import Usd

    stage = Usd.Stage.Open(str(path))
    assert stage, f"cannot open the exported {path}"
    return stage


def _textures(stage, material=MATERIAL):
    from pxr import Usd, UsdShade

    prim = stage.GetPrimAtPath(material)
    assert prim, f"no material <{material}> in the export"
    out = []
    for p in Usd.PrimRange(prim):
        shader = UsdShade.Shader(p)
        if shader and shader.GetIdAttr().Get() == "UsdUVTexture":
            out.append(shader)
    return out


def _resolved(shader) -> Path:
    value = shader.GetInput("file").Get()
    assert value is not None and value.resolvedPath, f"<{shader.GetPath()}> @{value}@ does not resolve"
    return Path(value.resolvedPath)


class Recorder:
    """Stands in for ``process_stage``: records what the hook hands over at hook time."""

    def __init__(self, edit=None):
        self.calls = []
        self.edit = edit

    def __call__(self, stage, options):
        layer = stage.GetRootLayer()
        textures = {}
        for shader in _textures(stage):
            value = shader.GetInput("file").Get()
            textures[str(shader.GetPath())] = (value.path, value.resolvedPath, Path(value.resolvedPath).is_file()
                                               if value.resolvedPath else False)
        self.calls.append(SimpleNamespace(layer=layer.realPath, edit_target=stage.GetEditTarget().GetLayer().realPath,
                                          options=options, textures=textures))
        if self.edit:
            self.edit(stage, options)
        return SimpleNamespace(stacks=[], findings=[], exit_code=0, unreadable=[])


@pytest.fixture()
def recorder(monkeypatch):
    rec = Recorder()
    monkeypatch.setattr(common, "_default_process", rec)
    return rec


def test_addon_registers_its_hook_and_preferences(prefs):
    hooks = {cls.bl_idname for cls in bpy.types.USDHook.__subclasses__()}
    assert "seamless_usd_export" in hooks
    assert (prefs.enabled, prefs.preset, prefs.output_dir, prefs.materials) == (True, "default", "", "")
    assert bpy.context.preferences.addons.get(ADDON) is not None


def test_hook_gets_the_exported_stage_with_textures_already_on_disk(prefs, brick_scene, recorder, tmp_path):
    """Blender writes each material's textures before the hooks run: at on_export time every
    inputs:file of the exported stage resolves to a file in <export dir>/textures/."""
    prefs.preset, prefs.materials, prefs.seed = "draft", "/root/_materials/*", 3
    out = tmp_path / "export" / "scene.usda"

    def mark(stage, options):  # an edit made in the hook must reach the saved file
        stage.GetPrimAtPath(MATERIAL).SetCustomDataByKey("seamlessHookRan", True)

    recorder.edit = mark
    assert export_usd(out, export_textures_mode="NEW") == {"FINISHED"}
    (call,) = recorder.calls
    assert Path(call.layer) == out and Path(call.edit_target) == out
    assert (call.options.preset, call.options.materials, call.options.seed) == ("draft", ("/root/_materials/*",), 3)
    assert call.options.output_dir is None  # library default: <export dir>/tileable
    assert len(call.textures) == 3
    for prim, (asset, resolved, exists) in call.textures.items():
        assert asset.startswith("./textures/") and exists, f"<{prim}> @{asset}@ not on disk at hook time"
        assert Path(resolved).parent == out.parent / "textures"
    assert _stage(out).GetPrimAtPath(MATERIAL).GetCustomDataByKey("seamlessHookRan") is True


def test_keep_mode_packed_image_is_written_before_processing(prefs, brick_scene, recorder, tmp_path):
    """With export_textures_mode='KEEP' Blender points a packed image at ./textures/<name> but
    writes no file; the hook writes it from the image datablock in on_material_export."""
    original = (brick_scene["src"] / "brick_albedo.png").read_bytes()
    image = brick_scene["albedo"].image
    image.pack()
    image.filepath = "//not_on_disk/brick_albedo.png"
    (brick_scene["src"] / "brick_albedo.png").unlink()
    out = tmp_path / "keep" / "scene.usda"
    assert export_usd(out, export_textures_mode="KEEP") == {"FINISHED"}
    (call,) = recorder.calls
    albedo = call.textures[f"{MATERIAL}/Albedo"]
    assert albedo[0] == "./textures/brick_albedo.png" and albedo[2], albedo
    assert (out.parent / "textures" / "brick_albedo.png").read_bytes() == original
    rough = call.textures[f"{MATERIAL}/Roughness"]
    assert Path(rough[1]) == brick_scene["src"] / "brick_roughness.png" and rough[2]  # KEEP: the source file


def test_keep_mode_generated_image_is_saved_before_processing(prefs, brick_scene, recorder, tmp_path):
    """A generated image (no file, not packed) in KEEP mode: the hook saves a copy of it."""
    image = bpy.data.images.new("GeneratedAlbedo", 64, 64)
    image.generated_type = "COLOR_GRID"
    brick_scene["albedo"].image = image
    out = tmp_path / "keepgen" / "scene.usda"
    assert export_usd(out, export_textures_mode="KEEP") == {"FINISHED"}
    (call,) = recorder.calls
    asset, resolved, exists = call.textures[f"{MATERIAL}/Albedo"]
    assert exists, f"@{asset}@ not written"
    assert Path(resolved).stat().st_size > 0 and image.filepath == ""  # the datablock keeps no path


def test_usdz_maps_written_beside_the_staging_layer_are_packaged(prefs, brick_scene, recorder, tmp_path):
    """A .usdz is staged in a temporary folder; maps written to <staging dir>/tileable (the default)
    and referenced from the stage end up inside the package."""

    def fake_tile(stage, options):
        from pxr import UsdShade

        staging = Path(stage.GetRootLayer().realPath).parent
        tile = staging / "tileable" / "brick_albedo_tile.png"
        tile.parent.mkdir(parents=True, exist_ok=True)
        tile.write_bytes((staging / "textures" / "brick_albedo.png").read_bytes())
        UsdShade.Shader(stage.GetPrimAtPath(f"{MATERIAL}/Albedo")).GetInput("file").Set("./tileable/brick_albedo_tile.png")

    recorder.edit = fake_tile
    out = tmp_path / "pkg" / "scene.usdz"
    assert export_usd(out) == {"FINISHED"}
    (call,) = recorder.calls
    assert Path(call.layer).parent != out.parent  # Blender's staging folder
    names = zipfile.ZipFile(out).namelist()
    assert "tileable/brick_albedo_tile.png" in names, names
    assert not (out.parent / "tileable").exists()


def test_disabled_addon_leaves_the_export_alone(prefs, brick_scene, recorder, tmp_path):
    prefs.enabled = False
    assert export_usd(tmp_path / "off" / "scene.usda") == {"FINISHED"}
    assert recorder.calls == []


def test_script_registration_without_the_addon(prefs, brick_scene, recorder, tmp_path):
    from seamless_usd.hooks import blender as hook
    from seamless_usd.hooks.common import HookSettings

    prefs.enabled = False  # only the script hook runs
    hook.register(HookSettings(preset="draft", max_size=32))
    try:
        assert export_usd(tmp_path / "script" / "scene.usda") == {"FINISHED"}
    finally:
        hook.unregister()
    (call,) = recorder.calls
    assert (call.options.preset, call.options.max_size) == ("draft", 32)


# --- end to end: the real process_stage -------------------------------------------------------


def _connected_shader(shader, input_name):
    from pxr import UsdShade

    inp = shader.GetInput(input_name)
    if not inp or not inp.HasConnectedSource():
        return None
    source = inp.GetConnectedSources()[0][0].source
    return UsdShade.Shader(source.GetPrim())


def test_export_writes_tileable_maps_with_uv_transform(prefs, brick_scene, monkeypatch, tmp_path):
    real = common._default_process
    reports = []

    def keep_report(stage, options):
        reports.append(real(stage, options))
        return reports[-1]

    monkeypatch.setattr(common, "_default_process", keep_report)
    prefs.preset = os.environ.get("SEAMLESS_USD_BLENDER_PRESET", "draft")
    prefs.iterations = int(os.environ.get("SEAMLESS_USD_BLENDER_ITERATIONS", "60"))
    prefs.max_size = int(os.environ.get("SEAMLESS_USD_BLENDER_MAX_SIZE", "128"))
    prefs.device = "cpu"
    prefs.strict = True  # a failing stack fails the export, so this test sees it
    prefs.cache_dir = str(tmp_path / "cache")
    out = tmp_path / "e2e" / "scene.usda"
    assert export_usd(out, export_textures_mode="NEW") == {"FINISHED"}

    (report,) = reports
    statuses = [s.status.value for s in report.stacks]
    assert statuses and "failed" not in statuses, statuses
    stage = _stage(out)
    textures = _textures(stage)
    assert len(textures) == 3
    tileable = out.parent / "tileable"
    for shader in textures:
        path = _resolved(shader)
        assert path.parent == tileable and path.is_file(), f"<{shader.GetPath()}> -> {path}"
        assert shader.GetInput("wrapS").Get() == "repeat" and shader.GetInput("wrapT").Get() == "repeat"
        transform = _connected_shader(shader, "st")
        assert transform is not None and transform.GetIdAttr().Get() == "UsdTransform2d", (
            f"<{shader.GetPath()}> st is not fed by a UsdTransform2d"
        )
        scale = transform.GetInput("scale").Get()
        (stack,) = report.stacks
        assert scale is not None and tuple(scale) == pytest.approx(stack.uv_scale, rel=1e-5), (
            f"<{transform.GetPath()}> scale {scale}, the stack's UV scale {stack.uv_scale}")
        reader = _connected_shader(transform, "in")
        assert reader is not None and reader.GetIdAttr().Get() == "UsdPrimvarReader_float2"
        api = shader.GetPrim().GetMetadata("apiSchemas")
        assert api is not None and "SeamlessTileAPI" in api.GetAddedOrExplicitItems()  # provenance
        source = shader.GetPrim().GetAttribute("seamless:sourceAsset").Get()
        assert source is not None and Path(source.resolvedPath).parent == out.parent / "textures"
    print("\n".join(str(line) for line in common.report_lines(report)))


# --- installed as a Blender 4.2+ extension ------------------------------------------------------

_EXTENSION_SCRIPT = r"""
import sys
import bpy
bpy.utils.expose_bundled_modules()
bpy.ops.wm.read_factory_settings(use_empty=True)
assert bpy.ops.extensions.package_install_files(
    filepath=sys.argv[1], repo="user_default", enable_on_install=True) == {"FINISHED"}
prefs = bpy.context.preferences.addons["bl_ext.user_default.seamless_usd_export"].preferences
prefs.dry_run = True
bpy.ops.mesh.primitive_plane_add(size=2)
mat = bpy.data.materials.new("Brick")
if not getattr(mat, "node_tree", None):
    mat.use_nodes = True
tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
tex.image = bpy.data.images.load(sys.argv[2])
mat.node_tree.links.new(tex.outputs["Color"], mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
bpy.context.active_object.data.materials.append(mat)
print("EXPORT", bpy.ops.wm.usd_export(filepath=sys.argv[3]))
"""


def test_installs_and_runs_as_an_extension(tmp_path):
    """The zip of blender_addon/seamless_usd_export installs as an extension (manifest checked by
    Blender), and its hook runs on export (a dry run: the stack is planned, nothing written)."""
    import subprocess
    import sys

    from conftest import ADDON_DIR, TEXTURES

    package = tmp_path / "seamless_usd_export.zip"
    with zipfile.ZipFile(package, "w") as zf:
        for f in sorted((ADDON_DIR / ADDON).iterdir()):
            if f.is_file() and f.suffix in {".py", ".toml"}:
                zf.write(f, f"{ADDON}/{f.name}")
    out = tmp_path / "ext" / "scene.usda"
    env = dict(os.environ, BLENDER_USER_RESOURCES=str(tmp_path / "blender_user"))
    done = subprocess.run(
        [sys.executable, "-c", _EXTENSION_SCRIPT, str(package), str(TEXTURES / "brick_albedo.png"), str(out)],
        capture_output=True, text=True, env=env, timeout=300,
    )
    assert "EXPORT {'FINISHED'}" in done.stdout, done.stdout[-3000:] + done.stderr[-3000:]
    assert "seamless-usd: 1 stack(s): 1 planned" in done.stdout, done.stdout[-3000:]
    assert not (out.parent / "tileable").exists()
