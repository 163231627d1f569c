"""One run: its line through the solver into its run file, with its snapshots'
energies and momentum (``observables``) and, if asked, its check.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from chainrun import interrupt
from chainrun.check import Check
from chainrun.config import RunSpec
from chainrun.errors import StoreError
from chainrun.paths import run_file
from chainrun.runner.results import RunSummary
from chainrun.units import run_message

#: ``on_progress(label, t)``: the simulated time t of a run computed in this process;
#: the label is the run's id, and while its check runs (``solver.check``), the id
#: followed by " (check)", whose time starts again from 0
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
        interrupt.check()  # (one the writing's callbacks swallowed stops the run here)
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
    from chainrun.solver import load_kernels, simulate, velocity_floor
    from chainrun.store import RunWriter

    check_memory(spec.n, len(spec.times), damped=spec.damped, samples=spec.sensor_samples)
    line = spec.line  # the line the file was checked with, or built now (ConfigError if wrong)
    # numba loads the kernels on their first call; the run's wall time is its solve's
    load_kernels()
    path = run_file(Path(outdir), spec)

    label = spec.run_id

    def hook(t: float) -> None:
        interrupt.check()
        if on_progress is not None:
            on_progress(label, t)
    with RunWriter(path, spec, velocity_floor=velocity_floor(spec.rtol)) as writer:
        sol = simulate(
            line, spec.times, t_end=spec.t_end, rtol=spec.rtol,
            max_events=spec.max_events, on_snapshot=recorder(writer, line), on_progress=hook,
            sensors=spec.sensors, sensor_dt=spec.sensor_dt, sensor_end=spec.sensor_end,
        )
        check = None
        if (spec.check or check_outdir is not None) and sol.outcome.ok:
            label = f"{spec.run_id} (check)"
            check = _check(spec, line, sol, check_outdir, hook)
        writer.finish(sol, check)
    d = sol.diagnostics
    return RunSummary(
        run_id=spec.run_id, file=path.name, n=spec.n, k=spec.k, alpha=spec.alpha,
        outcome=sol.outcome.value, ok=sol.outcome.ok, terminal=sol.terminal,
        end_time=sol.end_time, events=d.events, steps=d.steps,
        momentum_error=d.momentum_error, energy_error=d.energy_error,
        wall_time=d.wall_time, config_hash=spec.config_hash, message=run_message(sol, spec.units),
        final_velocity=sol.final_velocity,
        dissipated=_share(sol.dissipated_energy, line, sol.drive_energy, sol.end_time),
        units=spec.units,
        check=check, **_speed(line), driven=line.is_driven,
        energy_floor=d.energy_floor, momentum_scale=_momentum_scale(line),
    )


def _check(spec: RunSpec, line, sol, check_outdir, hook) -> Check:
    """Run ``spec``'s line again at its check's tolerance; the spreads against ``sol``.

    Snapshots and sensor samples do not change a run's steps (the solver evaluates
    them on its dense output), so a check run without them, as one with a
    ``check_outdir``, follows the trajectory it would with them.
    """
    from chainrun.solver import simulate, velocity_floor
    from chainrun.store import RunWriter

    checked = spec.for_check()
    args = dict(t_end=checked.t_end, rtol=checked.rtol, max_events=checked.max_events,
                on_progress=hook)
    if check_outdir is None:
        other = simulate(line, **args)
    else:
        Path(check_outdir).mkdir(parents=True, exist_ok=True)
        with RunWriter(run_file(Path(check_outdir), checked), checked,
                       velocity_floor=velocity_floor(checked.rtol)) as writer:
            other = simulate(line, checked.times, on_snapshot=recorder(writer, line),
                             sensors=checked.sensors, sensor_dt=checked.sensor_dt,
                             sensor_end=checked.sensor_end, **args)
            writer.finish(other)
    return Check.between(sol, other, checked.rtol, spec.units)


def _speed(line) -> dict:
    """The speed the line's spreads are measured against, and its name
    (``chainrun.check.reference_speed``), as RunSummary's fields."""
    from chainrun.check import reference_speed

    speed, name = reference_speed(line)
    return {"speed": speed, "speed_name": name}


def _momentum_scale(line) -> float:
    """The momentum of the line's scales, M V: the unit of its momentum error."""
    scales = line.scales()
    return scales.mass * scales.velocity


def _share(dissipated: float, line, work: float = 0.0, end_time: float = 0.0) -> float:
    """``dissipated`` as a share of the energy the line took up by ``end_time``: its
    impact energy, plus on a driven line the drives' ``work`` beyond the static load's
    (``physics.static_load_work``); 0 without either, or if none."""
    from chainrun.solver.physics import impact_energy, static_load_work

    if work:
        work = work - float(static_load_work(line, end_time))
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
        dissipated=_share(run.dissipated_energy, run.line, run.drive_energy, run.end_time),
        units=run.units,
        check=run.check, **_speed(run.line), driven=run.line.is_driven,
        energy_floor=float(d.get("energy_floor", 0.0)), momentum_scale=_momentum_scale(run.line),
    )
