"""Which meshes a material is bound to, as UsdShade resolves bindings: a collection binding, a parent's binding
``strongerThanDescendants`` over a child's own, and each render purpose's binding. Materials bound to UV atlases
these ways were read as unbound library materials, called tiling, and made tileable."""
from __future__ import annotations

import shutil
import sys
from pathlib import Path

from pxr import Usd, UsdGeom, UsdShade

import seamless_usd

ROOT = Path(__file__).resolve().parents[1]


def _scene(folder: Path) -> Path:
    sys.path.insert(0, str(ROOT / "sample_assets"))
    from usdkit import atlas_mesh, bind, new_layer, preview_material

    names = ("coll", "parent", "child", "full", "preview")
    for name in names:
        shutil.copy(ROOT / "sample_assets" / "textures" / "brick_albedo.png", folder / f"{name}.png")
    stage = new_layer(folder / "scene.usda", "World")
    UsdGeom.Xform.Define(stage, "/World")
    for name in names:
        preview_material(stage, f"/World/Looks/M_{name}", {"diffuseColor": (f"./{name}.png", "rgb", "auto")})
    material = {name: UsdShade.Material(stage.GetPrimAtPath(f"/World/Looks/M_{name}")) for name in names}
    atlas_mesh(stage, "/World/CollAtlas", 0.1, 0.9, 5, 3)
    world = stage.GetPrimAtPath("/World")
    collection = Usd.CollectionAPI.Apply(world, "atlases")
    collection.CreateIncludesRel().AddTarget("/World/CollAtlas")
    UsdShade.MaterialBindingAPI.Apply(world).Bind(collection, material["coll"], "Atlases")
    group = UsdGeom.Xform.Define(stage, "/World/Group").GetPrim()
    UsdShade.MaterialBindingAPI.Apply(group).Bind(material["parent"], UsdShade.Tokens.strongerThanDescendants)
    atlas_mesh(stage, "/World/Group/Child", 0.1, 0.9, 5, 3)
    bind(stage.GetPrimAtPath("/World/Group/Child"), "/World/Looks/M_child")
    atlas_mesh(stage, "/World/Both", 0.1, 0.9, 5, 3)
    both = UsdShade.MaterialBindingAPI.Apply(stage.GetPrimAtPath("/World/Both"))
    both.Bind(material["full"], materialPurpose="full")
    both.Bind(material["preview"], materialPurpose="preview")
    stage.Save()
    return folder / "scene.usda"


def test_atlases_bound_by_collection_parent_or_purpose_are_left_alone(tmp_path):
    scan = seamless_usd.scan(_scene(tmp_path))
    intent = {s.material: (s.intent, s.intent_reason) for s in scan.stacks}
    for name, mesh in (("coll", "CollAtlas"), ("parent", "Group/Child"), ("full", "Both"), ("preview", "Both")):
        got, why = intent[f"</World/Looks/M_{name}>"]
        assert got == "uv-atlas" and f"</World/{mesh}>" in why, (name, got, why)
    # the child's own binding loses to its parent's: no geometry shows it
    assert "no bound geometry" in intent["</World/Looks/M_child>"][1]


def test_a_material_on_an_atlas_and_a_repeating_floor_is_left_alone(tmp_path):
    """One material bound to a floor whose UVs repeat it and to a crate unwrapped as an atlas: its tile and UV scale
    would change the crate too. It was called tiling (the floor's span decided) and the atlas resampled."""
    sys.path.insert(0, str(ROOT / "sample_assets"))
    from usdkit import atlas_mesh, bind, new_layer, plane, preview_material

    shutil.copy(ROOT / "sample_assets" / "textures" / "brick_albedo.png", tmp_path / "albedo.png")
    stage = new_layer(tmp_path / "scene.usda", "World")
    UsdGeom.Xform.Define(stage, "/World")
    preview_material(stage, "/World/Looks/M", {"diffuseColor": ("./albedo.png", "rgb", "sRGB")})
    bind(plane(stage, "/World/Floor", 4, 4).GetPrim(), "/World/Looks/M")
    bind(atlas_mesh(stage, "/World/Crate", 0.1, 0.9, 4, 2).GetPrim(), "/World/Looks/M")
    stage.Save()
    before = (tmp_path / "scene.usda").read_bytes()
    [stack] = seamless_usd.scan(tmp_path / "scene.usda").stacks
    assert stack.intent == "uv-atlas"
    assert "</World/Crate>" in stack.intent_reason and "</World/Floor>" in stack.intent_reason
    assert "material of its own" in stack.intent_reason
    report = seamless_usd.process_paths(tmp_path / "scene.usda", seamless_usd.Options(preset="tiny"))
    assert [r.status.value for r in report.stacks] == ["left-alone"]
    assert not (tmp_path / "tileable").exists() and (tmp_path / "scene.usda").read_bytes() == before
