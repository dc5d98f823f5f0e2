"""A photo that neither repeats nor continues itself, end to end: `process` keeps it whole, mends its seams,
writes it with no GAN trained, and the report, the JSON and the map on disk agree."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
from pxr import Usd, UsdShade

from seamless_usd_cli.main import main
from scenes import ground_scene

SKIMAGE = Path(__import__("skimage").__file__).parent / "data"


def _scene(folder: Path) -> Path:
    """A ground plane whose UsdPreviewSurface reads a plain 256 px window of scikit-image's gravel photo (CC0)."""
    buf = oiio.ImageBuf(str(SKIMAGE / "gravel.png"))
    window = buf.get_pixels(oiio.UINT8)[30:286, 40:296]
    grey = np.repeat(window[..., :1], 3, axis=2).astype(np.float32) / 255.0
    return ground_scene(folder, grey, "gravel.png", "Gravel")


def test_a_gravel_photo_is_mended_and_passed_without_training(tmp_path, capsys):
    scene = _scene(tmp_path)
    code = main(["process", str(scene), "--cache-dir", str(tmp_path / "cache"), "--json",
                 "--report", str(tmp_path / "report.html")])
    payload = json.loads(capsys.readouterr().out)
    [stack] = payload["stacks"]
    gan = stack["resampled"]["gan"]
    assert code == 0 and stack["status"] == "passed", stack
    assert gan["layout"] == "mend" and "not trained" in gan["lattice"]["gan"]
    assert gan["lattice"]["band"] and gan["lattice"]["lines"] is False
    # the written map is the source's size, 8-bit RGB, and wraps where the photo's edges did not
    layer = Usd.Stage.Open(str(tmp_path / "scene.seamless.usda"))
    shader = UsdShade.Shader(layer.GetPrimAtPath("/World/Looks/Gravel/diffuseColorTex"))
    path = Path(shader.GetInput("file").Get().resolvedPath)
    written = oiio.ImageBuf(str(path))
    assert (written.spec().width, written.spec().height, written.spec().nchannels) == (256, 256, 3)
    assert written.spec().format == oiio.UINT8
    source = oiio.ImageBuf(str(tmp_path / "gravel.png")).get_pixels(oiio.UINT8)
    tile = written.get_pixels(oiio.UINT8)
    rolled = np.roll(source, (128, 128), (0, 1))
    kept = np.all(tile == rolled, axis=-1)
    assert kept[:80, :80].all() and 0.6 < kept.mean() < 1.0  # the photo kept whole away from the band
    page = (tmp_path / "report.html").read_text()
    assert "the source kept whole and rolled by half" in page


def test_an_unchanged_rerun_takes_everything_back_without_torch(tmp_path, capsys):
    """The second run of the same scene finds the tile in the cache, the written map unchanged on disk and the
    triage's figures kept: it measures nothing, so it never imports torch, and says what the first run said."""
    import subprocess

    scene = _scene(tmp_path)
    # seeds named: a job's seeds otherwise follow torch's threads, which an earlier test in this process may have set
    args = ["process", str(scene), "--cache-dir", str(tmp_path / "cache"), "--json", "--seeds", "1"]
    assert main(args) == 0
    first = json.loads(capsys.readouterr().out)
    code = ("import json, sys\nfrom seamless_usd_cli.main import main\n"
            f"rc = main({args!r})\nprint(json.dumps({{'rc': rc, 'torch': 'torch' in sys.modules}}))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, check=True)
    lines = run.stdout.strip().splitlines()
    again, facts = json.loads("\n".join(lines[:-1])), json.loads(lines[-1])
    assert facts == {"rc": 0, "torch": False}, run.stderr[-2000:]
    [before], [after] = first["stacks"], again["stacks"]
    assert after["status"] == before["status"] == "passed" and after["origin"] == "cache"
    assert after["verdict"] == before["verdict"] and after["maps"] == before["maps"]
    assert after["intent_reason"] == before["intent_reason"]
