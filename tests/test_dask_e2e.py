"""A real Dask deployment: ``dask scheduler`` and two ``dask worker`` processes on 127.0.0.1, and
``seamless-usd process --scheduler tcp://127.0.0.1:PORT`` on a small library.

The tiles the workers write are byte-identical to an in-process run's. A worker killed in the middle of
a stack loses nothing: the scheduler gives the stack to the other worker, the run completes with the
same tiles, and every output is written once.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from runchecks import PLUMBING
from test_reliability_inputs import write_scene

from seamless_usd_cli.main import main

SAMPLES = Path(__file__).resolve().parents[1] / "sample_assets"
ARGS = (*PLUMBING, "--max-size", "112", "--json")


def _library(root: Path) -> Path:
    """Two one-map stacks in one layer."""
    (root / "textures").mkdir(parents=True)
    for name in ("brick_albedo.png", "cloth.png"):
        shutil.copy(SAMPLES / "textures" / name, root / "textures" / name)
    return write_scene(root / "looks" / "two.usda",
                       {"Brick": "../textures/brick_albedo.png", "Cloth": "../textures/cloth.png"})


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _dask() -> str:
    exe = Path(sys.executable).with_name("dask")
    if not exe.is_file():
        pytest.fail(f"the dask command is not installed beside {sys.executable} (the test extra installs it)")
    return str(exe)


class Deployment:
    """A scheduler and named workers as separate processes on the loopback address."""

    def __init__(self, root: Path):
        self.root = root
        self.address = f"tcp://127.0.0.1:{_free_port()}"
        self.procs: dict[str, subprocess.Popen] = {}

    def _spawn(self, name: str, *args: str) -> None:
        log = open(self.root / f"{name}.log", "wb")  # noqa: SIM115 - closed with the process
        self.procs[name] = subprocess.Popen([_dask(), *args], stdout=log, stderr=subprocess.STDOUT, cwd=self.root,
                                            env=dict(os.environ, PYTHONUNBUFFERED="1"))
        log.close()

    def start(self, workers: int) -> None:
        port = self.address.rsplit(":", 1)[1]
        self._spawn("scheduler", "scheduler", "--host", "127.0.0.1", "--port", port, "--no-dashboard")
        for n in range(workers):
            self._spawn_worker(f"worker{n}")
        self.wait_for_workers(workers)

    def _spawn_worker(self, name: str) -> None:
        self._spawn(name, "worker", self.address, "--name", name, "--nthreads", "1",
                    "--no-nanny", "--no-dashboard", "--host", "127.0.0.1", "--death-timeout", "60")

    def ensure_workers(self, workers: int) -> None:
        """Start again the workers of ``start(workers)`` that are no longer running (a test killed one)."""
        for n in range(workers):
            name = f"worker{n}"
            if self.procs[name].poll() is not None:
                self._spawn_worker(name)
        self.wait_for_workers(workers)

    def client(self):
        from distributed import Client

        return Client(self.address, timeout=30)

    def wait_for_workers(self, n: int, timeout: float = 60.0) -> None:
        with self.client() as client:
            client.wait_for_workers(n, timeout=timeout)

    def logs(self) -> str:
        return "\n".join(f"--- {p.name}\n{p.read_text(errors='replace')[-1500:]}" for p in self.root.glob("*.log"))

    def stop(self) -> None:
        """The workers first (they close at once while their scheduler is there), then the scheduler."""
        workers = [p for name, p in self.procs.items() if name != "scheduler"]
        for group in (workers, [self.procs["scheduler"]]):
            for proc in group:
                if proc.poll() is None:
                    proc.send_signal(signal.SIGTERM)
            for proc in group:
                try:
                    proc.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(timeout=10)


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """One scheduler and two workers for the module (starting them costs seconds of imports)."""
    d = Deployment(tmp_path_factory.mktemp("dask"))
    try:
        d.start(workers=2)
        yield d
    finally:
        d.stop()


@pytest.fixture()
def deployment(cluster) -> Deployment:
    """The module's deployment with both workers running (one killed by an earlier test is started again)."""
    cluster.ensure_workers(2)
    return cluster


def _tiles(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> tuple[dict[str, bytes], float]:
    """The tiles of an in-process run (cold cache) and its wall time, once for the module."""
    import contextlib
    import io

    scene = _library(tmp_path_factory.mktemp("inprocess"))
    out = io.StringIO()
    start = time.perf_counter()
    with contextlib.redirect_stdout(out):
        code = main(["process", str(scene), "--cache-dir", str(scene.parents[1] / "cache"), *ARGS])
    seconds = time.perf_counter() - start
    payload = json.loads(out.getvalue())
    assert code == payload["exit_code"] and len(payload["stacks"]) == 2
    assert {s["origin"] for s in payload["stacks"]} == {"trained"}
    tiles = _tiles(scene.parent / "tileable")
    assert len(tiles) == 2, tiles.keys()
    return tiles, seconds


def _check_run(payload: dict, scene: Path, expected: dict[str, bytes], origins: frozenset = frozenset({"trained"})
               ) -> None:
    """The run wrote every tile of the in-process run and nothing else; each stack's origin is one of
    ``origins``, and at least one stack was trained in this run."""
    assert not [f for f in payload["findings"] if f["severity"] == "error"], payload["findings"]
    statuses = sorted(s["status"] for s in payload["stacks"])
    assert len(statuses) == 2 and "failed" not in statuses, payload["stacks"]
    found = [s["origin"] for s in payload["stacks"]]
    assert set(found) <= origins and "trained" in found, payload["stacks"]
    assert payload["counts"]["trained"] == found.count("trained")
    assert payload["counts"]["from_cache"] == found.count("cache")
    # nothing lost, nothing extra (no second copy, no temporary file), every byte the in-process run's
    assert _tiles(scene.parent / "tileable") == expected
    written = [m["output"] for s in payload["stacks"] for m in s["maps"]]
    assert sorted(Path(p).name for p in written) == sorted(expected)
    assert sorted(p.name for p in scene.parent.iterdir() if p.is_file()) == ["two.seamless.usda", "two.usda"]


def test_a_tcp_scheduler_with_two_workers_writes_the_in_process_tiles(deployment, reference, tmp_path, capsys):
    expected, inprocess_s = reference
    scene = _library(tmp_path / "remote")
    start = time.perf_counter()
    code = main(["process", str(scene), "--cache-dir", str(tmp_path / "remote-cache"),
                 "--scheduler", deployment.address, *ARGS])
    remote_s = time.perf_counter() - start
    payload = json.loads(capsys.readouterr().out)
    assert code == payload["exit_code"]
    _check_run(payload, scene, expected)
    with deployment.client() as client:  # both stacks ran on the workers, none in this process
        assert len(client.scheduler_info()["workers"]) == 2
    print(f"\nwall time, 2 stacks: in-process {inprocess_s:.1f} s, tcp:// with 2 workers {remote_s:.1f} s")


def test_a_worker_killed_in_the_middle_of_a_stack_loses_nothing(deployment, reference, tmp_path):
    expected, _ = reference
    scene = _library(tmp_path / "killed")
    cache = tmp_path / "killed-cache"
    client_proc = subprocess.Popen(
        [sys.executable, "-m", "seamless_usd_cli.main", "process", str(scene), "--cache-dir", str(cache),
         "--scheduler", deployment.address, *ARGS],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    try:
        victim = _kill_a_worker_mid_stack(deployment, cache)
        out, err = client_proc.communicate(timeout=240)
    finally:
        if client_proc.poll() is None:
            client_proc.kill()
            client_proc.wait()
    assert client_proc.returncode in (0, 1), err.decode(errors="replace")[-3000:] + deployment.logs()
    assert deployment.procs[victim].poll() is not None, "the killed worker stays dead"
    # the worker is killed while it runs a stack and a training checkpoint exists; when the stack it ran had
    # just stored its result, the retry reads it from the cache (origin "cache"): nothing lost either way
    _check_run(json.loads(out), scene, expected, frozenset({"trained", "cache"}))


def _kill_a_worker_mid_stack(deployment: Deployment, cache: Path, timeout: float = 120.0) -> str:
    """SIGKILL a worker that holds a started stack: the scheduler says which worker runs a task, and its
    first training checkpoint in the cache says the stack is under way. Returns the worker's name."""
    with deployment.client() as client:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            busy = {info["name"]: addr for addr, info in client.scheduler_info()["workers"].items()
                    if client.processing(addr)[addr]}
            if busy and list(cache.glob("*/*/checkpoints/*.safetensors")):
                name = sorted(busy)[0]
                proc = deployment.procs[name]
                proc.send_signal(signal.SIGKILL)
                proc.wait(timeout=30)
                return name
            time.sleep(0.05)
    raise AssertionError("no stack was under way on a worker in time\n" + deployment.logs())


def test_ctrl_c_to_a_run_on_its_own_local_cluster_stops_it_quietly(tmp_path):
    """Ctrl-C from a terminal reaches every process of its group: the client and its local cluster's workers. The
    workers leave it to the client, which reports the run as interrupted and closes the cluster; no worker prints a
    traceback and Dask logs nothing (before: a traceback from every worker and warnings from every nanny), and the
    run ends at once (each nanny waited 4 s for its busy worker)."""
    from fswatch import wait_until

    lib = _library(tmp_path / "lib")
    cache = tmp_path / "cache"
    cmd = [sys.executable, "-m", "seamless_usd_cli.main", "process", *ARGS, "--iterations", "400",
           "--scheduler", "local:2", "--cache-dir", str(cache), str(lib)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))  # as a terminal's
    training = wait_until(lambda: bool(list(cache.glob("*/*/checkpoints/*"))), [tmp_path], timeout=240,
                          stop=lambda: proc.poll() is not None)
    assert training and proc.poll() is None, "the run ended before its workers trained"
    os.killpg(proc.pid, signal.SIGINT)
    stopped = time.monotonic()
    out, err = proc.communicate(timeout=120)
    assert time.monotonic() - stopped < 3.0, "the run ends at once: its workers are ended, not waited for"
    text = err.decode()
    assert proc.returncode == 130, text[-3000:]
    assert "Traceback" not in text and "distributed." not in text, text[-3000:]
    payload = json.loads(out)
    assert payload["interrupted"] and {s["status"] for s in payload["stacks"]} == {"failed"}
    assert not (lib / "two.seamless.usda").exists()
    time.sleep(1.0)
    listed = subprocess.run(["ps", "-e", "-o", "sid=,stat=,args="], capture_output=True, text=True).stdout.splitlines()
    alive = [line for line in listed if line.split()[0] == str(proc.pid) and not line.split()[1].startswith("Z")]
    assert not alive, f"processes of the run still running: {alive}"  # exited ones (zombies) wait for init to reap


def test_ctrl_c_to_a_run_on_a_remote_scheduler_leaves_no_tiles_from_jobs_still_running(deployment, tmp_path):
    """A job running on a remote worker cannot be ended from the client: it trained on after Ctrl-C and wrote its
    tiles a second after the report said none were made. The client now tells it the run stopped, and it writes
    nothing."""
    from fswatch import wait_until

    scene = _library(tmp_path / "lib")
    cache = tmp_path / "cache"
    proc = subprocess.Popen([sys.executable, "-m", "seamless_usd_cli.main", "process", str(scene), "--cache-dir",
                             str(cache), "--scheduler", deployment.address, *ARGS],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=tmp_path)
    training = wait_until(lambda: bool(list(cache.glob("*/*/checkpoints/*"))), [tmp_path], timeout=240,
                          stop=lambda: proc.poll() is not None)
    assert training and proc.poll() is None, "the run ended before its workers trained"
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err.decode(errors="replace")[-3000:]
    payload = json.loads(out)
    assert payload["interrupted"] and not [m for s in payload["stacks"] for m in s["maps"] if m.get("output")]
    with deployment.client() as client:  # the jobs the stopped run left on the workers have ended
        deadline = time.monotonic() + 120
        while any(client.processing().values()) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not any(client.processing().values()), deployment.logs()
    written = list((scene.parent / "tileable").glob("*")) if (scene.parent / "tileable").exists() else []
    assert not written, written
