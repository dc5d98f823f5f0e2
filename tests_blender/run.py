#!/usr/bin/env python3
"""The optional Blender test run: its own environment, then pytest on tests_blender/.

    python3 tests_blender/run.py            # set up .venv-blender (first time), run the tests
    python3 tests_blender/run.py -k usdz    # extra arguments go to pytest
    python3 tests_blender/run.py --setup    # set up only

The environment (``.venv-blender`` beside the repository's ``.venv``; ``SEAMLESS_USD_BLENDER_VENV``
overrides) holds the ``bpy`` package (Blender as a Python module, built for Python 3.11), PyTorch
(CPU) and seamless-usd installed with ``--no-deps`` plus its dependencies *except* those Blender
bundles: ``usd-core``, ``MaterialX`` and ``OpenImageIO``. Blender's own ``pxr`` has to be the one in
use (the stage Blender hands to a hook is of its types), and a second copy of these libraries
in the same process clashes with the bundled ones. ``bpy`` 5.0 is built against NumPy 1.x, so
NumPy stays below 2.
"""
from __future__ import annotations

import hashlib
import os
import re
import subprocess
import sys
import tomllib
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VENV = Path(os.environ.get("SEAMLESS_USD_BLENDER_VENV", ROOT / ".venv-blender"))
BPY = os.environ.get("SEAMLESS_USD_BPY", "bpy==5.0.1")  # 4.2's wheel has no pxr; 4.5's hangs at exit
TORCH = "torch==2.13.0"  # the CPU build, as dev.py installs it
BUNDLED_BY_BLENDER = {"usd-core", "materialx", "openimageio"}
CONSTRAINTS = ["numpy<2"]
EXTRA = ["pytest>=8"]


def _bin(name: str) -> Path:
    return VENV / ("Scripts" if os.name == "nt" else "bin") / name


def _run(*cmd: object) -> None:
    print("+", " ".join(str(c) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True)


def project_requirements() -> list[str]:
    """The project's dependencies from pyproject.toml, less torch and what Blender bundles."""
    deps = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["dependencies"]
    out = []
    for req in deps:
        name = re.match(r"[A-Za-z0-9_.\-]+", req).group(0).lower().replace("_", "-")
        if name == "torch" or name in BUNDLED_BY_BLENDER:
            continue
        out.append(req)
    return out


def setup() -> Path:
    """Create or update the Blender venv; a stamp skips the installs when nothing changed."""
    reqs = project_requirements()
    wanted = "\n".join([BPY, TORCH, *reqs, *EXTRA, *CONSTRAINTS])
    stamp = VENV / ".seamless-usd-stamp"
    digest = hashlib.sha256(wanted.encode()).hexdigest()
    if stamp.exists() and stamp.read_text() == digest and _bin("python").exists():
        return _bin("python")
    if not _bin("python").exists():
        venv.EnvBuilder(with_pip=True).create(VENV)
    py = _bin("python")
    pip = [py, "-m", "pip", "install", "--disable-pip-version-check", "-q"]
    constraints = VENV / "constraints.txt"
    constraints.write_text("\n".join(CONSTRAINTS) + "\n")
    _run(*pip, BPY, TORCH, "-c", constraints)
    _run(*pip, *reqs, *EXTRA, "-c", constraints)
    _run(*pip, "--no-deps", "-e", ROOT)
    stamp.write_text(digest)
    return py


def main(argv: list[str]) -> int:
    py = setup()
    if argv[:1] == ["--setup"]:
        return 0
    cmd = [str(py), "-m", "pytest", "-q", "-p", "no:cacheprovider", str(ROOT / "tests_blender"), *argv]
    print("+", " ".join(cmd), flush=True)
    return subprocess.run(cmd, cwd=ROOT / "tests_blender").returncode


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
