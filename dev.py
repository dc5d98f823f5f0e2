#!/usr/bin/env python3
"""Set up a virtual environment and run the project's main jobs.

    python3 dev.py demo      # set up, then process the bundled sample scene
    python3 dev.py tests     # set up, then run the test suite
    python3 dev.py setup     # set up only
    python3 dev.py blender-tests   # optional: the Blender hook tests in their own .venv-blender

Needs only Python 3.11+. The environment lives in ``.venv`` beside this file
(``SEAMLESS_USD_VENV`` overrides it). PyTorch is installed first, pinned to a CPU
build, so that no dependency drags in a multi-gigabyte CUDA build.
"""
from __future__ import annotations

import hashlib
import os
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent
VENV = Path(os.environ.get("SEAMLESS_USD_VENV", ROOT / ".venv"))
TORCH = "torch==2.13.0"
DEMO_SCENE = ROOT / "sample_assets" / "brick" / "scene.usda"
DEMO_OUT = ROOT / "out" / "demo"


def _bin(name: str) -> Path:
    return VENV / ("Scripts" if os.name == "nt" else "bin") / name


def _run(*cmd: object) -> None:
    print("+", " ".join(str(c) for c in cmd), flush=True)
    subprocess.run([str(c) for c in cmd], check=True)


def setup() -> None:
    """Create the venv and install torch (CPU) first, then the project with its test extras.

    The project is installed editable: its code needs no install again, only what ``pyproject.toml`` declares (its
    dependencies, its commands) and the torch build pinned here. So once done, set-up is done again only when one of
    them changed (checking the install and importing torch took 7 s a run)."""
    wanted = hashlib.sha256((ROOT / "pyproject.toml").read_bytes() + TORCH.encode()).hexdigest()
    stamp = VENV / ".seamless-usd-installed"
    if _bin("python").exists() and stamp.is_file() and stamp.read_text() == wanted:
        return
    if not _bin("python").exists():
        venv.EnvBuilder(with_pip=True).create(VENV)
    py = _bin("python")
    probe = subprocess.run([py, "-c", "import torch"], capture_output=True)
    if probe.returncode != 0:
        _run(py, "-m", "pip", "install", "--disable-pip-version-check", "-q", TORCH)
    _run(py, "-m", "pip", "install", "--disable-pip-version-check", "-q", "-e", f"{ROOT}[test]")
    stamp.write_text(wanted)


def demo(extra: list[str]) -> int:
    """Process the bundled brick scene with the draft preset; outputs go to out/demo/."""
    setup()
    cmd = [
        _bin("seamless-usd"), "process", DEMO_SCENE, "--preset", "draft",
        "-o", DEMO_OUT / "scene.seamless.usda", "--output-dir", DEMO_OUT / "tileable",
        "--report", DEMO_OUT / "report.html", *extra,
    ]
    print("+", " ".join(str(c) for c in cmd), flush=True)
    code = subprocess.run([str(c) for c in cmd]).returncode
    print(f"\noutput stage: {DEMO_OUT / 'scene.seamless.usda'}\nreport:       {DEMO_OUT / 'report.html'}")
    return code


def tests(extra: list[str]) -> int:
    """The suite on two pytest-xdist workers (just under 5 minutes on 2 cores); ``-n 0`` after
    ``tests`` runs it in one process, ``-n N`` on N workers (``SEAMLESS_USD_TEST_WORKERS`` sets the default)."""
    setup()
    workers = os.environ.get("SEAMLESS_USD_TEST_WORKERS", "2")
    env = _test_env(workers)
    # the project's bytecode once, before the workers and the commands the tests start each compile it
    subprocess.run([_bin("python"), "-m", "compileall", "-q", "-j", "0", str(ROOT / "seamless_usd"),
                    str(ROOT / "cli")], env=env, check=True)
    # work stealing: a worker that runs out takes the other's queued tests (the suite's tests run 0.01-11 s, so the
    # last minute of a fixed split ran on one worker): 281.5 s against 291.6 s, load 1.7 and 1.4 at the start
    cmd = [_bin("python"), "-m", "pytest", "-q", "-n", workers, "--dist", "worksteal", str(ROOT / "tests"), *extra]
    print("+", " ".join(str(c) for c in cmd), flush=True)
    return subprocess.run([str(c) for c in cmd], cwd=ROOT, env=env).returncode


def _test_env(workers: str) -> dict[str, str]:
    """Torch's threads shared out between the workers (each worker and the commands it starts): two workers
    of two threads each on two cores wait on each other. An ``OMP_NUM_THREADS`` already set is kept.
    Bytecode is written (``PYTHONDONTWRITEBYTECODE`` dropped): with it unset, every worker and every command a test
    starts compiled the project and pytest rewrote every test module again, about 3 s a worker and 0.3 s a command."""
    env = dict(os.environ)
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    n = int(workers) if workers.isdigit() else 0
    if n > 0:
        env.setdefault("OMP_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // n)))
    return env


def blender_tests(extra: list[str]) -> int:
    """Optional: tests_blender/run.py sets up .venv-blender (bpy, no usd-core) and runs them."""
    cmd = [sys.executable, str(ROOT / "tests_blender" / "run.py"), *extra]
    print("+", " ".join(cmd), flush=True)
    return subprocess.run(cmd, cwd=ROOT).returncode


def main(argv: list[str]) -> int:
    if argv and argv[0] == "blender-tests":
        return blender_tests(argv[1:])
    if not argv or argv[0] not in {"setup", "demo", "tests"}:
        print(__doc__)
        return 2
    action, extra = argv[0], argv[1:]
    if action == "setup":
        setup()
        return 0
    return demo(extra) if action == "demo" else tests(extra)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
