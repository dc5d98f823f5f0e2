"""A float OpenEXR map whose values leave [0, 1] (a linear albedo exposed up, HDR) is judged by ``check`` as
``process`` judged it: its tile read with its source's value range. Read with a range fitted to the tile's own
values, the same texels read differently from the source's, and the two commands disagreed."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd_cli.main import main

ROOT = Path(__file__).resolve().parents[1]


def test_check_agrees_with_process_on_an_hdr_float_map(tmp_path, capsys):
    for name in ("brick", "textures"):
        shutil.copytree(ROOT / "sample_assets" / name, tmp_path / name)
    photo = oiio.ImageBuf(str(ROOT / "benchmarks" / "photos" / "gravel_1.jpg")).get_pixels(oiio.FLOAT)
    linear = (photo[:160, :160, :3] ** 2.2 * 8.0).astype(np.float32)  # up to about 6
    out = oiio.ImageOutput.create(str(tmp_path / "textures" / "hdr.exr"))
    assert out.open(str(tmp_path / "textures" / "hdr.exr"), oiio.ImageSpec(160, 160, 3, oiio.FLOAT))
    out.write_image(np.ascontiguousarray(linear))
    out.close()
    scene = tmp_path / "brick" / "scene.usda"
    scene.write_text(scene.read_text().replace("brick_albedo.png", "hdr.exr"))
    main(["process", str(scene), "--preset", "tiny", "--max-size", "100", "--force", "--cache-dir",
          str(tmp_path / "cache"), "--json"])
    [stack] = json.loads(capsys.readouterr().out)["stacks"]
    main(["check", "--json", str(scene.with_name("scene.seamless.usda"))])
    [item] = json.loads(capsys.readouterr().out)["items"]
    assert not item["note"], item["note"]
    assert item["passed"] == stack["verdict"]["passed"], (item["verdict"]["failing"], stack["verdict"]["failing"])
    assert item["verdict"]["failing"] == stack["verdict"]["failing"]
    assert item["verdict"]["strongest"] == stack["verdict"]["strongest"]
