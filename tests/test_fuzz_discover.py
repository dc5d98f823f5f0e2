"""Property-based fuzzing of discovery on generated stages and MaterialX documents.

Random shader networks (UsdPreviewSurface, UsdUVTexture, primvar readers, UsdTransform2d,
NodeGraphs, MaterialX nodes, unknown ids), random connections (cycles, self-loops, dangling
targets), missing / corrupt / tiny files and odd values of the wrong type: discovery never raises
anything but the project's own errors, and every finding is well formed (a known severity, a
code, a ``<prim>`` or ``@asset@`` location, one line of message).
"""
from __future__ import annotations

import math
from pathlib import Path

import MaterialX as mx
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pxr import Gf, Sdf, Tf, Usd, UsdShade

from seamless_usd.discover import scan_mtlx, scan_stage
from seamless_usd.errors import SeamlessUsdError
from seamless_usd.findings import Finding, Severity

from test_reliability_inputs import texture, write_image

NODE_IDS = [
    "UsdPreviewSurface", "UsdUVTexture", "UsdPrimvarReader_float2", "UsdTransform2d", None,  # None: NodeGraph
    "ND_image_color3", "ND_tiledimage_float", "ND_gltf_image_color3_color3_1_0", "ND_separate3_color3",
    "ND_extract_color3", "ND_normalmap", "ND_mix_color3", "ND_place2d_vector2", "Unknown_thing", "",
]
INPUT_NAMES = ["file", "st", "in", "texcoord", "diffuseColor", "normal", "roughness", "scale", "bias", "wrapS",
               "wrapT", "sourceColorSpace", "index", "varname", "fg", "bg", "rotation", "translation",
               "uaddressmode", "metallic", "occlusion"]
OUTPUT_NAMES = ["rgb", "r", "g", "a", "out", "result", "surface", "outr", "outx"]
TYPES = {
    "asset": Sdf.ValueTypeNames.Asset, "float": Sdf.ValueTypeNames.Float, "float2": Sdf.ValueTypeNames.Float2,
    "float3": Sdf.ValueTypeNames.Float3, "float4": Sdf.ValueTypeNames.Float4, "color3f": Sdf.ValueTypeNames.Color3f,
    "token": Sdf.ValueTypeNames.Token, "string": Sdf.ValueTypeNames.String, "int": Sdf.ValueTypeNames.Int,
    "normal3f": Sdf.ValueTypeNames.Normal3f,
}
ODD_FLOATS = st.sampled_from([0.0, -1.0, 1e30, -1e-30, math.nan, math.inf, -math.inf, 2.0])
ODD_TEXT = st.sampled_from(["", "sRGB", "raw", "auto", "repeat", "nonsense", "st", "<UDIM>", "\u00e9\u6728", "x" * 300])


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, str]:
    d = tmp_path_factory.mktemp("fuzz-files")
    good = write_image(d / "good map.png", texture(1))
    tiny = write_image(d / "tiny.png", texture(2, 4))
    (d / "corrupt.png").write_bytes(good.read_bytes()[:50])
    write_image(d / "tile.1001.png", texture(3))
    return {
        "good": str(good), "tiny": str(tiny), "corrupt": str(d / "corrupt.png"), "missing": str(d / "missing.png"),
        "udim": str(d / "tile.<UDIM>.png"), "relative": "./nope/../x.png", "escape": "../../../../etc/passwd",
        "package": str(d / "a.usdz[textures/x.png]"), "empty": "", "dir": str(d),
    }


def _value(draw, type_name: str, files: dict[str, str]):
    if type_name == "asset":
        return Sdf.AssetPath(files[draw(st.sampled_from(sorted(files)))])
    if type_name == "float":
        return draw(ODD_FLOATS)
    if type_name in ("float2", "float3", "float4", "color3f", "normal3f"):
        n = {"float2": 2, "float4": 4}.get(type_name, 3)
        vals = [draw(ODD_FLOATS) for _ in range(n)]
        return {2: Gf.Vec2f, 3: Gf.Vec3f, 4: Gf.Vec4f}[n](*vals)
    if type_name == "int":
        return draw(st.integers(-3, 7))
    return draw(ODD_TEXT)


@st.composite
def networks(draw, files):
    """A recipe: node list, then inputs with values or connections (maybe cyclic or dangling)."""
    n = draw(st.integers(1, 8))
    nodes = [draw(st.sampled_from(NODE_IDS)) for _ in range(n)]
    recipe = {"nodes": nodes, "inputs": [], "terminals": [], "interface": []}
    for i in range(n):
        for _ in range(draw(st.integers(0, 5))):
            name = draw(st.sampled_from(INPUT_NAMES))
            type_name = draw(st.sampled_from(sorted(TYPES)))
            kind = draw(st.sampled_from(["value", "connect", "connect", "dangling", "interface", "none"]))
            if kind == "value":
                payload = _value(draw, type_name, files)
            elif kind == "connect":
                payload = (draw(st.integers(0, n - 1)), draw(st.sampled_from(OUTPUT_NAMES)))
            else:
                payload = None
            recipe["inputs"].append((i, name, type_name, kind, payload))
    for terminal in draw(st.lists(st.sampled_from(["surface", "mtlx:surface", "displacement", "volume"]),
                                  max_size=2)):
        recipe["terminals"].append((terminal, draw(st.integers(-1, n - 1)), draw(st.sampled_from(OUTPUT_NAMES))))
    for _ in range(draw(st.integers(0, 2))):
        type_name = draw(st.sampled_from(sorted(TYPES)))
        recipe["interface"].append((draw(st.sampled_from(INPUT_NAMES)), type_name, _value(draw, type_name, files)))
    return recipe


def _author(step) -> None:
    """Run one authoring step of a recipe; a step USD itself refuses (type clash) is left out."""
    try:
        step()
    except Tf.ErrorException:
        pass


def build_stage(recipe) -> Usd.Stage:
    stage = Usd.Stage.CreateInMemory()
    material = UsdShade.Material.Define(stage, "/M")
    prims = []
    for i, sid in enumerate(recipe["nodes"]):
        if sid is None:
            prims.append(UsdShade.NodeGraph.Define(stage, f"/M/N{i}").GetPrim())
        else:
            shader = UsdShade.Shader.Define(stage, f"/M/N{i}")
            if sid:
                shader.CreateIdAttr(sid)
            prims.append(shader.GetPrim())
    for name, type_name, value in recipe["interface"]:
        inp = material.CreateInput(name, TYPES[type_name])
        _author(lambda: inp.Set(value))
    for i, name, type_name, kind, payload in recipe["inputs"]:
        _author(lambda: _author_input(material, prims, i, name, type_name, kind, payload))
    for terminal, j, out in recipe["terminals"]:
        _author(lambda: _author_terminal(material, prims, terminal, j, out))
    return stage


def _author_input(material, prims, i, name, type_name, kind, payload) -> None:
    connectable = UsdShade.ConnectableAPI(prims[i])
    inp = connectable.CreateInput(name, TYPES[type_name])
    if kind == "value":
        inp.Set(payload)
    elif kind == "connect":
        j, out = payload
        source = UsdShade.ConnectableAPI(prims[j])
        source.CreateOutput(out, TYPES[type_name])
        inp.ConnectToSource(source, out)
    elif kind == "dangling":
        inp.GetAttr().AddConnection(Sdf.Path("/Nowhere/N.outputs:out"))
    elif kind == "interface":
        m_inp = material.GetInput(name) or material.CreateInput(name, TYPES[type_name])
        inp.ConnectToSource(m_inp)


def _author_terminal(material, prims, terminal, j, out) -> None:
    m_out = material.CreateOutput(terminal, Sdf.ValueTypeNames.Token)
    if j < 0:
        m_out.GetAttr().AddConnection(Sdf.Path("/M/Gone.outputs:surface"))
    else:
        src = UsdShade.ConnectableAPI(prims[j])
        src.CreateOutput(out, Sdf.ValueTypeNames.Token)
        m_out.ConnectToSource(src, out)


def check_well_formed(findings: list[Finding]) -> None:
    for f in findings:
        assert isinstance(f.severity, Severity)
        assert isinstance(f.code, str) and f.code and f.code == f.code.strip()
        assert "<" in f.where or "@" in f.where, f
        assert f.message and "\n" not in f.message, f
        f.to_dict()


def check_result(result) -> None:
    check_well_formed(result.findings)
    for stack in result.stacks:
        assert stack.maps
        for m in stack.maps:
            assert m.resolved and Path(m.resolved).is_file()
            assert m.image is not None and min(m.image.width, m.image.height) >= 100


# Bounded: the bugs these found (cycles, shared upstream nodes, truncated files) have their own tests; a
# few dozen random networks a run keep looking, each within a deadline (the walk must stay linear).
@settings(max_examples=60, deadline=2000, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_discovery_on_random_usd_networks_never_crashes(files, data):
    recipe = data.draw(networks(files))
    stage = build_stage(recipe)
    try:
        result = scan_stage(stage)
    except SeamlessUsdError:
        return
    check_result(result)


MTLX_CATEGORIES = ["image", "tiledimage", "gltf_image", "separate3", "extract", "normalmap", "mix", "place2d",
                   "texcoord", "add", "nodegraph_ref", "standard_surface", "UsdPreviewSurface", "bogus"]
MTLX_TYPES = ["color3", "float", "vector2", "vector3", "filename", "string", "integer", "surfaceshader"]


@st.composite
def mtlx_recipes(draw, files):
    n = draw(st.integers(1, 7))
    nodes = [(draw(st.sampled_from(MTLX_CATEGORIES)), draw(st.sampled_from(MTLX_TYPES))) for _ in range(n)]
    inputs = []
    for i in range(n):
        for _ in range(draw(st.integers(0, 4))):
            name = draw(st.sampled_from(["file", "in", "fg", "bg", "texcoord", "base_color", "normal", "index",
                                         "scale", "uaddressmode", "diffuseColor", "roughness"]))
            type_name = draw(st.sampled_from(MTLX_TYPES))
            kind = draw(st.sampled_from(["value", "node", "node", "dangling", "interface"]))
            if kind == "value":
                if type_name == "filename":
                    value = files[draw(st.sampled_from(sorted(files)))]
                else:
                    value = draw(st.sampled_from(["", "1", "nan", "0.5, 0.5", "-1, 1", "inf", "abc", "3"]))
            else:
                value = draw(st.integers(0, n - 1))
            inputs.append((i, name, type_name, kind, value))
    prefix = draw(st.sampled_from(["", files["dir"] + "/", "../", "nowhere/"]))
    return {"nodes": nodes, "inputs": inputs, "prefix": prefix, "material_to": draw(st.integers(-1, n - 1))}


def build_mtlx(recipe, path: Path) -> Path:
    doc = mx.createDocument()
    if recipe["prefix"]:
        doc.setFilePrefix(recipe["prefix"])
    graph = doc.addNodeGraph("NG")
    nodes = []
    for i, (category, type_name) in enumerate(recipe["nodes"]):
        parent = doc if category in ("standard_surface", "UsdPreviewSurface") else graph
        nodes.append(parent.addNode(category, f"n{i}", type_name))
    for i, name, type_name, kind, value in recipe["inputs"]:
        node = nodes[i]
        inp = node.getInput(name) or node.addInput(name, type_name)
        if kind == "value":
            inp.setValueString(value)
        elif kind == "node":
            other = nodes[value]
            if other.getParent() == node.getParent():
                inp.setNodeName(other.getName())
            else:
                out = graph.getOutput(f"o{value}") or graph.addOutput(f"o{value}", other.getType())
                out.setNodeName(other.getName())
                inp.setNodeGraphString("NG")
                inp.setOutputString(out.getName())
        elif kind == "dangling":
            inp.setNodeName("not_a_node")
        else:
            inp.setInterfaceName("missing_interface")
    shader = next((nd for nd in nodes if nd.getParent() == doc), None)
    if shader is None:
        shader = doc.addNode("standard_surface", "surf", "surfaceshader")
    material = doc.addMaterialNode("Mat")
    if recipe["material_to"] >= 0:
        material.addInput("surfaceshader", "surfaceshader").setNodeName(shader.getName())
    mx.writeToXmlFile(doc, str(path))
    return path


@settings(max_examples=40, deadline=2000, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_discovery_on_random_mtlx_documents_never_crashes(files, data, tmp_path_factory):
    recipe = data.draw(mtlx_recipes(files))
    path = build_mtlx(recipe, Path(files["dir"]) / "fuzz.mtlx")
    try:
        result = scan_mtlx(path)
    except SeamlessUsdError:
        return
    check_result(result)


# the cases the fuzzer found, kept as plain tests ------------------------------------------------


def _chain_of_mixes(stage: Usd.Stage, depth: int, texture_file: str) -> None:
    """A material whose surface reads a chain of mixes, each fed twice by the one below."""
    material = UsdShade.Material.Define(stage, "/M")
    surface = UsdShade.Shader.Define(stage, "/M/Surface")
    surface.CreateIdAttr("UsdPreviewSurface")
    material.CreateSurfaceOutput().ConnectToSource(surface.ConnectableAPI(), "surface")
    tex = UsdShade.Shader.Define(stage, "/M/Tex")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(texture_file)
    reader = UsdShade.Shader.Define(stage, "/M/St")
    reader.CreateIdAttr("UsdPrimvarReader_float2")
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(reader.ConnectableAPI(), "result")
    below = (tex.ConnectableAPI(), "rgb")
    for i in range(depth):
        mix = UsdShade.Shader.Define(stage, f"/M/Mix{i}")
        mix.CreateIdAttr("ND_mix_color3")
        for name in ("fg", "bg"):
            mix.CreateInput(name, Sdf.ValueTypeNames.Color3f).ConnectToSource(*below)
        below = (mix.ConnectableAPI(), "out")
    surface.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(*below)
    # and a self-loop beside it
    loop = UsdShade.Shader.Define(stage, "/M/Loop")
    loop.CreateIdAttr("ND_mix_color3")
    for name in ("fg", "bg"):
        loop.CreateInput(name, Sdf.ValueTypeNames.Color3f).ConnectToSource(loop.ConnectableAPI(), "out")
    surface.CreateInput("emissiveColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(loop.ConnectableAPI(), "out")


def test_shared_upstream_nodes_and_cycles_are_walked_once(files, monkeypatch):
    # 40 mixes each fed twice by the one below: 2**40 paths when every path is walked
    from seamless_usd.discover import usdgraph

    stage = Usd.Stage.CreateInMemory()
    _chain_of_mixes(stage, 40, files["good"])
    calls = []
    real = usdgraph.producing_outputs
    monkeypatch.setattr(usdgraph, "producing_outputs", lambda *a, **k: calls.append(1) or real(*a, **k))
    result = scan_stage(stage)
    # each of the ~44 nodes' inputs is followed a bounded number of times (2**40 when every path is)
    assert 0 < len(calls) < 1000, len(calls)
    [stack] = result.stacks
    assert [m.node for m in stack.maps] == ["/M/Tex"]
    check_well_formed(result.findings)


def test_mtlx_cycles_and_shared_nodes_are_walked_once(files, tmp_path, monkeypatch):
    from seamless_usd.discover import mtlx as mtlx_walk
    from seamless_usd.discover import mtlxgraph

    doc = mx.createDocument()
    graph = doc.addNodeGraph("NG")
    image = graph.addNode("image", "img", "color3")
    image.addInput("file", "filename").setValueString(files["good"])
    below = image
    for i in range(40):
        mix = graph.addNode("mix", f"mix{i}", "color3")
        for name in ("fg", "bg"):
            mix.addInput(name, "color3").setNodeName(below.getName())
        below = mix
    loop = graph.addNode("mix", "loop", "color3")
    for name in ("fg", "bg"):
        loop.addInput(name, "color3").setNodeName("loop")
    out = graph.addOutput("out", "color3")
    out.setNodeName(below.getName())
    out_loop = graph.addOutput("out_loop", "color3")
    out_loop.setNodeName("loop")
    surf = doc.addNode("standard_surface", "surf", "surfaceshader")
    for name, output in (("base_color", "out"), ("emission_color", "out_loop")):
        inp = surf.addInput(name, "color3")
        inp.setNodeGraphString("NG")
        inp.setOutputString(output)
    doc.addMaterialNode("Mat").addInput("surfaceshader", "surfaceshader").setNodeName("surf")
    path = tmp_path / "loops.mtlx"
    mx.writeToXmlFile(doc, str(path))
    calls = []
    real = mtlxgraph.upstream
    monkeypatch.setattr(mtlx_walk.mtlxgraph, "upstream", lambda *a, **k: calls.append(1) or real(*a, **k))
    result = scan_mtlx(path)
    assert 0 < len(calls) < 1000, len(calls)  # bounded: 2**40 when every path is walked
    check_well_formed(result.findings)
    assert [m.node for s in result.stacks for m in s.maps] == ["NG/img"]
    assert not [f for f in result.findings if f.severity.value == "error"], result.findings
