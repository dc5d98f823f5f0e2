"""Seamless USD Export: a Blender USD export hook that makes material textures tileable.

This add-on is a thin shell: preferences, and a ``USDHook`` that hands the exported stage to the
``seamless_usd`` Python package (``seamless_usd.hooks.blender``). The package and its dependencies
(PyTorch, ...) are not bundled: install them into a folder and give it as *site-packages path*
in the preferences, or make them importable from Blender's Python. See docs/blender.md.

Works as a legacy add-on (``bl_info``) and as a Blender 4.2+ extension (``blender_manifest.toml``).
"""
# No "from __future__ import annotations": Blender reads the property annotations below as values.
import importlib
import os
import sys

import bpy
from bpy.props import BoolProperty, IntProperty, StringProperty

bl_info = {
    "name": "Seamless USD Export",
    "author": "seamless-usd developers",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "File > Export > Universal Scene Description (runs on every USD export)",
    "description": "Make material textures tileable with SeamlessGAN when exporting USD",
    "category": "Import-Export",
}

HOOK_IDNAME = "seamless_usd_export"
_ADDON = __package__ or __name__


def _prefs():
    addon = bpy.context.preferences.addons.get(_ADDON)
    return addon.preferences if addon is not None else None


def _expose(path_text: str) -> str | None:
    """Put the user's site-packages folder on ``sys.path``; return an error message or None."""
    if getattr(bpy.app, "module", False) and hasattr(bpy.utils, "expose_bundled_modules"):
        bpy.utils.expose_bundled_modules()  # Blender's own pxr before anything imports one
    path = bpy.path.abspath(path_text.strip()) if path_text.strip() else ""
    if path:
        if not os.path.isdir(path):
            return f"site-packages path is not a folder: {path}"
        if path not in sys.path:
            sys.path.append(path)  # after Blender's own modules: Blender's pxr must win
    return None


def _hook_module():
    """``seamless_usd.hooks.blender``, imported on first export (never at add-on start-up)."""
    prefs = _prefs()
    problem = _expose(prefs.site_packages if prefs is not None else "")
    if problem:
        raise ImportError(problem)
    try:
        return importlib.import_module("seamless_usd.hooks.blender")
    except ImportError as exc:
        raise ImportError(
            "seamless-usd is not importable from Blender's Python: install it and set the add-on's "
            f"'site-packages path' preference ({exc})"
        ) from exc


def _settings(module):
    prefs = _prefs()
    if prefs is None:
        return module.HookSettings(enabled=False)
    return module.settings_from_preferences(prefs)


class SeamlessUsdExportPreferences(bpy.types.AddonPreferences):
    bl_idname = _ADDON

    enabled: BoolProperty(
        name="Make textures tileable on USD export",
        description="Run SeamlessGAN on the exported material textures at every USD export",
        default=True,
    )
    preset: StringProperty(
        name="Preset",
        description="Synthesis preset (for example default, draft, paper)",
        default="default",
    )
    materials: StringProperty(
        name="Materials",
        description="Glob patterns on USD material paths, comma separated (empty: all), e.g. /root/_materials/Brick*",
        default="",
    )
    output_dir: StringProperty(
        name="Output folder",
        description="Where tileable maps go. Empty: a 'tileable' folder beside the exported file. "
        "Relative: from the exported file's folder",
        default="",
        subtype="DIR_PATH",
    )
    device: StringProperty(name="Device", description="cpu, cuda or cuda:N (empty: CUDA when present)", default="")
    seed: IntProperty(name="Seed", default=0, min=0)
    max_size: IntProperty(
        name="Max size", description="Working resolution cap in pixels, longest side (0: native)", default=0, min=0
    )
    iterations: IntProperty(
        name="Iterations", description="Training iterations (0: the preset's)", default=0, min=0
    )
    report: StringProperty(
        name="Report", description="HTML report path (empty: none)", default="", subtype="FILE_PATH"
    )
    cache_dir: StringProperty(
        name="Cache folder", description="Trained models (empty: the user's cache folder)", default="", subtype="DIR_PATH"
    )
    straighten: BoolProperty(
        name="Straighten",
        description="Tile stacks whose lines run at an angle straight; the UVs turn the tile back, so the look is kept",
        default=False,
    )
    dry_run: BoolProperty(name="Dry run", description="Plan only; write nothing", default=False)
    strict: BoolProperty(
        name="Fail export on error",
        description="Make the USD export fail when a texture stack fails (for pipelines)",
        default=False,
    )
    site_packages: StringProperty(
        name="site-packages path",
        description="Folder where seamless-usd and its dependencies are installed (empty: Blender's Python path)",
        default="",
        subtype="DIR_PATH",
    )

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "enabled")
        col = layout.column()
        col.active = self.enabled
        col.prop(self, "preset")
        col.prop(self, "materials")
        col.prop(self, "output_dir")
        row = col.row()
        row.prop(self, "device")
        row.prop(self, "seed")
        row = col.row()
        row.prop(self, "max_size")
        row.prop(self, "iterations")
        col.prop(self, "report")
        col.prop(self, "cache_dir")
        col.prop(self, "straighten")
        row = col.row()
        row.prop(self, "dry_run")
        row.prop(self, "strict")
        layout.prop(self, "site_packages")


def _call(name: str, *args):
    """Run ``seamless_usd.hooks.blender.<name>(*args, settings)``; a missing package is reported
    on the console and leaves the export as it is (unless the *strict* preference is on)."""
    prefs = _prefs()
    if prefs is None or not prefs.enabled:
        return True
    try:
        module = _hook_module()
    except ImportError as exc:
        print(f"error: seamless-usd: {exc}", flush=True)
        if prefs.strict:
            raise
        return False
    return getattr(module, name)(*args, _settings(module))


class SeamlessUsdExportHook(bpy.types.USDHook):
    bl_idname = HOOK_IDNAME
    bl_label = "Seamless USD: tileable textures"
    bl_description = "Make the exported material textures tileable with SeamlessGAN"

    @staticmethod
    def on_material_export(export_context, bl_material, usd_material):
        return _call("on_material_export", export_context, bl_material, usd_material)

    @staticmethod
    def on_export(export_context):
        return _call("on_export", export_context)


_CLASSES = (SeamlessUsdExportPreferences, SeamlessUsdExportHook)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
