"""Runs experiments: each RunSpec through the solver into its run file, then the index.

This package owns how a sweep is executed, into an experiment's output folder
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
import os
import queue
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable

from chainrun import atomic
from chainrun.config import Experiment, RunSpec
from chainrun.errors import ChainrunError, StoreError
from chainrun.paths import INDEX_NAME, index_file, run_file
from chainrun.runner.executors import (SCHEDULER_ENV, DaskExecutor, InlineExecutor,
                                       check_placement, open_executor)
from chainrun.runner.results import RunError, RunSummary, SweepProgress, SweepResult
from chainrun.runner.run import (ProgressHook, observables, read_summary, recorder,
                                 simulate_run, write_run)

__all__ = ["INDEX_NAME", "SCHEDULER_ENV", "DaskExecutor", "InlineExecutor", "RunError",
           "RunSummary", "SweepProgress", "SweepResult", "check_placement", "observables",
           "open_executor", "plan_sweep", "read_summary", "recorder", "run_file",
           "simulate_experiment", "simulate_run", "sweep_specs", "write_run"]


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
    conflicting: list[RunSpec] = field(default_factory=list)  # the runs of conflicts


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
            plan.conflicting.append(spec)
        plan.todo.append(spec)
    return plan


def _flat(table, prefix: str = "") -> dict:
    """A nested config table as {dotted key: value}."""
    out = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, dict):
            out |= _flat(value, name + ".")
        else:
            out[name] = value
    return out


def _difference(path: Path, spec: RunSpec, most: int = 3) -> str:
    """``: chain.speed is 0.3 in run.h5, 0.31 here``: the keys of the run's config
    that differ from those its file was made with; "" where the file has none to read
    (not a chainrun run file)."""
    import json

    from chainrun.store import _h5, read_run

    try:
        stored = read_run(path).parameters.get("config_resolved", {})
    except (StoreError, OSError):
        return ""
    old, new = _flat(stored), _flat(json.loads(_h5.to_json(spec.config)))
    keys = [k for k in sorted(old.keys() | new.keys()) if old.get(k) != new.get(k)]
    if not keys:
        return ""

    def value(table, key):
        return json.dumps(table[key]) if key in table else "not set"

    said = [f"{k} is {value(old, k)} in {path.name}, {value(new, k)} here"
            for k in keys[:most]]
    return ": " + "; ".join(said) + (f" (and {len(keys) - most} more)"
                                     if len(keys) > most else "")


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
    on_progress : callable(label, t), optional
        Simulated time of a run computed in this process; the label is its run_id,
        with " (check)" after it while its check runs (``ProgressHook``).
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
    from chainrun.config.doubts import doubts
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
            f"({names}{more}{_difference(plan.conflicts[0], plan.conflicting[0])}); "
            "use --force to replace them"
        )
    warnings = doubts(plan.todo)
    figures = outdir / "figures"
    if plan.conflicts and figures.is_dir():
        warnings.append(f"{shown / 'figures'} holds the figures of the runs replaced now; "
                        f"`chainrun plot {shown}` draws them again")
    if scheduler is None and scheduler_file is None and executor is None:
        # refused before anything is made; on a cluster each worker checks its own
        # memory (simulate_run)
        warnings += check_runs(plan.todo, outdir, runs_at_once=jobs or 1)
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
            _remove_partials_of(getattr(executor, "killed", ()), outdir, specs,
                                check_outdir)
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


def _remove_partials_of(pids, outdir: Path, specs: list[RunSpec],
                        check_outdir: Path | None) -> None:
    """Remove the half-written run files of the worker processes ``pids``, killed by
    an interrupted sweep (a run computed in this process removes its own)."""
    if not pids:
        return
    ends = tuple(f".partial-{pid}" for pid in pids)
    leftovers = partial_files(outdir, specs)
    if check_outdir is not None:
        leftovers += partial_files(check_outdir, [s.for_check() for s in specs])
    for path in leftovers:
        if path.name.endswith(ends):
            try:
                path.unlink()
            except OSError:
                pass


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
