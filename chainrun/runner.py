"""Runs experiments: each RunSpec through the solver into its run file, then the index.

This module owns the layout of an experiment's output folder::

    OUTDIR/<run_id>.h5     one run file per point of the sweep (``run.h5`` without one)
    OUTDIR/index.h5        parameters and summary of every run, with external links

It reports through plain callbacks and never imports click.
"""

from __future__ import annotations

import os
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from chainrun.config import Experiment, RunSpec
from chainrun.errors import ChainrunError

INDEX_NAME = "index.h5"


@dataclass(frozen=True)
class RunSummary:
    """What a person (and the index file) needs to know about one finished run."""

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

    def line(self) -> str:
        """One line: how the run ended, its cost and its conservation errors."""
        how = f"terminal at t = {self.end_time:.6g}" if self.terminal else self.message
        return (f"{self.run_id}: {how}, {self.events} events, {self.steps} steps, "
                f"|dP| = {self.momentum_error:.1e}, |dE|/E = {self.energy_error:.1e}, "
                f"{self.wall_time:.2f} s")

    def index_entry(self) -> dict:
        return dict(
            run_id=self.run_id, file=self.file, n=self.n, k=self.k, alpha=self.alpha,
            outcome=self.outcome, terminal=self.terminal, end_time=self.end_time,
            events=self.events, wall_time=self.wall_time, config_hash=self.config_hash,
        )


ProgressHook = Callable[[str, float], None]


def run_file(outdir: Path, spec: RunSpec) -> Path:
    return Path(outdir) / f"{spec.run_id}.h5"


def simulate_run(spec: RunSpec, outdir, *, on_progress: ProgressHook | None = None) -> RunSummary:
    """Run one spec and write its run file atomically; return its summary."""
    from chainrun.solver import simulate, velocity_floor
    from chainrun.store import RunWriter

    path = run_file(Path(outdir), spec)
    hook = None if on_progress is None else (lambda t: on_progress(spec.run_id, t))
    with RunWriter(path, spec, velocity_floor=velocity_floor(spec.rtol)) as writer:
        sol = simulate(
            spec.n, spec.k, spec.alpha, spec.times, t_end=spec.t_end, rtol=spec.rtol,
            max_events=spec.max_events, on_snapshot=writer.snapshot, on_progress=hook,
        )
        writer.finish(sol)
    d = sol.diagnostics
    return RunSummary(
        run_id=spec.run_id, file=path.name, n=spec.n, k=spec.k, alpha=spec.alpha,
        outcome=sol.outcome.value, ok=sol.outcome.ok, terminal=sol.terminal,
        end_time=sol.end_time, events=d.events, steps=d.steps,
        momentum_error=d.momentum_error, energy_error=d.energy_error,
        wall_time=d.wall_time, config_hash=spec.config_hash, message=sol.message,
        final_velocity=sol.final_velocity,
    )


def existing_results(experiment: Experiment, outdir) -> list[Path]:
    """Files of this experiment already present under ``outdir``."""
    outdir = Path(outdir)
    paths = [run_file(outdir, s) for s in experiment.runs()] + [outdir / INDEX_NAME]
    return [p for p in paths if p.exists()]


def simulate_experiment(
    experiment: Experiment,
    outdir,
    *,
    force: bool = False,
    jobs: int = 1,
    on_progress: ProgressHook | None = None,
    on_run_done: Callable[[RunSummary], None] | None = None,
) -> list[RunSummary]:
    """Run every point of an experiment into ``outdir`` and write its index.

    Parameters
    ----------
    experiment : Experiment
    outdir : path-like
        Created if missing.
    force : bool
        Replace results already in ``outdir``; without it, existing results are an
        error and nothing is run.
    jobs : int
        Runs computed at once, in separate processes (1: in this process).
    on_progress : callable(run_id, t), optional
        Simulated time of a running run (only with jobs = 1).
    on_run_done : callable(RunSummary), optional
        Called as each run finishes, in completion order.

    Returns
    -------
    list of RunSummary, in the experiment's run order.
    """
    from chainrun.store import write_index

    outdir = Path(outdir)
    specs = experiment.runs()
    present = existing_results(experiment, outdir)
    if present and not force:
        names = ", ".join(p.name for p in present[:4]) + (" ..." if len(present) > 4 else "")
        raise ChainrunError(
            f"{outdir} already holds results of this experiment ({names}); "
            "use --force to replace them"
        )
    try:
        outdir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ChainrunError(f"cannot create output folder {outdir}: {exc.strerror}") from None
    if not os.access(outdir, os.W_OK):
        raise ChainrunError(f"output folder {outdir} is not writable")

    done: dict[str, RunSummary] = {}

    def finished(summary: RunSummary):
        done[summary.run_id] = summary
        if on_run_done is not None:
            on_run_done(summary)

    if jobs <= 1 or len(specs) == 1:
        for spec in specs:
            finished(simulate_run(spec, outdir, on_progress=on_progress))
    else:
        with ProcessPoolExecutor(max_workers=min(jobs, len(specs))) as pool:
            pending = {pool.submit(simulate_run, spec, outdir) for spec in specs}
            while pending:
                complete, pending = wait(pending, return_when=FIRST_COMPLETED)
                for fut in complete:
                    finished(fut.result())
    summaries = [done[s.run_id] for s in specs]
    write_index(outdir / INDEX_NAME, experiment.name, [s.index_entry() for s in summaries])
    return summaries


def velocity_table(summaries: list[RunSummary], max_balls: int = 20) -> str | None:
    """Final velocities as a text table (balls down, runs across), for short lines."""
    if not summaries or any(s.n != summaries[0].n for s in summaries):
        return None
    n = summaries[0].n
    if n > max_balls:
        return None
    head = ["n"] + [s.run_id for s in summaries]
    rows = [[str(i + 1)] + [f"{s.final_velocity[i]:.4f}" for s in summaries] for i in range(n)]
    widths = [max(len(r[c]) for r in [head] + rows) for c in range(len(head))]
    fmt = lambda r: "  ".join(v.rjust(w) for v, w in zip(r, widths))
    return "\n".join([fmt(head)] + [fmt(r) for r in rows])
