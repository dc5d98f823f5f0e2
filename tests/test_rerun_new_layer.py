"""Stages whose layers hold a material's opinions apart. A run again over a stage one of whose sublayers changed
since the new layer was written (a texture set anew there, the stage's own file unchanged): the new layer recorded
only the stage file's digest, so it was added to as if nothing had changed, and its earlier file values hid the
change. And in place, an st connection in a stronger layer than the file value."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

from pxr import Usd

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def test_a_texture_set_anew_in_a_sublayer_is_what_the_asset_shows_after_a_run_again(tmp_path, capsys):
    import numpy as np
    import OpenImageIO as oiio
    from scenes import ground_scene

    (tmp_path / "shot").mkdir()
    photo = oiio.ImageBuf(str(SAMPLES / "textures" / "brick_albedo.png")).get_pixels(oiio.FLOAT)[..., :3]
    ground_scene(tmp_path / "shot", np.asarray(photo), "brick.png", "Brick")  # a window of a photo: it tiles
    (tmp_path / "shot" / "scene.usda").rename(tmp_path / "shot" / "look.usda")
    shutil.copyfile(SAMPLES / "textures" / "wood_tileable.jpg", tmp_path / "shot" / "wood.jpg")  # made to repeat
    (tmp_path / "shot" / "scene.usda").write_text('#usda 1.0\n(\n    subLayers = [@./look.usda@]\n)\n')
    run = ["process", str(tmp_path / "shot" / "scene.usda"), "--preset", "tiny", "--seeds", "1", "--max-size", "128",
           "--cache-dir", str(tmp_path / "cache"), "--json"]

    def albedo() -> str:
        stage = Usd.Stage.Open(str(tmp_path / "shot" / "scene.seamless.usda"))
        shader = next(p for p in stage.Traverse() if p.GetAttribute("inputs:file"))
        return shader.GetAttribute("inputs:file").Get().resolvedPath

    main(run)
    capsys.readouterr()
    first = albedo()
    assert Path(first).name.startswith("brick.") and "tileable" in first
    main(run)  # unchanged: a no-op
    assert not json.loads(capsys.readouterr().out)["layers_written"] and albedo() == first
    look = tmp_path / "shot" / "look.usda"
    look.write_text(look.read_text().replace("./brick.png", "./wood.jpg"))  # set anew in the sublayer
    main(run)
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    assert stack["status"] == "left-alone", stack  # made to repeat: kept as it is
    assert Path(albedo()).name == "wood.jpg", albedo()  # what the asset shows: not the brick's tile


def test_an_st_connection_in_a_stronger_layer_than_the_file_is_said_so_without_variants(tmp_path, capsys):
    """In place, the file value in a sublayer and the st connection in the stage's own layer: the edits cannot
    compose, and the failure spoke of "an st connection outside the variant that sets the file" in a stage with no
    variants. It now names the layers and what to do."""
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    (tmp_path / "shot").mkdir()
    (tmp_path / "shot" / "look.usda").write_text((SAMPLES / "brick" / "scene.usda").read_text())
    (tmp_path / "shot" / "scene.usda").write_text("""#usda 1.0
(
    subLayers = [@./look.usda@]
)
over "World"
{
    over "Looks"
    {
        over "Brick"
        {
            over "Albedo"
            {
                float2 inputs:st.connect = </World/Looks/Brick/StReader.outputs:result>
            }
        }
    }
}
""")
    main(["process", str(tmp_path / "shot" / "scene.usda"), "--in-place", "--preset", "tiny", "--seeds", "1",
          "--max-size", "128", "--cache-dir", str(tmp_path / "cache"), "--json"])
    payload = json.loads(capsys.readouterr().out)
    said = [f["message"] for f in payload["findings"] if f["code"] == "edit-not-composed"]
    assert said and "variant" not in said[0] and "stronger layer than the file value" in said[0], said


def test_opinions_a_td_added_to_the_new_layer_are_kept_aside_when_it_is_made_again(tmp_path, capsys):
    """A light added to ``scene.seamless.usda`` after a run went without a word when a change below the stage (a
    geometry republish) had the layer made again. It is kept in a backup of the layer, and a warning names it; a
    layer with only this tool's opinions is made again with no backup."""
    from pxr import Sdf

    shutil.copytree(SAMPLES / "brick", tmp_path / "brick")
    shutil.copytree(SAMPLES / "textures", tmp_path / "textures")
    scene = tmp_path / "brick" / "scene.usda"
    layer = scene.with_name("scene.seamless.usda")
    run = ["process", str(scene), "--preset", "tiny", "--max-size", "128", "--cache-dir", str(tmp_path / "cache"),
           "--json"]

    def republish(name: str) -> None:  # the stage changes below the layer: an Xform added
        stage = Usd.Stage.Open(str(scene))
        stage.DefinePrim(f"/World/{name}", "Xform")
        stage.GetRootLayer().Save()

    main(run)
    capsys.readouterr()
    republish("Bolt")
    main(run)
    payload = json.loads(capsys.readouterr().out)
    assert not payload["backups"] and not scene.with_name("scene.seamless.usda.bak").exists()
    edited = Sdf.Layer.FindOrOpen(str(layer))
    Sdf.CreatePrimInLayer(edited, "/World/KeyLight").specifier = Sdf.SpecifierDef
    edited.Save()
    republish("Nut")
    main(run)
    payload = json.loads(capsys.readouterr().out)
    backup = scene.with_name("scene.seamless.usda.bak")
    assert payload["backups"] == [str(backup)] and "KeyLight" in backup.read_text()
    assert "KeyLight" not in layer.read_text()
    [said] = [f["message"] for f in payload["findings"] if "did not write" in f["message"]]
    assert "</World/KeyLight>" in said and "scene.seamless.usda.bak" in said
