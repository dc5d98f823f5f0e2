"""Executors: where stack jobs run. One interface, chosen by a validated name.

- ``None`` / ``"inprocess"``: one job after another in this process, using all cores for each
  (the embedded default; fine-grained progress).
- ``jobs=N`` (N > 1) with no scheduler: N worker processes on this machine (no Dask needed), each
  with ``cores // N`` torch threads: on few cores several 1-thread trainings give more
  throughput than one many-thread training.
- ``"local:N"``: a Dask ``LocalCluster`` of N single-threaded worker processes on this machine.
- ``"tcp://host:port"``: an existing Dask scheduler; outputs and cache must be on shared storage.

Workers only train, sample and write maps; stage and document edits happen in the client.
"""
from __future__ import annotations

import contextlib
import logging
import os
import sys
import uuid
from collections.abc import Callable, Iterator, Sequence
from typing import Protocol

from seamless_usd.errors import UsageError
from seamless_usd.pipeline.outcome import StackOutcome
from seamless_usd.pipeline.stackjob import StackJob, run_stack

__all__ = ["Executor", "InProcessExecutor", "ProcessPoolExecutor", "DaskExecutor", "make_executor", "EXECUTORS"]

Progress = Callable[[StackJob, str, object], None]
Result = StackOutcome | Exception


class Executor(Protocol):
    threads_per_job: int | None  # CPU threads each job trains on (None: not known, as on a remote cluster)

    def run(self, jobs: Sequence[StackJob], progress: Progress) -> Iterator[tuple[StackJob, Result]]:
        """Run ``jobs``; yield each with its outcome (or the exception that stopped it) as it ends."""


class InProcessExecutor:
    """Jobs one after another in this process; one failing job does not stop the others."""

    name = "inprocess"

    @property
    def threads_per_job(self) -> int:
        """The threads this process trains on: torch's where torch is loaded already (a host application may have
        set them), else what torch will take (``OMP_NUM_THREADS``, else every core), without loading torch."""
        torch = sys.modules.get("torch")
        if torch is not None:
            return torch.get_num_threads()
        try:
            return max(1, int(os.environ.get("OMP_NUM_THREADS", "")))
        except ValueError:
            return os.cpu_count() or 1

    def run(self, jobs, progress):
        for job in jobs:
            progress(job, "stack-start", None)
            try:
                result: Result = run_stack(job, lambda kind, detail, job=job: progress(job, kind, detail))
            except ImportError:  # not this stack's: every stack would fail alike (a broken install, or an import
                raise  # that Ctrl-C broke, which an extension's initialisation reports as an ImportError)
            except Exception as exc:  # noqa: BLE001 - reported per stack, the batch goes on
                result = exc
            yield job, result


def _run_on_worker(job: StackJob, threads: int, stop_event: str | None = None) -> Result:
    """Entry point on a worker process: limit torch threads, run, return errors as values. ``stop_event``: the name
    of the Dask event the client sets when the run is stopped (:class:`DaskExecutor`), asked before tiles are
    written."""
    import torch

    torch.set_num_threads(max(1, threads))
    stopped = None
    if stop_event is not None:
        from distributed import Event

        stopped = Event(stop_event).is_set
    try:
        return run_stack(job, None, stopped)
    except Exception as exc:  # noqa: BLE001 - the client reports it per stack
        return exc


def _ignore_ctrl_c() -> None:
    """A worker process leaves Ctrl-C to the client, which stops it (:func:`_stop`): a terminal's Ctrl-C reaches
    every process of its group, and a worker stopped by it printed its traceback."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _stop(pool) -> None:
    """Stop ``pool`` (a concurrent.futures process pool) now: its queued jobs cancelled, its worker processes ended
    (shutting it down waits for every job still running, a stack's whole training)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())  # not public; None once shut down
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        if process.is_alive():
            process.terminate()
    for process in processes:
        process.join(timeout=10)


def _threads_per_worker(workers: int) -> int:
    return max(1, (os.cpu_count() or 1) // max(1, workers))


class ProcessPoolExecutor:
    """Jobs in N local worker processes (spawned, so no state is inherited from the client)."""

    name = "processes"

    def __init__(self, workers: int):
        self.workers = workers
        self.threads_per_job = _threads_per_worker(workers)

    def run(self, jobs, progress):
        import multiprocessing
        from concurrent import futures

        if not jobs:  # nothing to do: no worker processes
            return
        threads = _threads_per_worker(self.workers)
        ctx = multiprocessing.get_context("spawn")
        pool = futures.ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_ignore_ctrl_c)
        try:
            pending = {}
            for job in jobs:
                progress(job, "stack-start", None)
                pending[pool.submit(_run_on_worker, job, threads)] = job
            for fut in futures.as_completed(pending):
                job = pending[fut]
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - a worker died (killed, out of memory)
                    result = exc
                yield job, result
        except BaseException:  # Ctrl-C, or the run stopped reading: the jobs not done are dropped, now
            _stop(pool)
            raise
        pool.shutdown(wait=True)


class DaskExecutor:
    """Jobs on a Dask cluster: a new local one (``local:N``) or an existing scheduler address."""

    name = "dask"

    def __init__(self, address: str, workers: int | None = None, threads_per_worker: int | None = None):
        self.address = address
        self.workers = workers
        self.threads_per_worker = threads_per_worker or _threads_per_worker(workers or 1)
        # a cluster of its own on this machine: its workers' threads; a remote one's are not known here
        self.threads_per_job = self.threads_per_worker if address == "local" else None

    def _remote(self, client_type):
        """A client of the scheduler at ``address``; a :class:`UsageError` naming it when it cannot be reached."""
        try:
            return client_type(self.address, timeout=CONNECT_TIMEOUT_S)
        except Exception as exc:  # noqa: BLE001 - whatever the comm raises (a timeout, a refused or garbled line)
            first = " ".join(str(exc).split())[:200] or type(exc).__name__
            raise UsageError(f"--scheduler {self.address}: cannot reach the Dask scheduler ({first}); check the "
                             "address and that the scheduler is running") from None

    def reach(self) -> None:
        """Make sure a remote scheduler answers, before a run writes anything: stacks from the cache are written in
        this process first, and a scheduler found unreachable only after them would leave their tiles with no
        layer. A local cluster is started when its jobs run."""
        if self.address != "local":
            try:
                from distributed import Client
            except ImportError:  # pragma: no cover - depends on the install
                return  # said when the jobs run
            self._remote(Client).close()

    def run(self, jobs, progress):
        if not jobs:  # nothing to do: no cluster started, no scheduler contacted
            return
        try:
            from distributed import Client, LocalCluster, as_completed
        except ImportError:  # pragma: no cover - depends on the install
            raise UsageError("a Dask scheduler needs the 'dask[distributed]' extra: pip install 'seamless-usd[dask]'") from None
        cluster = None
        if self.address == "local":
            with _ctrl_c_ignored_by_children():
                cluster = LocalCluster(
                    n_workers=self.workers or 2, threads_per_worker=self.threads_per_worker,
                    processes=True, dashboard_address=None, host="127.0.0.1",
                )
            client = Client(cluster)
        else:
            client = self._remote(Client)
        stop_event = f"seamless-usd-stop-{uuid.uuid4().hex}"
        try:
            futures = {}
            for job in jobs:
                progress(job, "stack-start", None)
                fut = client.submit(_run_on_worker, job, self.threads_per_worker, stop_event, pure=False)
                futures[fut] = job
            for fut in as_completed(futures):
                job = futures[fut]
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - a lost worker, say
                    result = exc
                yield job, result
        except BaseException:  # Ctrl-C, or the run stopped reading: the jobs still running are dropped
            level = _quiet()
            try:
                if cluster is not None:
                    _end_workers(cluster)
                else:  # a remote worker's job runs on: it is told not to write its tiles (the report says none)
                    _tell_stopped(client, stop_event)
                client.close()
                if cluster is not None:
                    cluster.close()
            finally:
                logging.getLogger("distributed").setLevel(level)  # a host process's own Dask logging, as it was
            raise
        client.close()
        if cluster is not None:
            cluster.close()


def _tell_stopped(client, stop_event: str) -> None:
    """Set the run's stop event, which jobs still running on remote workers read before they write any tile (jobs
    not started are dropped when the client closes); a scheduler that no longer answers is left as it is."""
    from distributed import Event

    try:
        Event(stop_event, client=client).set()
    except Exception:  # noqa: BLE001 - stopping anyway: nothing more can be told
        pass


@contextlib.contextmanager
def _ctrl_c_ignored_by_children():
    """Ctrl-C ignored while the block starts processes (a local Dask cluster's workers), which keep ignoring it: a
    terminal's Ctrl-C reaches every process of its group, and each worker stopped by it printed its traceback. The
    client stops them (it closes the cluster). Only from the main thread, where signals are handled."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def _quiet() -> int:
    """Dask's own logs in this process silenced before a run stopped part-way closes its cluster: jobs cancelled
    mid-task make the nannies and the client log warnings and tracebacks that say nothing to the user (the report
    says what stopped; a cluster of its own has its workers ended first, :func:`_end_workers`, so they log nothing).
    Returns the level before, to put back."""
    logger = logging.getLogger("distributed")
    level = logger.level
    logger.setLevel(logging.CRITICAL)
    return level


def _end_workers(cluster) -> None:
    """End a local cluster's worker processes now, as :func:`_stop` ends a process pool's: closed with a stack
    training, each nanny waited 4 s for its worker before it killed it. A worker killed mid-write leaves a temporary
    file at most, which the next write removes."""
    import signal

    for nanny in list(getattr(cluster, "workers", {}).values()):
        pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
        if pid:
            try:
                os.kill(pid, signal.SIGTERM)
            except OSError:  # ended already
                pass



#: Seconds to wait for a remote Dask scheduler to answer before the run is refused.
CONNECT_TIMEOUT_S = 20


def make_executor(scheduler: str | None, jobs: int | None = None) -> Executor:
    """Validated choice of executor; a clear error lists the valid forms."""
    if scheduler in (None, "", "inprocess"):
        if jobs is not None and jobs < 1:
            raise UsageError(f"--jobs {jobs}: needs at least 1")
        return InProcessExecutor() if (jobs or 1) == 1 else ProcessPoolExecutor(jobs)
    if scheduler == "local" or scheduler.startswith("local:"):  # not "localhost:8786" (a host without tcp://)
        _, _, n = scheduler.partition(":")
        try:
            workers = int(n) if n else (jobs or os.cpu_count() or 1)
        except ValueError:
            raise UsageError(f"--scheduler {scheduler!r}: expected local:N with N a whole number") from None
        if workers < 1:
            raise UsageError(f"--scheduler {scheduler!r}: N must be at least 1")
        if n and jobs is not None and jobs != workers:
            raise UsageError(f"--jobs {jobs} and --scheduler {scheduler} each set the workers: give one of them "
                             f"(--scheduler local --jobs {jobs} is the same as --scheduler local:{jobs})")
        return DaskExecutor("local", workers=workers)
    if scheduler.startswith(("tcp://", "tls://", "ucx://", "inproc://")):
        if jobs is not None:
            raise UsageError(f"--jobs {jobs} sets worker processes on this machine, but --scheduler {scheduler} runs "
                             "the stacks on that cluster's workers: leave --jobs out")
        return DaskExecutor(scheduler)
    hint = f" (a scheduler's address: tcp://{scheduler})" if ":" in scheduler and "/" not in scheduler else ""
    raise UsageError(
        f"unknown scheduler {scheduler!r}{hint}; use one of: inprocess (default), local:N, tcp://host:port"
    )


EXECUTORS = ("inprocess", "local:N", "tcp://host:port")
