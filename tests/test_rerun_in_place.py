"""A run again over tiles this tool wrote (after ``--in-place``, or on the layer a run wrote) makes each stack
again from the source its tiles record, never from the tiles themselves: a tile of a tile was judged against
the tile it was made from and could be called passed though it was never judged against the photo."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Usd, UsdShade

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
WOOD = "library/materials/wood.usda"


def _library(root: Path) -> Path:
    for name in ("library", "textures"):
        shutil.copytree(SAMPLES / name, root / name)
    return root / WOOD


def _run(scene: Path, capsys, *extra: str) -> dict:
    code = main(["process", str(scene), "--preset", "tiny", "--max-size", "192", "--in-place",
                 "--cache-dir", str(scene.parents[2] / "cache"), "--json", *extra])
    report = json.loads(capsys.readouterr().out)
    assert code == report["exit_code"]
    return report


def _file_inputs(scene: Path) -> dict[str, tuple[str, str, tuple | None]]:
    """Texture prim -> (the file it reads, the source it records, the UV scale of the node before it)."""
    stage = Usd.Stage.Open(str(scene))
    out = {}
    for prim in stage.Traverse():
        shader = UsdShade.Shader(prim)
        if not shader or shader.GetIdAttr().Get() != "UsdUVTexture":
            continue
        source = prim.GetAttribute("seamless:sourceAsset").Get()
        st = shader.GetInput("st").GetConnectedSources()[0]
        node = UsdShade.Shader(st[0].source.GetPrim())
        scale = node.GetInput("scale").Get() if node.GetIdAttr().Get() == "UsdTransform2d" else None
        out[str(prim.GetPath())] = (shader.GetInput("file").Get().resolvedPath, source.path if source else "",
                                    tuple(scale) if scale is not None else None)
    return out


def test_the_scan_reads_the_names_the_authoring_gives_its_own_nodes():
    from seamless_usd.authoring.mtlxinputs import MtlxNames
    from seamless_usd.authoring.schema import Schema
    from seamless_usd.authoring.usdnodes import Names
    from seamless_usd.discover.tokens import Recorded

    assert (Recorded.USD_UV_API, Recorded.USD_UV_READER) == (Schema.UV_TRANSFORM_API, Names.UV_READER)
    assert (Recorded.MTLX_UV_MARK, Recorded.MTLX_UV_READER) == (MtlxNames.MARK_UV, MtlxNames.UV_READER)


def _pixels(path: str) -> np.ndarray:
    return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)


def test_a_not_passed_tile_run_again_in_place_is_made_again_from_its_source(tmp_path, capsys):
    scene = _library(tmp_path)
    first = _run(scene, capsys)
    [stack] = first["stacks"]
    assert stack["status"] == "not-passed" and stack["origin"] == "trained"
    made = _file_inputs(scene)
    assert all(source.endswith(("wood_color.png", "wood_roughness.png")) for _, source, _ in made.values())

    again = _run(scene, capsys)
    [stack2] = again["stacks"]
    # the same source, so the same model and tile from the cache and the same verdict: not a tile of the tile
    assert stack2["origin"] == "cache", stack2["origin"]
    assert stack2["status"] == "not-passed" and stack2["verdict"] == stack["verdict"]
    assert [m["asset"] for m in stack2["maps"]] == [m["asset"] for m in stack["maps"]]  # the sources, as authored
    # the stack keeps its id over the UV node the first run inserted: the same tiles, the layer not written again
    assert _file_inputs(scene) == made
    assert "every texture already has these edits" in json.dumps(again["findings"])

    # check judges the stage's tiles against the sources they record, and agrees
    assert main(["check", str(scene), "--json"]) == 1
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert item["passed"] is False and not item["note"], item

    # the recorded source gone: the tile itself is made tileable, and the run says so
    (tmp_path / "textures" / "wood_color.png").unlink()
    gone = _run(scene, capsys)
    found = [f for f in gone["findings"] if f["code"] == "source-not-found"]
    assert len(found) == 1 and "wood_color.png" in found[0]["message"] and "from the tile itself" in found[0]["message"]
    assert gone["stacks"][0]["status"] in ("passed", "not-passed")


def _brick_in_place(root: Path) -> tuple[Path, list[str]]:
    """The bundled brick copied under ``root``, and the in-place run over it (a small tile, a cache of its own)."""
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, root / name)
    scene = root / "brick" / "scene.usda"
    return scene, ["process", str(scene), "--preset", "tiny", "--max-size", "128", "--in-place", "--cache-dir",
                   str(root / "cache"), "--json"]


def test_a_passed_tile_whose_source_changed_is_made_again_from_it(tmp_path, capsys):
    scene, run = _brick_in_place(tmp_path)
    main(run)
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "passed"
    tiles = _file_inputs(scene)
    main(run)  # unchanged: left alone
    assert json.loads(capsys.readouterr().out)["stacks"][0]["status"] == "left-alone"

    albedo = tmp_path / "textures" / "brick_albedo.png"
    flipped = oiio.ImageBufAlgo.flop(oiio.ImageBuf(str(albedo)))  # a source edited since, say
    assert flipped.write(str(albedo))
    main(run)
    [again] = json.loads(capsys.readouterr().out)["stacks"]
    assert again["intent"] == "tiling" and "brick_albedo.png@ has changed since: made again from it" in again["intent_reason"]
    assert again["origin"] in ("trained", "cut") and again["status"] in ("passed", "not-passed")  # made, not cached
    now = _file_inputs(scene)
    prim = next(p for p in now if p.endswith("Albedo"))
    assert now[prim][0] != tiles[prim][0] and now[prim][1] == tiles[prim][1]  # a new tile, the same recorded source
    assert not np.array_equal(_pixels(now[prim][0]), _pixels(tiles[prim][0]))


def test_a_stack_keeps_its_id_over_the_uv_nodes_a_run_inserted(tmp_path, capsys):
    """The UV scale node (and, for a MaterialX image that read its default UVs, the UV0 reader) a run inserts
    leave a stack's id as it was: a run again in place names the same tiles instead of writing new ones."""
    import seamless_usd

    for name in ("transform2d", "usd_mtlx", "mtlx", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    # after a transform of the asset's own, in USD and in a MaterialX shader in USD; an image that read its default UVs
    for scene in ("transform2d/scene.usda", "usd_mtlx/scene.usda", "mtlx/prefixed.mtlx"):
        path = tmp_path / scene
        before = sorted((s.material, s.id) for s in seamless_usd.scan(path).stacks)
        code = main(["process", str(path), "--preset", "tiny", "--max-size", "100", "--refine", "off", "--in-place",
                     "--force", "--cache-dir", str(tmp_path / "cache")])
        capsys.readouterr()
        assert code in (0, 1) and path.with_name(path.name + ".bak").is_file()
        after = seamless_usd.scan(path)
        assert all(s.uv.before_ours for s in after.stacks)
        assert sorted((s.material, s.id) for s in after.stacks) == before, scene


def test_tiles_deleted_after_an_in_place_run_are_made_again_from_their_recorded_sources(tmp_path, capsys):
    """The tiles folder deleted after ``--in-place``: check names each missing tile, and process makes them again
    from the sources the stage records (the material failed, 'no texture of it can be read', with no way on but
    the .bak)."""
    scene = _library(tmp_path)
    first = _run(scene, capsys)
    made = _file_inputs(scene)
    shutil.rmtree(scene.parent / "tileable")
    assert main(["check", "--json", str(scene)]) != 0
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert "is not there (its recorded source is): process again" in item["error"]
    again = _run(scene, capsys)
    [stack] = again["stacks"]
    assert stack["status"] == first["stacks"][0]["status"] and stack["origin"] == "cache"
    assert [f["code"] for f in again["findings"]].count("tile-missing") == 2
    assert _file_inputs(scene) == made and all(Path(tile).is_file() for tile, _, _ in made.values())


def test_a_file_set_by_hand_after_an_in_place_run_is_left_as_it_is_and_its_stack_fails(tmp_path, capsys):
    """An artist set the albedo back to the photo after an in-place run: a run again took the node's provenance at
    its word (already tileable, passed, exit 0), the scan agreed, check did not, and the photo stayed under the tile's
    UV scale. The stack now fails naming the file, which is left as it is; scan judges the pixels, as check does."""
    scene, run = _brick_in_place(tmp_path)
    main(run)
    assert json.loads(capsys.readouterr().out)["stacks"][0]["status"] == "passed"
    text = scene.read_text()
    tile = next(p for p in text.split("@") if "tileable/brick_albedo" in p)
    scene.write_text(text.replace(f"@{tile}@", "@../textures/brick_albedo.png@"))
    before = scene.read_bytes()
    assert main(run) == 1
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "failed" and "set by hand" in stack["message"] and "brick_albedo.png" in stack["message"]
    assert scene.read_bytes() == before
    assert main(["scan", "--json", str(scene)]) == 0
    [scanned] = json.loads(capsys.readouterr().out)["stacks"]
    assert scanned["intent"] == "tiling" and "set by hand since" in scanned["intent_reason"]


def test_a_map_added_to_a_material_after_an_in_place_run_joins_its_stack(tmp_path, capsys):
    """An occlusion map wired in after an in-place run reads the texture coordinates directly, the run's maps read
    its UV transform: the scan made two stacks under one id, the new one took the other's left-alone status, and the
    run said nothing was to be done (exit 0). It now joins the stack, made again with it, every map at one UV scale."""
    from pxr import Sdf

    scene, run = _brick_in_place(tmp_path)
    main(run)
    capsys.readouterr()
    stage = Usd.Stage.Open(str(scene))
    look = "/World/Looks/Brick"
    occl = UsdShade.Shader.Define(stage, f"{look}/Occl")
    occl.CreateIdAttr("UsdUVTexture")
    occl.CreateInput("file", Sdf.ValueTypeNames.Asset).Set("../textures/brick_orm.png")
    occl.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("raw")
    occl.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(
        UsdShade.Shader.Get(stage, f"{look}/StReader").ConnectableAPI(), "result")
    occl.CreateOutput("r", Sdf.ValueTypeNames.Float)
    UsdShade.Shader.Get(stage, f"{look}/Surface").CreateInput("occlusion", Sdf.ValueTypeNames.Float).ConnectToSource(
        occl.ConnectableAPI(), "r")
    stage.GetRootLayer().Save()
    main(["scan", "--json", str(scene)])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert len(stack["maps"]) == 4 and stack["intent"] == "tiling"
    main(run)
    [made] = json.loads(capsys.readouterr().out)["stacks"]
    assert made["status"] in ("passed", "not-passed") and len(made["maps"]) == 4
    stage = Usd.Stage.Open(str(scene))
    scales = set()
    for node in ("Albedo", "Occl"):
        shader = UsdShade.Shader.Get(stage, f"{look}/{node}")
        assert "tileable/" in shader.GetInput("file").Get().path
        scales.add(tuple(shader.GetInput("st").GetConnectedSources()[0][0].source.GetInput("scale").Get()))
    assert len(scales) == 1  # one UV scale for every map of the stack
