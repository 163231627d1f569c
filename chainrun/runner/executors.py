"""Where a sweep's runs are computed: ``concurrent.futures`` executors.

In this process (``InlineExecutor``, one job), on a local Dask cluster or a pool of
local processes (``jobs > 1``), or on an existing Dask cluster (a scheduler address or
scheduler file); ``open_executor`` chooses among them.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import os
import signal
import threading
import time
from pathlib import Path

from chainrun.errors import ChainrunError

#: The environment variable naming a Dask scheduler: Dask's own convention (it sets the
#: ``scheduler-address`` config key that ``distributed.Client()`` reads), read here
#: directly so that a sweep without it does not import Dask.
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"

#: Seconds to wait for an existing Dask scheduler to answer.
CONNECT_TIMEOUT = 20.0


class InlineExecutor(cf.Executor):
    """Runs each task in this process, at once, when it is submitted."""

    workers = "in this process"
    slots = 1

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        future: cf.Future = cf.Future()
        future.set_running_or_notify_cancel()
        try:
            result = fn(*args, **kwargs)
        except Exception as exc:  # reported per run, like a worker's exception
            future.set_exception(exc)
        else:
            future.set_result(result)
        return future


def _process_executor(jobs: int) -> cf.ProcessPoolExecutor:
    """Local processes, for ``jobs > 1`` when Dask is not installed.

    A function rather than a subclass: ``cf.ProcessPoolExecutor`` imports
    multiprocessing, which a sweep in this process does not need.
    """
    executor = cf.ProcessPoolExecutor(max_workers=jobs)
    executor.slots = jobs
    executor.workers = f"on {jobs} local processes"
    return executor


class DaskExecutor(cf.Executor):
    """A ``concurrent.futures.Executor`` over a Dask distributed client.

    Tasks are submitted as *pure*: a task's key is a hash of the function and its
    arguments. A client that resubmits a run (say, after a restart) while the same
    run still executes on a worker is attached to that execution rather than starting
    a second writer of the same file.

    Parameters
    ----------
    client : distributed.Client
    cluster : distributed.LocalCluster, optional
        An embedded cluster, closed with the executor.
    """

    def __init__(self, client, cluster=None):
        self.client = client
        self.cluster = cluster
        self._executor = client.get_executor(pure=True)
        self._slots = (0.0, 1)
        #: the worker processes an interrupted sweep killed (``shutdown``): their
        #: half-written files are removed by the sweep
        self.killed: set[int] = set()
        address = client.scheduler.address
        self.workers = (f"on a local Dask cluster of {len(cluster.workers)} workers"
                        if cluster is not None else f"on the Dask scheduler at {address}")

    @classmethod
    def local(cls, jobs: int) -> "DaskExecutor":
        """An embedded cluster of ``jobs`` single-threaded worker processes on 127.0.0.1."""
        import logging

        from distributed import Client, LocalCluster

        with _sigint_ignored():  # Ctrl-C stops this process, which stops the workers
            cluster = LocalCluster(
                n_workers=jobs, threads_per_worker=1, processes=True, host="127.0.0.1",
                dashboard_address=None, worker_dashboard_address=None,
                # the scheduler's HTTP server (metrics) would bind :8787 otherwise
                scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                memory_limit=0,  # like plain processes: a large run is not paused or killed
                silence_logs=logging.CRITICAL,  # failures come back with each run
            )
        try:
            return cls(Client(cluster, set_as_default=False), cluster)
        except BaseException:
            cluster.close()
            raise

    @classmethod
    def connect(cls, address: str | None = None, scheduler_file=None) -> "DaskExecutor":
        """A client of an existing cluster, checked to have chainrun on its machines."""
        from distributed import Client

        where = address or f"the scheduler in {scheduler_file}"
        if scheduler_file is not None and not Path(scheduler_file).is_file():
            raise ChainrunError(f"no Dask scheduler file {scheduler_file}")
        try:
            client = Client(address, scheduler_file=None if scheduler_file is None
                            else os.fspath(scheduler_file),
                            timeout=CONNECT_TIMEOUT, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise ChainrunError(f"cannot connect to Dask at {where}: {reason}") from None
        try:
            _check_versions(client)
        except BaseException:
            client.close()
            raise
        return cls(client)

    @property
    def slots(self) -> int:
        """Worker threads of the cluster now (asked at most every 2 s)."""
        when, slots = self._slots
        if time.monotonic() - when > 2.0:
            try:
                slots = max(1, sum(self.client.nthreads().values()))
            except Exception:  # a cluster that went away: keep the last count
                pass
            self._slots = (time.monotonic(), slots)
        return slots

    def submit(self, fn, /, *args, **kwargs) -> cf.Future:
        return self._executor.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Close the client (and the embedded cluster).

        With ``cancel_futures`` (an interrupted sweep), queued runs are cancelled and
        an embedded cluster is stopped without waiting for its running tasks.
        """
        hurry = cancel_futures or not wait
        if hurry and self.cluster is not None:
            # Our own worker processes: a run they compute is lost either way, and a
            # graceful close would wait for it (numba holds the worker's GIL).
            for nanny in list(self.cluster.workers.values()):
                pid = getattr(nanny, "pid", None)
                if pid:
                    try:
                        os.kill(pid, signal.SIGKILL)
                    except OSError:
                        pass
                    else:
                        self.killed.add(pid)
        try:
            if hurry:
                self._executor.shutdown(wait=False)
            self.client.close(timeout=2 if hurry else None)
        finally:
            if self.cluster is not None:
                try:
                    self.cluster.close(timeout=5 if hurry else None)
                except TimeoutError:
                    pass


@contextlib.contextmanager
def _sigint_ignored():
    """Ignore SIGINT while the worker processes start: they inherit it.

    Ctrl-C then reaches only this process, which stops the workers itself, rather
    than every worker printing a traceback. (A Ctrl-C within this second or so of
    start-up is lost; blocking the signal instead does not reach processes that
    Dask spawns from its own thread.)
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _check_versions(client) -> None:
    """Refuse a cluster whose scheduler or workers lack this version of chainrun."""
    import chainrun

    versions = client.get_versions(packages=["chainrun"])
    places = {"scheduler": versions.get("scheduler") or {}}
    places.update(versions.get("workers") or {})
    wrong = []
    for where, info in places.items():
        got = (info.get("packages") or {}).get("chainrun")
        if got != chainrun.__version__:
            wrong.append(f"{where} ({'not installed' if got is None else got})")
    if wrong:
        raise ChainrunError(
            f"the Dask cluster needs chainrun {chainrun.__version__} on the scheduler "
            f"and every worker; wrong on {', '.join(wrong)}"
        )


def dask_available() -> bool:
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def check_placement(*, jobs: int | None = None, scheduler: str | None = None,
                    scheduler_file=None) -> None:
    """Refuse contradictory choices of where to compute (see ``open_executor``)."""
    if scheduler is not None and scheduler_file is not None:
        raise ChainrunError("give a Dask scheduler address or a scheduler file, not both")
    if (scheduler is not None or scheduler_file is not None) and jobs is not None:
        raise ChainrunError("--jobs is for this machine; with a Dask scheduler the "
                            "cluster decides how many runs go at once")
    if jobs is not None and jobs < 1:
        raise ChainrunError(f"jobs must be >= 1, got {jobs}")


def open_executor(*, jobs: int | None = None, scheduler: str | None = None,
                  scheduler_file=None, runs: int | None = None) -> cf.Executor:
    """The executor a sweep runs on.

    Parameters
    ----------
    jobs : int, optional
        Runs computed at once on this machine. 1 (the default) computes in this
        process; more start a local Dask cluster of that many workers (local
        processes if Dask is not installed).
    scheduler : str, optional
        Address of an existing Dask scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    scheduler_file : path, optional
        A Dask scheduler file (``dask scheduler --scheduler-file``).
    runs : int, optional
        Runs to compute; local workers are not started beyond it, and a single run
        is computed in this process.

    Without ``jobs``, ``scheduler`` and ``scheduler_file``, the environment variable
    ``DASK_SCHEDULER_ADDRESS`` names the scheduler if it is set. ``jobs`` given
    explicitly wins over that variable.
    """
    check_placement(jobs=jobs, scheduler=scheduler, scheduler_file=scheduler_file)
    if scheduler is None and scheduler_file is None and jobs is None:
        scheduler = os.environ.get(SCHEDULER_ENV) or None
    if scheduler is not None or scheduler_file is not None:
        if not dask_available():
            raise ChainrunError(
                "a Dask scheduler needs Dask: pip install 'chainrun[dask]'")
        return DaskExecutor.connect(scheduler, scheduler_file)
    jobs = jobs or 1
    if runs is not None:
        jobs = min(jobs, max(runs, 1))
    if jobs <= 1:
        return InlineExecutor()
    if dask_available():
        return DaskExecutor.local(jobs)
    return _process_executor(jobs)
