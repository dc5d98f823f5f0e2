"""Which geometry a material is bound to, and how that geometry's UVs use the texture.

For tiling intent (``intent.py``): a texture whose UVs span several periods is meant to repeat;
one whose UVs stay inside one period as unwrapped islands is a UV atlas of that model.

Bindings are resolved as UsdShade resolves them, for each render purpose (direct and collection
bindings, inherited down namespace, ``strongerThanDescendants``, per-face ``GeomSubset`` bindings), and the
winning relationship's target is read rather than a ``UsdShade.Material``: a material composed from a
``.mtlx`` reference is not a Material prim under usd-core, but meshes still bind to its path. UV islands
are the connected components of faces that share a welded UV vertex (same mesh point and same UV value).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from pxr import Usd, UsdGeom

__all__ = ["MeshUse", "UVStats", "material_bindings", "uv_stats"]

_UV_FALLBACKS = ("st", "st0", "UVMap", "uv", "map1")
_WELD_DIGITS = 6  # UV values equal to 1e-6 are one UV vertex


@dataclass(frozen=True)
class MeshUse:
    """A mesh (or the faces of it in a GeomSubset) bound to a material."""

    mesh: str  # prim path
    faces: tuple[int, ...] | None = None  # face indices; None: the whole mesh


@dataclass(frozen=True)
class UVStats:
    """UVs of one mesh use, as read from its primvar."""

    mesh: str
    primvar: str
    faces: int
    lo: tuple[float, float]  # (u, v) minimum over the faces used
    hi: tuple[float, float]  # (u, v) maximum
    islands: int
    full_islands: int  # islands whose own UV extent covers (nearly) a whole period on both axes
    selection: str = ""  # the variant selection the binding was found under ("" : the stage's own)

    @property
    def span(self) -> tuple[float, float]:
        return (self.hi[0] - self.lo[0], self.hi[1] - self.lo[1])


#: The purposes a renderer binds for: each mesh counts for the material each of them resolves to.
_PURPOSES = ("full", "preview")


def _winners(prims: list, purpose: str) -> list:
    """The winning binding relationship of each prim for ``purpose`` (or None), as UsdShade resolves it: collection
    bindings, ``bindMaterialAs = strongerThanDescendants`` on an ancestor, a purpose's own binding over the
    all-purpose one. Its material need not exist as a Material prim (one composed from a ``.mtlx`` reference is
    not one under usd-core): the relationship's target is what is read."""
    from pxr import Tf, UsdShade

    if not prims:
        return []
    with Tf.DiagnosticTrap() as trap:  # bindings on prims without MaterialBindingAPI still count, without a warning
        _, rels = UsdShade.MaterialBindingAPI.ComputeBoundMaterials(prims, purpose)
        trap.Clear()
    return [rel if rel else None for rel in rels]


def _target(rel) -> str | None:
    """The material a winning binding relationship binds: its target (a collection binding's last)."""
    targets = rel.GetForwardedTargets() if rel is not None else []
    return str(targets[-1]) if targets else None


def material_bindings(stage: Usd.Stage) -> dict[str, list[MeshUse]]:
    """``"<material path>"`` -> the mesh uses bound to it, over the composed stage, for every render purpose."""
    out: dict[str, dict[MeshUse, None]] = {}  # ordered sets: the same use under both purposes counts once
    meshes = [prim for prim in stage.Traverse(Usd.TraverseInstanceProxies(Usd.PrimDefaultPredicate))
              if prim.IsA(UsdGeom.Mesh)]
    subsets = {str(m.GetPath()): [s for s in UsdGeom.Subset.GetAllGeomSubsets(UsdGeom.Mesh(m))
                                  if s.GetElementTypeAttr().Get() == UsdGeom.Tokens.face
                                  and s.GetIndicesAttr().Get() is not None] for m in meshes}
    every_subset = [s.GetPrim() for m in meshes for s in subsets[str(m.GetPath())]]
    for purpose in _PURPOSES:
        whole = dict(zip((str(m.GetPath()) for m in meshes), _winners(meshes, purpose)))
        parts = dict(zip((str(p.GetPath()) for p in every_subset), _winners(every_subset, purpose)))
        for prim in meshes:
            path = str(prim.GetPath())
            own, taken = _target(whole[path]), set()
            for subset in subsets[path]:
                rel = parts[str(subset.GetPath())]
                target = _target(rel)
                if target is None or (target == own and rel.GetPrim() != subset.GetPrim()):
                    continue  # the mesh's own material reaches it
                faces = tuple(int(i) for i in subset.GetIndicesAttr().Get())
                taken.update(faces)
                _add(out, target, MeshUse(path, faces))
            if own is None:
                continue
            if taken:
                counts = UsdGeom.Mesh(prim).GetFaceVertexCountsAttr().Get() or []
                rest = tuple(i for i in range(len(counts)) if i not in taken)
                if rest:
                    _add(out, own, MeshUse(path, rest))
            else:
                _add(out, own, MeshUse(path))
    return {material: list(uses) for material, uses in out.items()}


def _add(out: dict[str, dict[MeshUse, None]], material: str, use: MeshUse) -> None:
    out.setdefault(f"<{material}>", {})[use] = None


def _primvar(mesh: UsdGeom.Mesh, name: str | None) -> UsdGeom.Primvar | None:
    api = UsdGeom.PrimvarsAPI(mesh)
    names = [name] if name else []
    if name and name.upper().startswith("UV") and name[2:].isdigit():  # MaterialX texcoord index
        index = int(name[2:])
        names.append("st" if index == 0 else f"st{index}")
    for candidate in [*names, *_UV_FALLBACKS]:
        pv = api.GetPrimvar(candidate)
        if pv and pv.HasValue():
            return pv
    for pv in api.GetPrimvarsWithValues():
        if pv.GetTypeName().role == "TextureCoordinate":
            return pv
    return None


def uv_stats(stage: Usd.Stage, use: MeshUse, primvar: str | None) -> UVStats | None:
    """UV range and islands of ``use`` read from ``primvar`` (or the usual UV names); None when
    the mesh has no UVs."""
    mesh = UsdGeom.Mesh(stage.GetPrimAtPath(use.mesh))
    pv = _primvar(mesh, primvar)
    counts = np.asarray(mesh.GetFaceVertexCountsAttr().Get() or [], dtype=np.int64)
    fvi = np.asarray(mesh.GetFaceVertexIndicesAttr().Get() or [], dtype=np.int64)
    if pv is None or counts.size == 0 or fvi.size != counts.sum():
        return None
    values = np.asarray(pv.Get(Usd.TimeCode.EarliestTime()), dtype=np.float64).reshape(-1, 2)
    indices = np.asarray(pv.GetIndices(Usd.TimeCode.EarliestTime()) or [], dtype=np.int64)
    interp = pv.GetInterpolation()
    face_of_fv = np.repeat(np.arange(counts.size), counts)
    if interp == UsdGeom.Tokens.faceVarying:
        per_fv = indices if indices.size else np.arange(fvi.size)
    elif interp in (UsdGeom.Tokens.vertex, UsdGeom.Tokens.varying):
        per_fv = indices[fvi] if indices.size else fvi
    elif interp == UsdGeom.Tokens.uniform:
        per_fv = indices[face_of_fv] if indices.size else face_of_fv
    else:  # constant
        per_fv = np.zeros(fvi.size, dtype=np.int64)
    if per_fv.size != fvi.size or per_fv.max(initial=-1) >= len(values) or values.size == 0:
        return None
    keep = np.ones(fvi.size, dtype=bool) if use.faces is None else np.isin(face_of_fv, np.asarray(use.faces))
    if not keep.any():
        return None
    uv = values[per_fv[keep]]
    faces = face_of_fv[keep]
    points = fvi[keep]
    labels = _islands(faces, points, uv)
    n_islands = int(labels.max()) + 1
    lo = np.full((n_islands, 2), np.inf)
    hi = np.full((n_islands, 2), -np.inf)
    np.minimum.at(lo, labels, uv)
    np.maximum.at(hi, labels, uv)
    full = int(np.sum(np.all(hi - lo >= _FULL_ISLAND, axis=1)))
    return UVStats(
        mesh=use.mesh, primvar=pv.GetPrimvarName(), faces=int(np.unique(faces).size),
        lo=tuple(float(v) for v in uv.min(axis=0)), hi=tuple(float(v) for v in uv.max(axis=0)),
        islands=n_islands, full_islands=full,
    )


_FULL_ISLAND = 0.95  # an island covering >= 95 % of a period on both axes shows the whole texture once


def _islands(faces: np.ndarray, points: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Island label per face-vertex: faces sharing a welded UV vertex are one island."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    quantised = np.round(uv, _WELD_DIGITS)
    weld = np.column_stack([points.astype(np.float64), quantised])
    _, vertex = np.unique(weld, axis=0, return_inverse=True)
    vertex = vertex.reshape(-1)
    _, face = np.unique(faces, return_inverse=True)
    face = face.reshape(-1)
    n_faces, n_vertices = int(face.max()) + 1, int(vertex.max()) + 1
    # bipartite graph: faces 0..n_faces-1, welded UV vertices after them
    graph = coo_matrix((np.ones(face.size), (face, n_faces + vertex)), shape=(n_faces + n_vertices,) * 2)
    _, labels = connected_components(graph, directed=False)
    face_label = labels[:n_faces]
    _, compact = np.unique(face_label, return_inverse=True)
    return compact.reshape(-1)[face]
