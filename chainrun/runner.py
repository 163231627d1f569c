"""Runs experiments: each RunSpec through the solver into its run file, then the index.

This module owns how a sweep is executed, into an experiment's output folder
(``chainrun.paths``)::

    OUTDIR/<run_id>.h5     one run file per point of the sweep (``run.h5`` without one)
    OUTDIR/index.h5        parameters and summary of every run, with external links

Runs go through a ``concurrent.futures.Executor``: in this process (one job), a
local Dask cluster or a pool of local processes (``jobs > 1``), or an existing Dask
cluster (a scheduler address or scheduler file). Each task writes its own run file
(a temporary name, then a rename); only this process writes the index.

A sweep is resumable: a run whose file exists and holds the run's ``config_hash`` is
skipped, so the same command after an interruption computes only what is missing.
A file holding another hash (or a file that is not a chainrun run file) is replaced
only with ``force``; otherwise the sweep refuses before running anything.

It reports through typed results and events (``RunSummary``, ``RunError``,
``SweepProgress``, ``SweepResult``) to plain callbacks; the words a person reads are
the command line's (``chainrun.cli``). It never imports click.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import math
import os
import queue
import signal
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from chainrun import atomic
from chainrun.check import Check
from chainrun.config import Experiment, RunSpec
from chainrun.errors import ChainrunError, StoreError
from chainrun.paths import INDEX_NAME, index_file, run_file  # noqa: F401 (INDEX_NAME: for callers)

#: The environment variable naming a Dask scheduler: Dask's own convention (it sets the
#: ``scheduler-address`` config key that ``distributed.Client()`` reads), read here
#: directly so that a sweep without it does not import Dask.
SCHEDULER_ENV = "DASK_SCHEDULER_ADDRESS"

#: Seconds to wait for an existing Dask scheduler to answer.
CONNECT_TIMEOUT = 20.0


@dataclass(frozen=True)
class RunSummary:
    """What a person (and the index file) needs to know about one run with a file.

    ``skipped`` is True for a run whose file was already there (from an earlier,
    identical computation) and was read instead of computed.
    """

    run_id: str
    file: str
    n: int
    k: int
    alpha: float
    outcome: str
    ok: bool
    terminal: bool
    end_time: float
    events: int
    steps: int
    momentum_error: float
    energy_error: float
    wall_time: float
    config_hash: str
    message: str
    final_velocity: np.ndarray
    skipped: bool = False
    dissipated: float = 0.0  # share of the energy taken up that the damping took
    units: str = "paper"  # the run's units: "paper" or "si"
    check: Check | None = None  # the conditioning check, if the run had one
    speed: float = 1.0  # the line's impact speed (largest initial speed)
    driven: bool = False  # the line is driven: it took up its impact and the drives' work

    def index_entry(self) -> dict:
        return dict(
            run_id=self.run_id, file=self.file, n=self.n, k=self.k, alpha=self.alpha,
            outcome=self.outcome, terminal=self.terminal, end_time=self.end_time,
            events=self.events, wall_time=self.wall_time, config_hash=self.config_hash,
        )


@dataclass(frozen=True)
class RunError:
    """A run that raised (or whose worker was lost for good): it has no file."""

    run_id: str
    message: str
    ok = False
    skipped = False


@dataclass(frozen=True)
class SweepProgress:
    """Counts of a sweep's runs, for a progress display.

    ``running`` counts runs handed to the executor and not finished, up to the
    number of runs it can compute at once; the rest of the unfinished runs wait.
    """

    total: int
    done: int = 0
    running: int = 0
    failed: int = 0
    skipped: int = 0
    current: str = ""  # e.g. "k=2 t = 12.5", for a run computed in this process

    @property
    def finished(self) -> int:
        return self.done + self.failed + self.skipped


@dataclass
class SweepResult:
    """What a sweep did.

    Attributes
    ----------
    runs : list of RunSummary or RunError
        Every run, in the experiment's run order.
    index : Path
        The index file written (it lists the runs that have a file).
    workers : str
        Where the runs were computed, e.g. "in this process" or "on the Dask
        scheduler at tcp://10.0.0.5:8786"; empty if nothing was computed.
    """

    runs: list[RunSummary | RunError]
    index: Path
    workers: str = ""

    @property
    def summaries(self) -> list[RunSummary]:
        """Runs with a file, computed now or skipped, in run order."""
        return [r for r in self.runs if isinstance(r, RunSummary)]

    @property
    def failures(self) -> list[RunSummary | RunError]:
        """Runs that raised or ended in a non-ok outcome (skipped ones included)."""
        return [r for r in self.runs if not r.ok]

    @property
    def computed(self) -> list[RunSummary | RunError]:
        """Runs tried now (failed ones included)."""
        return [r for r in self.runs if not r.skipped]

    @property
    def skipped(self) -> list[RunSummary]:
        """Runs read back from a file that matched (failed ones included)."""
        return [r for r in self.summaries if r.skipped]


ProgressHook = Callable[[str, float], None]


def observables(line, t: float, x: np.ndarray, v: np.ndarray) -> dict[str, float]:
    """The energies and momentum of ``line`` at one snapshot, as a run file keeps them
    (``chainrun.store.OBSERVABLES``): kinetic energy, the energy of its contacts and
    walls less the external forces' work, and momentum (``chainrun.solver.physics``).

    Parameters
    ----------
    line : chainrun.solver.Line
    t : float
    x, v : ndarray, shape (N,)
        Displacements and velocities at ``t``.
    """
    from chainrun.solver.physics import (line_kinetic_energy, line_momentum,
                                         line_potential_energy)

    return {"kinetic_energy": float(line_kinetic_energy(v, line.mass)),
            "potential_energy": float(line_potential_energy(x, line, t)),
            "momentum": float(line_momentum(v, line.mass))}


def recorder(writer, line):
    """The solver's ``on_snapshot`` hook that writes each snapshot of ``line`` and its
    ``observables`` with ``writer`` (a ``chainrun.store.RunWriter``)."""
    def on_snapshot(index: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
        writer.snapshot(index, t, x, v, observables(line, t, x, v))
    return on_snapshot


def write_run(path, spec: RunSpec, solution, *, velocity_floor: float) -> None:
    """Write a whole run file from a ``Solution`` that kept its snapshots.

    Parameters
    ----------
    path : str or path
    spec : RunSpec
    solution : chainrun.solver.Solution
        With ``positions`` and ``velocities`` of shape (T, N), or None when T = 0.
    velocity_floor : float
    """
    from chainrun.store import RunWriter

    times = np.asarray(solution.times, dtype=np.float64).reshape(-1)
    if len(times) and (solution.positions is None or solution.velocities is None):
        raise StoreError(f"{path}: the solution's snapshots were consumed by an observer; "
                         "write them with RunWriter.snapshot")
    with RunWriter(path, spec, velocity_floor=velocity_floor) as writer:
        record = recorder(writer, spec.line)
        for i, t in enumerate(times):
            record(i, float(t), solution.positions[i], solution.velocities[i])
        writer.finish(solution)


def simulate_run(spec: RunSpec, outdir, *, on_progress: ProgressHook | None = None,
                 check_outdir=None) -> RunSummary:
    """Run one spec and write its run file atomically; return its summary.

    This is the task a worker executes: it needs only the spec and a folder it can
    write to (the same path on every machine of a cluster).

    With ``spec.check``, a run that succeeds is run a second time at
    ``chainrun.check.check_rtol(spec.rtol)`` and its file stores the spread of each
    ball's velocities between the two (``chainrun.check``). With ``check_outdir``
    (which implies the check), the check run writes its own whole run file there
    (``spec.for_check()``: snapshots, events, sensors), so that any number derived
    from the runs can be computed from both.
    """
    from chainrun.limits import check_memory
    from chainrun.solver import load_kernels, simulate_line, velocity_floor
    from chainrun.store import RunWriter

    check_memory(spec.n, len(spec.times), damped=spec.damped, samples=spec.sensor_samples)
    line = spec.line  # built here, on the worker: as long as the line (ConfigError if wrong)
    # numba loads the kernels on their first call; the run's wall time is its solve's
    load_kernels()
    path = run_file(Path(outdir), spec)
    hook = None if on_progress is None else (lambda t: on_progress(spec.run_id, t))
    with RunWriter(path, spec, velocity_floor=velocity_floor(spec.rtol)) as writer:
        sol = simulate_line(
            line, spec.times, t_end=spec.t_end, rtol=spec.rtol,
            max_events=spec.max_events, on_snapshot=recorder(writer, line), on_progress=hook,
            sensors=spec.sensors, sensor_dt=spec.sensor_dt, sensor_end=spec.sensor_end,
        )
        check = None
        if (spec.check or check_outdir is not None) and sol.outcome.ok:
            check = _check(spec, line, sol, check_outdir, hook)
        writer.finish(sol, check)
    d = sol.diagnostics
    return RunSummary(
        run_id=spec.run_id, file=path.name, n=spec.n, k=spec.k, alpha=spec.alpha,
        outcome=sol.outcome.value, ok=sol.outcome.ok, terminal=sol.terminal,
        end_time=sol.end_time, events=d.events, steps=d.steps,
        momentum_error=d.momentum_error, energy_error=d.energy_error,
        wall_time=d.wall_time, config_hash=spec.config_hash, message=sol.message,
        final_velocity=sol.final_velocity,
        dissipated=_share(sol.dissipated_energy, line, sol.drive_energy), units=spec.units,
        check=check, speed=_speed(line), driven=line.is_driven,
    )


def _check(spec: RunSpec, line, sol, check_outdir, hook) -> Check:
    """Run ``spec``'s line again at its check's tolerance; the spreads against ``sol``.

    Snapshots and sensor samples do not change a run's steps (the solver evaluates
    them on its dense output), so a check run without them, as one with a
    ``check_outdir``, follows the trajectory it would with them.
    """
    from chainrun.solver import simulate_line, velocity_floor
    from chainrun.store import RunWriter

    checked = spec.for_check()
    args = dict(t_end=checked.t_end, rtol=checked.rtol, max_events=checked.max_events,
                on_progress=hook)
    if check_outdir is None:
        other = simulate_line(line, **args)
    else:
        Path(check_outdir).mkdir(parents=True, exist_ok=True)
        with RunWriter(run_file(Path(check_outdir), checked), checked,
                       velocity_floor=velocity_floor(checked.rtol)) as writer:
            other = simulate_line(line, checked.times, on_snapshot=recorder(writer, line),
                                  sensors=checked.sensors, sensor_dt=checked.sensor_dt,
                                  sensor_end=checked.sensor_end, **args)
            writer.finish(other)
    return Check.between(sol, other, checked.rtol)


def _speed(line) -> float:
    """The line's impact speed: its largest initial speed (1 for a line at rest)."""
    return float(np.max(np.abs(line.velocity), initial=0.0)) or 1.0


def _share(dissipated: float, line, work: float = 0.0) -> float:
    """``dissipated`` as a share of the energy the line took up: its impact energy,
    plus the drives' ``work`` on a driven line (0 without either, or if none)."""
    from chainrun.solver.physics import impact_energy

    taken = impact_energy(line) + work if dissipated else 0.0
    return dissipated / taken if taken > 0.0 else 0.0


def read_summary(path, spec: RunSpec) -> RunSummary:
    """The summary of an existing run file of ``spec`` (marked ``skipped``)."""
    from chainrun.solver import Outcome
    from chainrun.store import read_run

    run = read_run(path)
    d = run.diagnostics
    try:
        ok = Outcome(run.outcome).ok
    except ValueError:
        ok = False
    return RunSummary(
        run_id=spec.run_id, file=Path(path).name, n=run.n, k=run.k, alpha=run.alpha,
        outcome=run.outcome, ok=ok, terminal=run.terminal, end_time=run.end_time,
        events=int(d.get("events", len(run.event_time))), steps=int(d.get("steps", 0)),
        momentum_error=float(d.get("momentum_error", np.nan)),
        energy_error=float(d.get("energy_error", np.nan)),
        wall_time=float(d.get("wall_time", 0.0)), config_hash=spec.config_hash,
        message=run.message, final_velocity=run.final_velocity, skipped=True,
        dissipated=_share(run.dissipated_energy, run.line, run.drive_energy), units=run.units,
        check=run.check, speed=_speed(run.line), driven=run.line.is_driven,
    )


# ------------------------------------------------------------------ planning a sweep


@dataclass
class SweepPlan:
    """Which runs of a sweep to compute and which are already done.

    Attributes
    ----------
    todo : list of RunSpec
        Runs to compute: no file yet, or (with ``force``) a file of another config.
    done : dict of run_id to RunSummary
        Runs whose file holds their config hash, read back (``skipped``).
    conflicts : list of Path
        Files under a run's name that hold another config hash or are not readable
        chainrun run files; replaced only with ``force``.
    """

    todo: list[RunSpec] = field(default_factory=list)
    done: dict[str, RunSummary] = field(default_factory=dict)
    conflicts: list[Path] = field(default_factory=list)


def sweep_specs(experiment: Experiment, *, check: bool = False,
                check_outdir=None) -> list[RunSpec]:
    """The runs of ``experiment``, each checked if ``check`` or ``check_outdir`` asks
    (``RunSpec.check``; ``solver.check`` in the file asks for it too)."""
    specs = experiment.runs()
    if check or check_outdir is not None:
        specs = [replace(spec, check=True) for spec in specs]
    return specs


def plan_sweep(experiment: Experiment, outdir, *, check: bool = False,
               check_outdir=None) -> SweepPlan:
    """Compare the runs of ``experiment`` with the run files in ``outdir``.

    A file of the run's config is done unless the run asks for a check the file does
    not hold, or ``check_outdir`` lacks the check run's own file: such a run is
    computed again (both runs), not reported as a conflict.
    """
    from chainrun.store import run_config_hash

    outdir = Path(outdir)
    plan = SweepPlan()
    for spec in sweep_specs(experiment, check=check, check_outdir=check_outdir):
        path = run_file(outdir, spec)
        if not path.exists():
            plan.todo.append(spec)
            continue
        if run_config_hash(path) == spec.config_hash:
            try:
                summary = read_summary(path, spec)
            except StoreError:  # our hash but damaged elsewhere: the same run, recompute
                summary = None
            if summary is not None and _has_check(summary, spec, check_outdir):
                plan.done[spec.run_id] = summary
                continue
        else:
            plan.conflicts.append(path)
        plan.todo.append(spec)
    return plan


def _has_check(summary: RunSummary, spec: RunSpec, check_outdir) -> bool:
    """Whether an existing run file holds the check its spec asks for (a failed run
    has none to hold)."""
    from chainrun.store import run_config_hash

    if not spec.check or not summary.ok:
        return True
    if summary.check is None:
        return False
    if check_outdir is None:
        return True
    checked = spec.for_check()
    return run_config_hash(run_file(Path(check_outdir), checked)) == checked.config_hash


def partial_files(outdir, specs: list[RunSpec]) -> list[Path]:
    """Temporary files (``.<run_id>.h5.partial-*``) of these runs left in ``outdir``.

    They are what a writer killed before its rename leaves behind. They are never
    read, so they are harmless; a completed sweep removes them.
    """
    outdir = Path(outdir)
    return atomic.leftovers(outdir, [run_file(outdir, s).name for s in specs])


# ------------------------------------------------------------------------- executors


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


# --------------------------------------------------------------------------- a sweep


def simulate_experiment(
    experiment: Experiment,
    outdir,
    *,
    force: bool = False,
    check: bool = False,
    check_outdir=None,
    jobs: int | None = None,
    scheduler: str | None = None,
    scheduler_file=None,
    executor: cf.Executor | None = None,
    on_progress: ProgressHook | None = None,
    on_run_done: Callable[[RunSummary | RunError], None] | None = None,
    on_update: Callable[[SweepProgress], None] | None = None,
    on_warning: Callable[[str], None] | None = None,
) -> SweepResult:
    """Run every point of an experiment into ``outdir`` and write its index.

    Runs whose file already holds their config hash are skipped (read, not
    computed). A run that raises or ends in a non-ok outcome does not stop the
    others; see ``SweepResult.failures``. Stale temporary files of the sweep's runs
    are removed once every run has finished.

    Parameters
    ----------
    experiment : Experiment
    outdir : path-like
        Created if missing; on a cluster, a folder every worker sees at this path.
    force : bool
        Replace run files that hold another config (or are not chainrun run files);
        without it such files are an error and nothing is run. Files that match are
        skipped either way.
    check : bool
        Check every run (as ``solver.check = true`` does): run it a second time at
        ``chainrun.check.check_rtol(rtol)`` and store each ball's spreads. A file of
        the run's config without them is computed again.
    check_outdir : path-like, optional
        Check every run, and write each check run's own file into this folder, with
        its index (``chainrun analyze --check`` reads them).
    jobs, scheduler, scheduler_file
        Where to compute; see ``open_executor``.
    executor : concurrent.futures.Executor, optional
        Use this executor instead (not shut down here).
    on_progress : callable(run_id, t), optional
        Simulated time of a run computed in this process.
    on_run_done : callable(RunSummary or RunError), optional
        Called for each run as it is skipped, finishes or fails.
    on_update : callable(SweepProgress), optional
        Called when the counts change, and about every 0.25 s while runs compute.
    on_warning : callable(str), optional
        One line per warning (e.g. the run files may not fit on the disk).

    Returns
    -------
    SweepResult

    Raises
    ------
    ChainrunError
        Conflicting files without ``force``, an output folder that cannot be
        written, runs that would not fit in this machine's memory, or an executor
        that cannot be started.
    """
    from chainrun.limits import check_runs
    from chainrun.store import write_index

    check_placement(jobs=jobs, scheduler=scheduler, scheduler_file=scheduler_file)
    shown = Path(outdir)
    outdir = shown.absolute()  # the same folder for workers in other working folders
    if check_outdir is not None:
        check_outdir = Path(check_outdir).absolute()
    specs = sweep_specs(experiment, check=check, check_outdir=check_outdir)
    plan = plan_sweep(experiment, outdir, check=check, check_outdir=check_outdir)
    if plan.conflicts and not force:
        names = ", ".join(p.name for p in plan.conflicts[:4])
        more = f" and {len(plan.conflicts) - 4} more" if len(plan.conflicts) > 4 else ""
        raise ChainrunError(
            f"{shown} holds run files of another config or of no chainrun run "
            f"({names}{more}); use --force to replace them"
        )
    warnings = []
    if scheduler is None and scheduler_file is None and executor is None:
        # refused before anything is made; on a cluster each worker checks its own
        # memory (simulate_run)
        warnings = check_runs(plan.todo, outdir, runs_at_once=jobs or 1)
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ChainrunError(f"cannot create output folder {shown}: {exc.strerror}") from None
    if not os.access(outdir, os.W_OK):
        raise ChainrunError(f"output folder {shown} is not writable")
    for warning in warnings:
        if on_warning is not None:
            on_warning(warning)

    results: dict[str, RunSummary | RunError] = {}
    counts = SweepProgress(total=len(specs))

    def report(run: RunSummary | RunError) -> None:
        nonlocal counts
        results[run.run_id] = run
        key = "failed" if not run.ok else "skipped" if run.skipped else "done"
        counts = replace(counts, **{key: getattr(counts, key) + 1})
        if on_run_done is not None:
            on_run_done(run)

    def update(**changes) -> None:
        nonlocal counts
        counts = replace(counts, **changes)
        if on_update is not None:
            on_update(counts)

    for spec in specs:
        if spec.run_id in plan.done:
            report(plan.done[spec.run_id])
    update()

    own = executor is None and bool(plan.todo)
    if own:
        executor = open_executor(jobs=jobs, scheduler=scheduler,
                                 scheduler_file=scheduler_file, runs=len(plan.todo))
    workers = getattr(executor, "workers", type(executor).__name__) if plan.todo else ""
    try:
        if plan.todo:
            _execute(executor, plan.todo, outdir, report, update, on_progress,
                     check_outdir)
    except BaseException:
        if own:
            executor.shutdown(wait=False, cancel_futures=True)
        raise
    if own:
        executor.shutdown()

    checked = [s.for_check() for s in specs]
    leftovers = partial_files(outdir, specs)
    if check_outdir is not None:
        leftovers += partial_files(check_outdir, checked)
    for path in leftovers:
        try:
            path.unlink()
        except OSError:
            pass
    runs = [results[s.run_id] for s in specs]
    index = index_file(outdir)
    entries = [r.index_entry() for r in runs if isinstance(r, RunSummary)]
    write_index(index, experiment.name, entries)
    if check_outdir is not None:
        _write_check_index(check_outdir, experiment.name, checked)
    return SweepResult(runs=runs, index=index, workers=workers)


def _write_check_index(check_outdir: Path, name: str, checked: list[RunSpec]) -> None:
    """The index of the check runs' own files (those written: a run that failed has
    no check run)."""
    from chainrun.store import run_config_hash, write_index

    entries = []
    for spec in checked:
        path = run_file(check_outdir, spec)
        if run_config_hash(path) == spec.config_hash:
            try:
                entries.append(read_summary(path, spec).index_entry())
            except StoreError:
                continue
    if entries or check_outdir.is_dir():
        write_index(index_file(check_outdir), name, entries)


def _execute(executor: cf.Executor, todo: list[RunSpec], outdir: Path, report, update,
             on_progress: ProgressHook | None, check_outdir: Path | None = None) -> None:
    """Submit every run, then report each as it finishes, in completion order."""
    inline = isinstance(executor, InlineExecutor)
    finished: queue.SimpleQueue = queue.SimpleQueue()
    pending: dict[cf.Future, RunSpec] = {}
    outstanding = 0

    def running() -> int:
        return min(outstanding, getattr(executor, "slots", outstanding) or outstanding)

    def collect(future: cf.Future) -> None:
        nonlocal outstanding
        spec = pending.pop(future)
        outstanding -= 1
        try:
            report(future.result())
        except cf.CancelledError:
            report(RunError(spec.run_id, "cancelled"))
        except Exception as exc:  # the run's own error, or a worker lost for good
            report(RunError(spec.run_id, _describe(exc)))
        update(running=running(), current="")

    def drain(timeout: float | None) -> None:
        try:
            future = finished.get(timeout=timeout) if timeout else finished.get_nowait()
        except queue.Empty:
            return
        collect(future)
        while True:
            try:
                collect(finished.get_nowait())
            except queue.Empty:
                return

    for spec in todo:
        outstanding += 1
        if inline:
            update(running=1, current=spec.run_id)
            future = executor.submit(simulate_run, spec, outdir, on_progress=on_progress,
                                     check_outdir=check_outdir)
        else:
            future = executor.submit(simulate_run, spec, outdir, check_outdir=check_outdir)
        pending[future] = spec
        future.add_done_callback(finished.put)
        drain(None)
    update(running=running())
    while pending:
        drain(0.25)
        update(running=running())


def _describe(exc: BaseException) -> str:
    """One line for an exception raised by a run, or by Dask on its behalf."""
    name = type(exc).__name__
    text = " ".join(str(exc).split())
    if name == "KilledWorker":
        return f"its worker died repeatedly while computing it ({text})"
    if isinstance(exc, ChainrunError):
        return text
    return f"{name}: {text}" if text else name
