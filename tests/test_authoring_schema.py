"""The SeamlessTileAPI schema plugin: registration, application, and loading from an installed wheel."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

from pxr import Usd

from seamless_usd.authoring import Provenance, Schema, read_provenance, register_schemas, schemas_known
from seamless_usd.authoring.schema import write_provenance
from seamless_usd_schemas import usd_plugin_dir

REPO = Path(__file__).resolve().parents[1]


def test_register_twice_and_schema_definition():
    assert register_schemas() and register_schemas() and schemas_known()
    definition = Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(Schema.TILE_API)
    assert set(definition.GetPropertyNames()) >= {
        Schema.SOURCE_ASSET, Schema.CROP_SIZE, Schema.UV_SCALE, Schema.Q_PASSED, Schema.Q_TAU,
        Schema.Q_BAND_MIN, Schema.MODEL_HASH, Schema.TOOL_VERSION,
    }
    assert Usd.SchemaRegistry.GetSchemaKind(Schema.TILE_API) == Usd.SchemaKind.SingleApplyAPI
    assert Usd.SchemaRegistry().FindAppliedAPIPrimDefinition(Schema.UV_TRANSFORM_API) is not None
    assert (usd_plugin_dir() / "plugInfo.json").is_file()
    assert (usd_plugin_dir() / "generatedSchema.usda").is_file()


def test_provenance_round_trip_through_a_saved_layer(tmp_path: Path):
    stage = Usd.Stage.CreateNew(str(tmp_path / "p.usda"))
    prim = stage.DefinePrim("/Tex", "Shader")
    prov = Provenance("./a b.png", (100, 80), (2.5, 1.25), True, 0.7, (0.8, 0.9), "hash", "0.1.0")
    write_provenance(prim, prov)
    stage.Save()
    again = Usd.Stage.Open(str(tmp_path / "p.usda"))
    reopened = again.GetPrimAtPath("/Tex")
    assert reopened.HasAPI(Schema.TILE_API)
    assert read_provenance(reopened) == prov
    empty = Usd.Stage.CreateInMemory()
    assert read_provenance(empty.DefinePrim("/X")) is None


CHECK = """
import json, sys
import seamless_usd_schemas
import seamless_usd.authoring as authoring
from pxr import Usd
stage = Usd.Stage.CreateInMemory()
prim = stage.DefinePrim("/T", "Shader")
prim.ApplyAPI("SeamlessTileAPI")
print(json.dumps({
    "schemas": seamless_usd_schemas.__file__,
    "authoring": authoring.__file__,
    "known": authoring.schemas_known(),
    "has_api": prim.HasAPI("SeamlessTileAPI"),
    "uv_scale_type": str(prim.GetAttribute("seamless:uvScale").GetTypeName()),
}))
"""


def test_schema_loads_from_an_installed_wheel(tmp_path: Path):
    """Build the wheel, install it into a throwaway venv, and ask USD about the schema there.

    By hand: ``pip wheel . --no-deps --no-build-isolation -w dist/``, then install it with
    ``pip install --no-deps`` into a venv that sees usd-core and MaterialX, and run
    ``python -c "import seamless_usd.authoring as a; print(a.schemas_known())"`` outside the
    source tree.
    """
    wheels = tmp_path / "wheels"
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(REPO), "--no-deps",
                    "--no-build-isolation", "-q", "-w", str(wheels)],
                   check=True, cwd=tmp_path, capture_output=True)
    (wheel,) = wheels.glob("seamless_usd-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True)
    python = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
                               check=True, capture_output=True, text=True).stdout.strip())
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "-q",
                    "--target", str(site), str(wheel)], check=True, capture_output=True)
    # usd-core and MaterialX come from this environment, after the wheel's own files; the
    # editable install of this checkout is not activated (its .pth is not read from there).
    (site / "zz_project_deps.pth").write_text(sysconfig.get_path("purelib") + "\n")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PXR_PLUGINPATH_NAME")}
    run = subprocess.run([str(python), "-c", CHECK], capture_output=True, text=True,
                         cwd=tmp_path, env=env)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert Path(report["schemas"]).resolve().is_relative_to(site.resolve()), report
    assert Path(report["authoring"]).resolve().is_relative_to(site.resolve()), report
    assert report["known"] and report["has_api"] and report["uv_scale_type"] == "double2", report


LATE = """
from pxr import Usd
stage = Usd.Stage.CreateInMemory()
prim = stage.DefinePrim("/T", "Shader")  # builds USD's schema registry before the plugin is known
import json, seamless_usd.authoring as authoring
from seamless_usd.authoring.schema import write_provenance
write_provenance(prim, authoring.Provenance("a.png", (8, 8), (2.0, 2.0), True, 0.1, (0.2, 0.3), "h", "v"))
from seamless_usd.authoring.schema import has_applied
print(json.dumps({"known": authoring.schemas_known(), "applied": has_applied(prim, "SeamlessTileAPI"),
                  "read": authoring.read_provenance(prim).uv_scale}))
"""


def test_late_registration_still_writes_readable_provenance(tmp_path: Path):
    run = subprocess.run([sys.executable, "-c", LATE], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout.strip().splitlines()[-1])
    assert not report["known"] and report["applied"], report
    assert report["read"] == [2.0, 2.0]
