"""Builders the sample-asset scripts share: layers, meshes (planes, UV atlases), bindings, UsdPreviewSurface
materials and payload roots, made the way published USD assets are.

Used by ``make_scenes.py`` and ``make_variants.py`` (and ``benchmarks/endtoend.py``); it imports neither.
"""
from __future__ import annotations

from pathlib import Path

from pxr import Gf, Kind, Sdf, Usd, UsdGeom, UsdShade, Vt

__all__ = ["atlas_mesh", "plane", "bind", "preview_material", "new_layer", "root_with_payload", "payload_layer"]


# -- geometry ---------------------------------------------------------------------------------

def atlas_mesh(stage: Usd.Stage, path: str, lo: float, hi: float, grid: int, box_islands: int) -> UsdGeom.Mesh:
    """A mesh whose UVs are ``grid`` x ``grid`` separate islands packed inside [lo, hi]^2.

    The first ``box_islands`` islands are 2x2-quad patches (welded inside the island), the rest
    single quads; positions are laid out as the faces of a rough box so it looks like a prop.
    """
    cell = (hi - lo) / grid
    gap = cell * 0.08
    points, counts, indices, uvs = [], [], [], []
    n = 0
    for k in range(grid * grid):
        i, j = divmod(k, grid)
        u0, v0 = lo + j * cell + gap, lo + i * cell + gap
        size = cell - 2 * gap
        sub = 2 if k < box_islands else 1
        base = len(points)
        for a in range(sub + 1):
            for b in range(sub + 1):
                points.append(Gf.Vec3f(j + b / sub, i + a / sub, (k % 3) * 0.1))
        for a in range(sub):
            for b in range(sub):
                corners = [(a, b), (a, b + 1), (a + 1, b + 1), (a + 1, b)]
                counts.append(4)
                for ca, cb in corners:
                    indices.append(base + ca * (sub + 1) + cb)
                    uvs.append(Gf.Vec2f(u0 + size * cb / sub, v0 + size * ca / sub))
                n += 1
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(Vt.Vec3fArray(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
    pv = UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray, UsdGeom.Tokens.faceVarying)
    pv.Set(Vt.Vec2fArray(uvs))
    return mesh


def plane(stage: Usd.Stage, path: str, size: float, periods: float, cells: int = 4) -> UsdGeom.Mesh:
    """A ``cells`` x ``cells`` grid whose UVs span 0..periods (vertex interpolation, one island)."""
    points, uvs, counts, indices = [], [], [], []
    for a in range(cells + 1):
        for b in range(cells + 1):
            points.append(Gf.Vec3f(size * (b / cells - 0.5), 0, size * (a / cells - 0.5)))
            uvs.append(Gf.Vec2f(periods * b / cells, periods * a / cells))
    for a in range(cells):
        for b in range(cells):
            counts.append(4)
            indices += [a * (cells + 1) + b, a * (cells + 1) + b + 1, (a + 1) * (cells + 1) + b + 1,
                        (a + 1) * (cells + 1) + b]
    mesh = UsdGeom.Mesh.Define(stage, path)
    mesh.CreatePointsAttr(Vt.Vec3fArray(points))
    mesh.CreateFaceVertexCountsAttr(Vt.IntArray(counts))
    mesh.CreateFaceVertexIndicesAttr(Vt.IntArray(indices))
    UsdGeom.PrimvarsAPI(mesh).CreatePrimvar("st", Sdf.ValueTypeNames.TexCoord2fArray,
                                            UsdGeom.Tokens.vertex).Set(Vt.Vec2fArray(uvs))
    return mesh


def bind(prim: Usd.Prim, material: str) -> None:
    UsdShade.MaterialBindingAPI.Apply(prim)
    prim.CreateRelationship("material:binding").SetTargets([Sdf.Path(material)])


# -- materials --------------------------------------------------------------------------------

def preview_material(stage: Usd.Stage, path: str, maps: dict[str, tuple[str, str, str]], wrap: str | None = "repeat"):
    """UsdPreviewSurface material; ``maps``: input -> (texture file, output, colour space)."""
    mat = UsdShade.Material.Define(stage, path)
    surface = UsdShade.Shader.Define(stage, f"{path}/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    mat.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    reader = UsdShade.Shader.Define(stage, f"{path}/StReader")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    reader.CreateInput("varname", Sdf.ValueTypeNames.String).Set("st")
    reader.CreateOutput("result", Sdf.ValueTypeNames.Float2)
    for name, (asset, output, cs) in maps.items():
        tex = UsdShade.Shader.Define(stage, f"{path}/{name}Tex")
        tex.CreateIdAttr("UsdUVTexture")
        tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(asset)
        tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
        tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set(cs)
        if wrap:
            tex.CreateInput("wrapS", Sdf.ValueTypeNames.Token).Set(wrap)
            tex.CreateInput("wrapT", Sdf.ValueTypeNames.Token).Set(wrap)
        vtype = Sdf.ValueTypeNames.Float3 if output == "rgb" else Sdf.ValueTypeNames.Float
        tex.CreateOutput(output, vtype)
        itype = Sdf.ValueTypeNames.Color3f if name == "diffuseColor" else (
            Sdf.ValueTypeNames.Normal3f if name == "normal" else Sdf.ValueTypeNames.Float)
        surface.CreateInput(name, itype).ConnectToSource(tex.ConnectableAPI(), output)
    return mat


def new_layer(path: Path, default_prim: str | None = None, doc: str = "") -> Usd.Stage:
    stage = Usd.Stage.CreateNew(str(path))
    UsdGeom.SetStageUpAxis(stage, UsdGeom.Tokens.y)
    UsdGeom.SetStageMetersPerUnit(stage, 1.0)
    if doc:
        stage.GetRootLayer().documentation = doc
    if default_prim:
        stage.GetRootLayer().defaultPrim = default_prim
    return stage


def root_with_payload(path: Path, prim: str, payload: str, doc: str) -> None:
    stage = new_layer(path, prim, doc)
    xf = UsdGeom.Xform.Define(stage, f"/{prim}")
    Usd.ModelAPI(xf.GetPrim()).SetKind(Kind.Tokens.component)
    xf.GetPrim().GetPayloads().AddPayload(payload)
    stage.Save()


def payload_layer(path: Path, prim: str, sublayers: list[str]) -> None:
    stage = new_layer(path, prim)
    stage.GetRootLayer().subLayerPaths = sublayers
    stage.Save()
