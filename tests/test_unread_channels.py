"""A packed file wired by one channel (an ORM file whose red channel alone feeds roughness): the tile keeps the
file's layout, its other channels written as their mean, and the run says so (it did not)."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import OpenImageIO as oiio

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"


def test_channels_no_input_reads_are_named(tmp_path, capsys):
    for name in ("brick", "textures"):
        shutil.copytree(SAMPLES / name, tmp_path / name)
    scene = tmp_path / "brick" / "scene.usda"
    scene.write_text(scene.read_text().replace("brick_roughness.png", "brick_orm.png"))
    main(["process", str(scene), "--preset", "tiny", "--max-size", "100", "--cache-dir", str(tmp_path / "cache"),
          "--json"])
    payload = json.loads(capsys.readouterr().out)
    [found] = [f for f in payload["findings"] if f["code"] == "unread-channels"]
    assert "brick_orm.png" in found["where"] and "channels G, B of the file are read by no input" in found["message"]
    [stack] = payload["stacks"]
    [tile] = [m["output"] for m in stack["maps"] if "brick_orm" in m["output"]]
    pixels = oiio.ImageBuf(tile).get_pixels(oiio.FLOAT)
    assert pixels.shape[2] == 3 and pixels[..., 0].std() > 0.01 and pixels[..., 1:].std(axis=(0, 1)).max() < 1e-3
