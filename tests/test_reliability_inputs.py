"""Reliability: a corpus of bad inputs, generated here as real files, through ``seamless-usd process``.

Every bad item sits in its own material of one library, beside a good material. For each item
the run must report one clear line naming ``<prim>`` or ``@asset@``, go on with the rest, leave
no temporary file behind and end with exit code 1 (2 only for an unreadable top-level input).
The helpers here (scene and texture writers) are shared by the other reliability tests.
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import json
import os
import shutil
import struct
import subprocess
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
from pxr import Sdf, Usd

from seamless_usd import fileio
from runchecks import PLUMBING
from seamless_usd_cli.main import main

TEX = 112  # just above the 100 px minimum crop: small stacks train in a second with --preset tiny
PROCESS_ARGS = (*PLUMBING, "--max-size", str(TEX))


# real files ------------------------------------------------------------------------------------


def texture(seed: int, size: int = TEX, channels: int = 3) -> np.ndarray:
    """A non-tileable pattern (bricks with noise, lit unevenly as a photo is: the wrap steps in tone), float32
    in [0, 1], (H, W, C)."""
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[0:size, 0:size].astype(np.float32)
    bricks = ((x + 8 * (y // 16 % 2)) % 32 > 2) & (y % 16 > 1)
    base = 0.25 + 0.5 * bricks[..., None] + 0.15 * rng.random((size, size, channels))
    lit = (0.75 + 0.35 * x / max(size - 1, 1))[..., None]
    return np.clip(base * lit * (0.6 + 0.4 * np.linspace(0, 1, channels)), 0, 1).astype(np.float32)


def write_image(path: Path, pixels: np.ndarray, fmt=oiio.UINT8) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    h, w, c = pixels.shape
    out = oiio.ImageOutput.create(str(path))
    assert out is not None, oiio.geterror()
    assert out.open(str(path), oiio.ImageSpec(w, h, c, fmt)), out.geterror()
    assert out.write_image(np.ascontiguousarray(pixels, dtype=np.float32)), out.geterror()
    out.close()
    return path


def png_claiming(path: Path, width: int, height: int) -> Path:
    """A small valid PNG whose IHDR claims ``width x height`` (valid CRC, same image data)."""
    small = write_image(path.with_name("_small_" + path.name), texture(9, 8))
    data = small.read_bytes()
    small.unlink()
    out, pos = [data[:8]], 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos: pos + 4])
        raw = data[pos: pos + 12 + length]
        if raw[4:8] == b"IHDR":
            body = struct.pack(">II", width, height) + raw[16:21]
            raw = struct.pack(">I", 13) + b"IHDR" + body + struct.pack(">I", zlib.crc32(b"IHDR" + body))
        out.append(raw)
        pos += 12 + length
    path.write_bytes(b"".join(out))
    return path


MATERIAL = """
        def Material "{name}"
        {{
            token outputs:surface.connect = </Root/Looks/{name}/Surface.outputs:surface>

            def Shader "Surface"
            {{
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </Root/Looks/{name}/Tex.outputs:rgb>
                token outputs:surface
            }}

            def Shader "St"
            {{
                uniform token info:id = "UsdPrimvarReader_float2"
                string inputs:varname = "st"
                float2 outputs:result
            }}

            def Shader "Tex"
            {{
                uniform token info:id = "UsdUVTexture"
                asset inputs:file = @{asset}@
                float2 inputs:st.connect = </Root/Looks/{name}/St.outputs:result>
                float3 outputs:rgb
            }}
        }}
"""


def write_scene(path: Path, materials: dict[str, str], sublayers: tuple[str, ...] = (),
                references: tuple[str, ...] = (), extra: str = "") -> Path:
    """A ``.usda`` with one UsdPreviewSurface material per ``name -> texture asset path``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    subs = f"    subLayers = [{', '.join(f'@{s}@' for s in sublayers)}]\n" if sublayers else ""
    refs = "".join(
        f'    def "Ref{i}" (prepend references = @{r}@)\n    {{\n    }}\n' for i, r in enumerate(references)
    )
    body = "".join(MATERIAL.format(name=n, asset=a) for n, a in materials.items())
    path.write_text(
        f'#usda 1.0\n(\n    defaultPrim = "Root"\n{subs})\n\ndef Xform "Root"\n{{\n{refs}'
        f'    def Scope "Looks"\n    {{{body}{extra}\n    }}\n}}\n',
        encoding="utf-8",
    )
    assert Usd.Stage.Open(str(path)), f"{path} must be a valid stage"
    return path


def hashes(root: Path) -> dict[str, str]:
    return {str(p.relative_to(root)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(root.rglob("*")) if p.is_file()}


def leftovers(root: Path) -> list[str]:
    """Temporary files of atomic writes left anywhere under ``root``."""
    return sorted(str(p.relative_to(root)) for p in root.rglob("*") if ".tmp" in p.name)


def image_size(path: Path) -> tuple[int, int]:
    inp = oiio.ImageInput.open(str(path))
    assert inp is not None, f"{path} does not open: {oiio.geterror()}"
    try:
        spec = inp.spec()
        pixels = inp.read_image(oiio.FLOAT)
        assert pixels is not None, f"{path} does not decode: {inp.geterror()}"
        return spec.width, spec.height
    finally:
        inp.close()


def _pixels(path: Path) -> np.ndarray:
    inp = oiio.ImageInput.open(str(path))
    try:
        return inp.read_image(oiio.FLOAT)
    finally:
        inp.close()


def run_cli(capsys, *args: str) -> tuple[int, dict, str]:
    code = main(["process", *PROCESS_ARGS, "--json", *args])
    captured = capsys.readouterr()
    return code, json.loads(captured.out), captured.err


# the corpus ------------------------------------------------------------------------------------


@dataclass
class Bad:
    name: str  # material name
    asset: str  # as authored in the stage
    expect: str  # "error" (a one-line error naming the item) or "ok" (processed into a valid tile)


def _corpus(tex: Path, far: Path) -> list[Bad]:
    """Write the bad texture files under ``tex`` and list the materials using them."""
    png = write_image(tex / "good.png", texture(1)).read_bytes()
    jpg = write_image(tex / "good.jpg", texture(2)).read_bytes()
    exr = write_image(tex / "good.exr", texture(3), oiio.HALF).read_bytes()
    (tex / "good.jpg").unlink()
    (tex / "good.exr").unlink()
    rng = np.random.default_rng(0)

    def garble(data: bytes, start: int) -> bytes:
        return data[:start] + rng.integers(0, 256, len(data) - start, dtype=np.uint8).tobytes()

    files = {
        "trunc.png": png[: len(png) * 2 // 5],
        "corrupt.png": garble(png, 60),
        "trunc.jpg": jpg[: len(jpg) // 3],
        "corrupt.jpg": jpg[:2] + garble(jpg, 2)[2:],
        "trunc.exr": exr[: len(exr) // 2],
        "corrupt.exr": garble(exr, len(exr) // 3),
        "empty.png": b"",
        "text.png": b"this is not an image\n" * 10,
    }
    for name, data in files.items():
        (tex / name).write_bytes(data)
    write_image(tex / "one_pixel.png", texture(4, 1))
    png_claiming(tex / "huge.png", 50_000, 50_000)
    # wrong extensions: a PNG named .jpg / .exr, an EXR named .png
    write_image(tex / "other.png", texture(5))
    (tex / "other.png").rename(tex / "png_named.jpg")
    (tex / "exr_named.png").write_bytes(exr)
    (tex / "png_as.exr").write_bytes(png)
    nonfinite = texture(6)
    nonfinite[3:9, 3:9, 0] = np.nan
    nonfinite[20:24, 50:60, 1] = np.inf
    nonfinite[40, 40, 2] = -np.inf
    write_image(tex / "nonfinite.exr", nonfinite, oiio.FLOAT)
    write_image(tex / "dir with spaces" / "bríck ñ 木 tex.png", texture(7))
    write_image(far / "far.png", texture(8))

    items = [Bad(f"Bad_{Path(n).stem}_{Path(n).suffix[1:]}", f"./tex/{n}", "error") for n in files]
    items += [
        Bad("Bad_one_pixel", "./tex/one_pixel.png", "error"),
        Bad("Bad_huge_header", "./tex/huge.png", "error"),
        Bad("Bad_missing_file", "./tex/not_there.png", "error"),
        Bad("Odd_png_named_jpg", "./tex/png_named.jpg", "ok"),
        Bad("Odd_exr_named_png", "./tex/exr_named.png", "ok"),
        Bad("Odd_png_named_exr", "./tex/png_as.exr", "ok"),
        Bad("Odd_nonfinite_exr", "./tex/nonfinite.exr", "ok"),
        Bad("Odd_unicode_path", "./tex/dir with spaces/bríck ñ 木 tex.png", "ok"),
        # outputs are named from the stem only: a source far up the tree still lands in the output folder
        Bad("Odd_escaping_asset", f"../../{far.parent.name}/{far.name}/../{far.name}/far.png", "ok"),
    ]
    return items


CYCLE = """
        def Material "Bad_cycle"
        {
            token outputs:surface.connect = </Root/Looks/Bad_cycle/Surface.outputs:surface>

            def Shader "Surface"
            {
                uniform token info:id = "UsdPreviewSurface"
                color3f inputs:diffuseColor.connect = </Root/Looks/Bad_cycle/A.outputs:out>
                token outputs:surface
            }

            def NodeGraph "A"
            {
                color3f inputs:in.connect = </Root/Looks/Bad_cycle/B.outputs:out>
                color3f outputs:out.connect = </Root/Looks/Bad_cycle/B.outputs:out>
            }

            def NodeGraph "B"
            {
                color3f outputs:out.connect = </Root/Looks/Bad_cycle/A.outputs:out>
            }

            def Shader "Mix"
            {
                uniform token info:id = "ND_mix_color3"
                color3f inputs:fg.connect = </Root/Looks/Bad_cycle/Mix.outputs:out>
                color3f inputs:bg.connect = </Root/Looks/Bad_cycle/Mix.outputs:out>
                color3f outputs:out
            }
        }
"""


@pytest.fixture(scope="module")
def shared_cache(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("reliability-cache")


def test_bad_input_corpus_each_item_one_line_rest_goes_on(tmp_path, capsys, shared_cache):
    lib = tmp_path / "lib"
    items = _corpus(lib / "tex", tmp_path / "far")
    good = {"Good": "./tex/good.png"}
    scene = write_scene(
        lib / "scene.usda",
        {**good, **{b.name: b.asset for b in items}},
        sublayers=("./missing_sublayer.usda",),
        references=("./missing_reference.usda",),
        extra=CYCLE + CYCLE.replace("Bad_cycle", "Bad_cycle2").replace(
            "color3f inputs:diffuseColor.connect = </Root/Looks/Bad_cycle2/A.outputs:out>",
            "color3f inputs:diffuseColor.connect = </Root/Looks/Bad_cycle2/Mix.outputs:out>"),
    )
    unreadable = {  # top-level inputs that cannot be read
        "broken.usda": b"#usda 1.0\ndef Xform (\n",
        "empty.usda": b"",
        "garbage.usdc": bytes(np.random.default_rng(1).integers(0, 256, 300, dtype=np.uint8)),
        "garbage.usdz": bytes(np.random.default_rng(2).integers(0, 256, 300, dtype=np.uint8)),
        "cut.mtlx": b'<?xml version="1.0"?>\n<materialx version="1.38">\n<nodegraph name="x"><image name=',
    }
    for name, data in unreadable.items():
        (lib / name).write_bytes(data)
    top_level = [lib / name for name in unreadable] + [lib / "not_there.usda"]
    before = hashes(lib)

    code, report, err = run_cli(capsys, str(scene), "--cache-dir", str(shared_cache))
    assert code == 1, err
    by_material = {s["material"]: s for s in report["stacks"]}
    findings = report["findings"]
    handled, problems, tried = [], [], 0

    def mentions(item: Bad) -> list[dict]:
        asset = Path(item.asset).name
        return [f for f in findings if f"/Looks/{item.name}" in f["where"] + f["message"] + f.get("material", "")
                or asset in f["where"] + f["message"]]

    for item in items:
        tried += 1
        stack = by_material.get(f"</Root/Looks/{item.name}>")
        about = mentions(item)
        if item.expect == "error":
            errors = [f for f in about if f["severity"] in ("error", "skipped")]
            ok = bool(errors) and all("\n" not in f["message"] for f in about)
            ok = ok and all(("<" in f["where"] or "@" in f["where"]) for f in errors)
            set_aside = all(f["code"] in ("too-small", "udim", "animated-file") for f in errors)  # not made, not broken
            ok = ok and (stack is None or stack["status"] == ("left-alone" if set_aside else "failed"))
        else:
            ok = stack is not None and stack["status"] in ("passed", "not-passed")
            for m in stack["maps"] if ok else []:
                ok = ok and bool(np.isfinite(_pixels(Path(m["output"]))).all())
        if ok:
            handled.append(item.name)
        else:
            problems.append((item.name, stack and stack["status"], stack and stack["message"], about))
    # cycles: the scan goes on, the material is simply without maps (or reported), never a crash
    from seamless_usd.discover import scan_paths

    scanned = scan_paths([scene])
    for name in ("Bad_cycle", "Bad_cycle2"):
        tried += 1
        material = f"</Root/Looks/{name}>"
        cyc = [f for f in findings if name in f["where"] + f.get("material", "")]
        # seen by the scan, no stack (nothing to train), any finding about it on one line
        if material in scanned.materials and material not in by_material and all("\n" not in f["message"] for f in cyc):
            handled.append(name)
        else:
            problems.append((name, cyc))
    # missing sublayer and reference: warnings naming the asset; the rest composed
    for asset in ("missing_sublayer.usda", "missing_reference.usda"):
        tried += 1
        if any(asset in f["message"] or asset in f["where"] for f in findings if f["code"] == "composition-error"):
            handled.append(asset)
        else:
            problems.append((asset, [f for f in findings if f["code"] == "composition-error"]))
    assert by_material["</Root/Looks/Good>"]["status"] in ("passed", "not-passed")
    for stack in report["stacks"]:
        for m in stack["maps"]:
            if m["output"]:
                w, h = image_size(Path(m["output"]))
                assert (w, h) == tuple(stack["tile_size"][::-1])
                assert Path(m["output"]).parent == (lib / "tileable").resolve()
    assert leftovers(lib) == []
    assert hashes(lib) == {**before, **{k: v for k, v in hashes(lib).items() if k not in before}}
    assert (lib / "scene.seamless.usda").is_file() and Usd.Stage.Open(str(lib / "scene.seamless.usda"))

    # unreadable top-level inputs among a good one: exit 2, one line each, the good one still processed
    code2, report2, _ = run_cli(capsys, *map(str, top_level), str(scene), "--cache-dir", str(shared_cache))
    good_done = any(s["status"] in ("passed", "not-passed", "reused") for s in report2["stacks"])
    for path in top_level:
        tried += 1
        lines = [f for f in report2["findings"] if f["code"] == "unreadable-input" and path.name in f["where"]]
        if code2 == 2 and str(path) in report2["unreadable"] and good_done and len(lines) == 1 \
                and "\n" not in lines[0]["message"]:
            handled.append(path.name)
        else:
            problems.append((path.name, code2, report2["unreadable"], lines))
    with capsys.disabled():
        print(f"\nbad inputs (corpus, two process runs): tried {tried}, handled cleanly {len(handled)}")
    assert not problems, problems
    assert len(handled) == tried


def test_temporary_files_of_killed_writers_are_removed_by_the_next_write(tmp_path):
    target = tmp_path / "albedo.tile.png"
    dead = subprocess.Popen(["true"])
    dead.wait()
    owner = fileio._OWNER
    stale = tmp_path / f".albedo.tile.{owner}-{dead.pid}.abc123.tmp.png"
    alive = tmp_path / f".albedo.tile.{owner}-{os.getpid()}.def456.tmp.png"
    other_host = tmp_path / f".albedo.tile.elsewhere-{dead.pid}.ghi789.tmp.png"
    other_file = tmp_path / f".brick.{owner}-{dead.pid}.jkl000.tmp.png"
    for p in (stale, alive, other_host, other_file):
        p.write_bytes(b"partial")
    fileio.atomic_write_bytes(target, b"new")
    assert target.read_bytes() == b"new"
    assert not stale.exists()
    assert alive.exists() and other_host.exists() and other_file.exists()


def test_a_layer_left_half_saved_by_a_killed_run_is_not_taken_for_a_stage(tmp_path):
    """A run killed while it saved a layer in place left its temporary layer (a whole copy, or empty) and USD's own
    temporary file beside it: a folder walk took the temporary layer for a stage (its materials counted twice, or an
    exit 2 for a stage that cannot be read), and the next write of the layer left USD's file behind."""
    from seamless_usd.pipeline.inputs import expand_inputs

    dead = subprocess.Popen(["true"])
    dead.wait()
    scene = write_scene(tmp_path / "looks.usda", {"M": "./m.png"})
    ours = tmp_path / f".looks.{fileio._OWNER}-{dead.pid}.abc123.tmp.usda"
    usds = tmp_path / f".looks.{fileio._OWNER}-{dead.pid}.abc123.tmp.Hv97tP"
    ours.write_text(scene.read_text())
    usds.write_text("#usda 1.0\n")
    assert expand_inputs([tmp_path], require_scenes=True) == [scene]
    fileio.atomic_write_text(scene, scene.read_text())
    assert not ours.exists() and not usds.exists()


# read-only output folder, full disk -------------------------------------------------------------


@contextlib.contextmanager
def small_filesystem(path: Path, size: str, read_only: bool = False):
    """A real tmpfs of ``size`` mounted at ``path`` (as root), else None."""
    path.mkdir(parents=True)
    if os.geteuid() != 0 or shutil.which("mount") is None:
        yield None
        return
    options = f"size={size}" + (",ro" if read_only else "")
    if subprocess.run(["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)], capture_output=True).returncode:
        yield None
        return
    try:
        yield path
    finally:
        subprocess.run(["umount", "-l", str(path)], capture_output=True)


def _three_materials(lib: Path) -> Path:
    names = {f"M{i}": f"./tex/m{i}.png" for i in range(3)}
    for i in range(3):
        write_image(lib / "tex" / f"m{i}.png", texture(20 + i))
    return write_scene(lib / "scene.usda", names)


def _write_failures(report: dict) -> list[str]:
    return [s["message"] for s in report["stacks"] if s["status"] == "failed"]


def _one_line_naming_asset(message: str) -> bool:
    return "\n" not in message and message.count("@") >= 2


def test_read_only_output_folder(tmp_path, capsys, shared_cache):
    scene = _three_materials(tmp_path / "lib")
    with small_filesystem(tmp_path / "ro", "1m", read_only=True) as mounted:
        out = mounted
        if out is None:
            if os.geteuid() == 0:
                pytest.skip("running as root without mount: a chmod'ed folder stays writable")
            out = tmp_path / "ro"
            out.chmod(0o555)
        # refused before any work, naming the folder (every stack would fail to write there)
        code = main(["process", *PROCESS_ARGS, str(scene), "--output-dir", str(out), "--cache-dir", str(shared_cache)])
        err = capsys.readouterr().err
        assert code == 2 and "--output-dir" in err and str(out) in err
        assert "read-only" in err.lower() or "permission" in err.lower(), err
        assert list(out.iterdir()) == []
    assert leftovers(tmp_path / "lib") == []


def test_a_scene_on_a_read_only_file_system_fails_each_stack_with_why(tmp_path, capsys, shared_cache):
    """The default tiles' folder beside the stage cannot be made: each stack fails naming it, before any work
    (it was an internal error on every stack after the work)."""
    made = tmp_path / "made"
    _three_materials(made)
    with small_filesystem(tmp_path / "ro", "4m") as mounted:
        if mounted is None:
            pytest.skip("cannot mount a tmpfs here")
        shutil.copytree(made, mounted / "lib")
        if subprocess.run(["mount", "-o", "remount,ro", str(mounted)], capture_output=True).returncode:
            pytest.skip("cannot remount read-only here")
        code, report, _ = run_cli(capsys, str(mounted / "lib" / "scene.usda"), "--cache-dir", str(shared_cache))
        failures = _write_failures(report)
        assert code == 1 and len(failures) == 3, report["stacks"]
        assert all("its tiles cannot be written" in m and "tileable" in m and "internal error" not in m
                   for m in failures), failures
        assert all("give --output-dir to write the tiles elsewhere (and -o for the new layer" in m for m in failures)


def test_full_disk_real_small_filesystem(tmp_path, capsys, shared_cache):
    scene = _three_materials(tmp_path / "lib")
    with small_filesystem(tmp_path / "full", "90k") as out:
        if out is None:
            pytest.skip("cannot mount a small tmpfs here; the fault-injecting test covers a full disk")
        # the paper's 2c tiles (4x the source's area, 50-70 KB each as PNG): the first stack fits in 90 KB, the
        # three do not
        code, report, _ = run_cli(capsys, str(scene), "--output-dir", str(out), "--cache-dir", str(shared_cache),
                                  "--tile-size", "paper", "--refine", "on")
        failures = _write_failures(report)
        written = [Path(m["output"]) for s in report["stacks"] if s["status"] != "failed" for m in s["maps"]]
        assert code == 1 and failures and written, report["stacks"]
        assert all(_one_line_naming_asset(m) for m in failures), failures
        assert all("space" in m.lower() or "read back" in m.lower() for m in failures), failures
        for path in written:
            image_size(path)  # complete: opens and decodes
        assert sorted(p.name for p in out.iterdir()) == sorted(p.name for p in written)  # no partial file
        layer = scene.with_name("scene.seamless.usda")
        assert Usd.Stage.Open(str(layer))  # the layer holds the stacks that were written


def test_full_disk_fault_injected_at_flush(tmp_path, capsys, shared_cache, monkeypatch):
    """Portable: the second tile's flush fails with ENOSPC, as a full disk makes it."""
    scene = _three_materials(tmp_path / "lib")
    real_fsync = fileio._fsync_file
    calls = []

    def failing_fsync(path: Path) -> None:
        if path.suffix == ".png":
            calls.append(path)
            if len(calls) == 2:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        real_fsync(path)

    monkeypatch.setattr(fileio, "_fsync_file", failing_fsync)
    code, report, _ = run_cli(capsys, str(scene), "--cache-dir", str(shared_cache))
    failures = _write_failures(report)
    assert code == 1 and len(failures) == 1, report["stacks"]
    assert _one_line_naming_asset(failures[0]) and "No space left on device" in failures[0]
    out = tmp_path / "lib" / "tileable"
    assert leftovers(tmp_path / "lib") == []
    assert len(list(out.iterdir())) == 2
    assert Usd.Stage.Open(str(scene.with_name("scene.seamless.usda")))


def test_pixel_limit_is_a_job_setting_refused_before_decoding(tmp_path, shared_cache):
    from seamless_usd.discover import scan_paths
    from seamless_usd.errors import InputError
    from seamless_usd.pipeline.stackjob import JobSettings, StackJob, run_stack

    write_image(tmp_path / "tex" / "a.png", texture(40))
    [stack] = scan_paths([write_scene(tmp_path / "scene.usda", {"A": "./tex/a.png"})]).stacks
    settings = JobSettings(preset="tiny", cache_dir=shared_cache, max_pixels=TEX * TEX - 1)
    with pytest.raises(InputError, match=rf"@.*a\.png@: the header claims {TEX}x{TEX} .*limit of {TEX * TEX - 1}"):
        run_stack(StackJob(stack=stack, settings=settings, output_dir=tmp_path / "out"))
    assert not (tmp_path / "out").exists() or not list((tmp_path / "out").iterdir())
    done = run_stack(StackJob(stack=stack, settings=JobSettings(preset="tiny", cache_dir=shared_cache,
                                                                  max_pixels=TEX * TEX), output_dir=tmp_path / "out"))
    assert all(Path(m.output).is_file() for m in done.maps.values())


def test_a_layer_that_does_not_read_back_never_replaces_the_old_one(tmp_path):
    from seamless_usd.authoring.files import check_layer, write_atomically
    from seamless_usd.errors import InputError

    target = tmp_path / "scene.seamless.usda"
    target.write_text("#usda 1.0\n", encoding="utf-8")
    with pytest.raises(InputError, match=r"@.*scene\.seamless\.usda@: the written layer does not read back"):
        write_atomically(target, lambda tmp: tmp.write_text("#usda 1.0\ndef (", encoding="utf-8"), check=check_layer)
    assert target.read_text(encoding="utf-8") == "#usda 1.0\n"
    assert leftovers(tmp_path) == []


def test_a_layer_that_cannot_be_written_is_one_line_and_the_other_scene_goes_on(tmp_path, capsys, shared_cache,
                                                                                  monkeypatch):
    """ENOSPC injected when the first override layer is flushed: that scene's edits are reported."""
    scenes = []
    for k in range(2):
        write_image(tmp_path / f"s{k}" / "tex" / "a.png", texture(50 + k))
        scenes.append(write_scene(tmp_path / f"s{k}" / "scene.usda", {"A": "./tex/a.png"}))
    real_fsync = fileio._fsync_file
    failed: list[Path] = []

    def failing_fsync(path: Path) -> None:
        if path.suffix == ".usda" and not failed:
            failed.append(path)
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        real_fsync(path)

    monkeypatch.setattr(fileio, "_fsync_file", failing_fsync)
    code, report, _ = run_cli(capsys, *map(str, scenes), "--cache-dir", str(shared_cache))
    assert code == 1
    errors = [f for f in report["findings"] if f["severity"] == "error"]
    assert len(errors) == 1 and "\n" not in errors[0]["message"], errors
    assert "No space left on device" in errors[0]["message"] and "scene.seamless.usda@" in errors[0]["message"]
    written = [s for s in scenes if s.with_name("scene.seamless.usda").is_file()]
    assert len(written) == 1 and Usd.Stage.Open(str(written[0].with_name("scene.seamless.usda")))
    assert leftovers(tmp_path) == []
