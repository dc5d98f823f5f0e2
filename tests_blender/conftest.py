"""Blender for the hook tests: the ``bpy`` package, the add-on enabled, a textured plane.

Runs only in the Blender environment (``python3 tests_blender/run.py``); the main test suite
never collects this folder.
"""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

import pytest

bpy = pytest.importorskip("bpy", reason="the Blender tests need the bpy package: python3 tests_blender/run.py")

if hasattr(bpy.utils, "expose_bundled_modules"):
    bpy.utils.expose_bundled_modules()  # Blender's own pxr, before anything imports pxr

REPO = Path(__file__).resolve().parents[1]
TEXTURES = REPO / "sample_assets" / "textures"
ADDON_DIR = REPO / "blender_addon"
ADDON = "seamless_usd_export"


def _enable_addon():
    import addon_utils

    if str(ADDON_DIR) not in sys.path:
        sys.path.insert(0, str(ADDON_DIR))
    addon_utils.enable(ADDON, default_set=True, persistent=True, handle_error=None)
    return bpy.context.preferences.addons[ADDON].preferences


@pytest.fixture(scope="session")
def blender():
    bpy.ops.wm.read_factory_settings(use_empty=True)  # also disables add-ons: enable ours after
    _enable_addon()
    return bpy


@pytest.fixture()
def prefs(blender):
    """The add-on preferences, reset to their defaults for each test."""
    p = bpy.context.preferences.addons[ADDON].preferences
    for name in ("enabled", "preset", "materials", "output_dir", "device", "seed", "max_size", "iterations",
                 "report", "cache_dir", "straighten", "dry_run", "strict", "site_packages"):
        p.property_unset(name)
    return p


def _clear_scene():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.images):
        for item in list(collection):
            collection.remove(item)


def image_node(tree, name: str, path: Path, colorspace: str = "sRGB"):
    node = tree.nodes.new("ShaderNodeTexImage")
    node.name = node.label = name
    node.image = bpy.data.images.load(str(path))
    node.image.colorspace_settings.name = colorspace
    return node


@pytest.fixture()
def brick_scene(blender, tmp_path):
    """A plane with UVs and a Principled BSDF fed by albedo, roughness and normal image textures
    (copies of the sample textures, so a test may pack or remove them)."""
    _clear_scene()
    src = tmp_path / "src"
    src.mkdir()
    for name in ("brick_albedo.png", "brick_roughness.png", "brick_normal.png"):
        shutil.copy(TEXTURES / name, src / name)
    bpy.ops.mesh.primitive_plane_add(size=2)  # has a UV map
    plane = bpy.context.active_object
    mat = bpy.data.materials.new("Brick")
    if not getattr(mat, "node_tree", None):
        mat.use_nodes = True  # Blender < 5 starts materials without nodes
    tree = mat.node_tree
    bsdf = tree.nodes["Principled BSDF"]
    albedo = image_node(tree, "Albedo", src / "brick_albedo.png")
    tree.links.new(albedo.outputs["Color"], bsdf.inputs["Base Color"])
    rough = image_node(tree, "Roughness", src / "brick_roughness.png", "Non-Color")
    tree.links.new(rough.outputs["Color"], bsdf.inputs["Roughness"])
    normal = image_node(tree, "Normal", src / "brick_normal.png", "Non-Color")
    normal_map = tree.nodes.new("ShaderNodeNormalMap")
    tree.links.new(normal.outputs["Color"], normal_map.inputs["Color"])
    tree.links.new(normal_map.outputs["Normal"], bsdf.inputs["Normal"])
    plane.data.materials.append(mat)
    return {"plane": plane, "material": mat, "albedo": albedo, "roughness": rough, "normal": normal, "src": src}


def export_usd(path: Path, **kwargs) -> set:
    """``bpy.ops.wm.usd_export`` with the options the tests rely on spelled out."""
    path.parent.mkdir(parents=True, exist_ok=True)
    kwargs.setdefault("export_materials", True)
    kwargs.setdefault("relative_paths", True)
    return bpy.ops.wm.usd_export(filepath=str(path), **kwargs)
