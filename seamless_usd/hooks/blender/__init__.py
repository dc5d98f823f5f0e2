"""Blender USD export hook: the exported materials get tileable textures (Blender only).

Two ways in, one implementation:

- the add-on in ``blender_addon/seamless_usd_export`` (settings in its preferences), which calls
  :func:`on_material_export` and :func:`on_export` here;
- a pipeline script: ``seamless_usd.hooks.blender.register(HookSettings(...))`` registers a hook
  with fixed settings, then ``bpy.ops.wm.usd_export(...)`` runs it.

When the textures exist: Blender writes each material's textures while it exports that material,
before calling ``on_material_export`` for it and long before ``on_export``; so at ``on_export``
time every ``inputs:file`` normally points at a file on disk (the ``textures/`` folder beside the
exported file, or, for a ``.usdz``, beside the staging layer in a temporary folder that Blender
packages afterwards). One case breaks that: with ``export_textures_mode='KEEP'``, packed and
generated images get an ``inputs:file`` of ``./textures/<name>`` but no file is written.
:func:`on_material_export` writes those missing files from the image datablocks, so the library
finds every texture. See ``docs/blender.md``.

Importing this module imports ``bpy``: only Blender (or the ``bpy`` package) loads it.
"""
from __future__ import annotations

import logging
from pathlib import Path

import bpy

from seamless_usd.hooks import common
from seamless_usd.hooks.common import HookSettings, Level, LogLine

__all__ = [
    "SCRIPT_HOOK_IDNAME",
    "ensure_pxr",
    "settings_from_preferences",
    "on_material_export",
    "on_export",
    "write_missing_textures",
    "register",
    "unregister",
]

SCRIPT_HOOK_IDNAME = "seamless_usd_script_hook"
log = logging.getLogger("seamless_usd.hooks.blender")


def ensure_pxr() -> None:
    """Make Blender's own ``pxr`` importable (``bpy`` package); a no-op inside the Blender app.

    Blender's ``pxr`` must be the one used: the stage Blender hands to a hook is of its types.
    """
    if getattr(bpy.app, "module", False) and hasattr(bpy.utils, "expose_bundled_modules"):
        bpy.utils.expose_bundled_modules()


def _abspath(text: str) -> str:
    """Blender's ``//`` (relative to the .blend file) made absolute; other text unchanged."""
    return bpy.path.abspath(text) if text.startswith("//") else text


def settings_from_preferences(prefs: object) -> HookSettings:
    """The add-on preferences (same attribute names as :class:`HookSettings`) as settings."""
    settings = common.settings_from_attributes(prefs)
    return settings.with_(
        output_dir=_abspath(settings.output_dir),
        report=_abspath(settings.report),
        cache_dir=_abspath(settings.cache_dir),
    )


def console_emit(line: LogLine) -> None:
    """Blender shows hook output in its system console; errors also go to ``logging``."""
    print(str(line), flush=True)
    if line.level is not Level.INFO:
        log.log(logging.ERROR if line.level is Level.ERROR else logging.WARNING, line.text)


def _texture_shaders(usd_material):
    from pxr import Usd, UsdShade

    for prim in Usd.PrimRange(usd_material.GetPrim()):
        shader = UsdShade.Shader(prim)
        if shader and shader.GetIdAttr().Get() == "UsdUVTexture":
            yield shader


def _image_for(bl_material, prim_name: str, asset_name: str):
    """The Blender image behind a USD texture shader: by node name (as Blender names the prim),
    else by file name."""
    from pxr import Tf

    tree = getattr(bl_material, "node_tree", None)
    if tree is None:
        return None
    images = [n for n in tree.nodes if n.type == "TEX_IMAGE" and n.image is not None]
    for node in images:
        if Tf.MakeValidIdentifier(node.name) == prim_name:
            return node.image
    for node in images:
        if Path(bpy.path.abspath(node.image.filepath)).name == asset_name or node.image.name == asset_name:
            return node.image
    return None


def _write_image(image, target: Path) -> None:
    from seamless_usd.fileio import atomic_write, atomic_write_bytes

    target.parent.mkdir(parents=True, exist_ok=True)
    if image.packed_file is not None:
        atomic_write_bytes(target, bytes(image.packed_file.data))  # the original file's bytes, lossless
        return

    def save(tmp: Path) -> None:  # the temporary name keeps the target's suffix
        try:
            image.save(filepath=str(tmp), save_copy=True)  # keeps the datablock's own path
        except TypeError:  # Blender without save_copy
            image.save_render(str(tmp))

    atomic_write(target, save)


def write_missing_textures(export_context, bl_material, usd_material) -> list[Path]:
    """Write texture files the export references but did not write (KEEP mode, packed images).

    Returns the files written. Files that exist are never touched.
    """
    from pxr import Sdf

    stage = export_context.get_stage()
    root = stage.GetRootLayer()
    written: list[Path] = []
    for shader in _texture_shaders(usd_material):
        file_input = shader.GetInput("file")
        value = file_input.Get() if file_input else None
        asset = getattr(value, "path", "") if value is not None else ""
        if not asset or "<UDIM>" in asset:
            continue
        target = Path(Sdf.ComputeAssetPathRelativeToLayer(root, asset) if not root.anonymous else asset)
        if not target.is_absolute() and not root.anonymous:
            # A search-path style name (generated images in KEEP mode: @GeneratedAlbedo.png@):
            # the resolver looks beside the layer first, so that is where it goes.
            target = Path(root.realPath).parent / asset
        if target.exists() or not target.is_absolute():
            continue
        image = _image_for(bl_material, shader.GetPrim().GetName(), target.name)
        if image is None:
            continue
        _write_image(image, target)
        written.append(target)
        console_emit(LogLine(Level.INFO, f"{common.PREFIX}: wrote missing texture @{asset}@ from image '{image.name}'"))
    return written


def on_material_export(export_context, bl_material, usd_material, settings: HookSettings) -> bool:
    if settings.enabled:
        ensure_pxr()
        common.run_guarded(lambda: write_missing_textures(export_context, bl_material, usd_material), settings,
                           f"writing the textures of {bl_material.name!r} the export left unwritten", emit=console_emit)
    return True


def on_export(export_context, settings: HookSettings) -> bool:
    """Process the stage Blender is about to save; edits go into its root layer."""
    if not settings.enabled:
        return True
    ensure_pxr()
    stage = export_context.get_stage()
    wm = getattr(bpy.context, "window_manager", None)
    if wm is None or bpy.app.background:
        return common.export_ok(common.run_hook(stage, settings, emit=console_emit), settings)
    wm.progress_begin(0, 1000)  # the export blocks the UI while stacks train: show where it is

    def progress(event) -> None:
        if event.kind == "report":  # a library report's pages: a hook's run writes one stage's
            return
        done = event.index + (1 if event.kind == "stack-done" else 0)
        wm.progress_update(int(1000 * done / max(event.total, 1)))

    try:
        return common.export_ok(common.run_hook(stage, settings, emit=console_emit, on_progress=progress), settings)
    finally:
        wm.progress_end()


# --- registration for pipeline scripts (the add-on registers its own hook class) ---------------

_script_settings = HookSettings()


class SeamlessUsdScriptHook(bpy.types.USDHook):
    bl_idname = SCRIPT_HOOK_IDNAME
    bl_label = "Seamless USD (script)"
    bl_description = "Make exported material textures tileable (settings given by a script)"

    @staticmethod
    def on_material_export(export_context, bl_material, usd_material):
        return on_material_export(export_context, bl_material, usd_material, _script_settings)

    @staticmethod
    def on_export(export_context):
        return on_export(export_context, _script_settings)


def register(settings: HookSettings | None = None) -> None:
    """Register the script hook (or just change its settings when it is registered)."""
    global _script_settings
    ensure_pxr()
    _script_settings = settings or HookSettings()
    if not getattr(SeamlessUsdScriptHook, "is_registered", False):
        bpy.utils.register_class(SeamlessUsdScriptHook)


def unregister() -> None:
    if getattr(SeamlessUsdScriptHook, "is_registered", False):
        bpy.utils.unregister_class(SeamlessUsdScriptHook)
