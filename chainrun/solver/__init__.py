"""The event-driven solver: its one entry point, ``simulate``, and its public types.

This package owns the dynamics and nothing else: it turns a line of balls (``Line``:
masses, contacts, walls, forces; the paper's N, K, alpha is ``Line.paper``), output
times and an accuracy into arrays, and never touches files. ``simulate`` is its one
entry point. ``model`` defines the line and the scales it is solved in, ``build`` makes
one from plain values, ``physics`` holds the force law and the conserved quantities,
``result`` the ``Solution`` and its vocabulary; ``_driver`` converts the line to its
scales, runs the numba kernels (``_loop.advance`` and the modules it imports) between
output times, maps their status codes to named outcomes and hands snapshots to a hook.
The modules' layers, each importing only those below it, are in docs/design.md ("The
solver's layers"); tests/unit/test_layout.py holds the code to them.

Equations, for balls n = 1..N (``model``; in the paper's units every coefficient is 1
and there is no gap, wall or force)::

    m_n x_n'' = F_{n-1} - F_n + f_n,   F_j = kappa_j (x_j - x_{j+1} - g_j)_+^alpha_j

Contact j joins balls j and j+1 (0-based here: contact j joins balls j and j+1 of the
arrays); a wall is a contact with a ball of infinite mass at rest. A damped contact
(``Line.damping`` eta_j > 0, exponent beta_j) carries, while compressed (d_j > 0),

    F_j = max(0, kappa_j d_j^alpha_j + eta_j d_j^beta_j d_j')

held at 0 from where it would pull (``EventKind.UNLOAD``: the collision ends there,
before the compression is gone) until it pushes again (``RELOAD``) or the compression
goes (``OPEN``). Energy is then ``kinetic + contact + dissipated``, the dissipated
energy (``Solution.dissipated``) integrated along the run: the damping's power
eta d^beta d'^2 by each step's quadrature, and the elastic energy a contact held at 0
still stores as it goes, exactly.

A driven line (a wall whose displacement follows ``Wall.motion``, forces prescribed in
time on chosen balls, ``Line.drives``; ``chainrun.solver.drive``) adds its drives to
the accelerations, exactly in time, and ends every step at the drives' breakpoints as
at contact events (``_drive``); its energy is ``kinetic + contact + dissipated =
initial + drive work`` (``Solution.drive_work``), the drives' work integrated along
the run as the dissipation is.
"""

from __future__ import annotations

from chainrun.solver.drive import Drive, Sine
from chainrun.solver.model import Line, Scales, Wall
from chainrun.solver.result import (
    DEFAULT_RTOL, FLOOR_MIN, Diagnostics, EventKind, Outcome, ProgressHook, SnapshotHook,
    Solution, velocity_floor,
)

__all__ = [
    "DEFAULT_RTOL",
    "Diagnostics",
    "Drive",
    "Sine",
    "EventKind",
    "Outcome",
    "Solution",
    "Line",
    "Scales",
    "Wall",
    "load_kernels",
    "simulate",
    "velocity_floor",
]

def simulate(
    line: Line,
    times=(),
    *,
    t_end: float | None = None,
    rtol: float = DEFAULT_RTOL,
    max_events: int | None = None,
    on_snapshot: SnapshotHook | None = None,
    on_progress: ProgressHook | None = None,
    sensors=(),
    sensor_dt: float | None = None,
    sensor_end: float | None = None,
    closed_form: bool = True,
) -> Solution:
    """Run a line of balls to its terminal state (or to ``t_end``).

    Inputs and results are in the line's own units; the run itself is in the units of
    its scales (``Line.scales``). A line whose forces keep doing work, that is driven,
    or that is held between two walls has no terminal state
    (``Line.has_terminal_state``): it needs ``t_end``.

    Parameters
    ----------
    line : Line
        Masses, contacts, walls, forces, drives and the initial state; the paper's line
        of N unit balls, K of them striking at velocity 1, is ``Line.paper(n, k, alpha)``.
    times : array_like, shape (T,)
        Non-decreasing, non-negative snapshot times. Snapshots are the exact state
        at those times (interpolated within a step, analytic in free flight).
    t_end : float, optional
        Stop time; by default run to the terminal state.
    rtol : float
        Relative accuracy of a step; also sets ``velocity_floor``.
    max_events : int, optional
        Stop with ``Outcome.EVENT_LIMIT`` after this many contact events.
    on_snapshot : callable(index, t, x, v), optional
        Receives each snapshot as it is taken (x, v of shape (N,), only valid during
        the call); when given, ``Solution.positions`` and ``velocities`` are None.
    on_progress : callable(t), optional
        Called between output times and periodically during long stretches.
    sensors : sequence of int, optional
        Balls (numbered from 1) whose contact forces are sampled every ``sensor_dt``
        from t = 0 to ``sensor_end`` or the end of the run, the earlier
        (``Solution.sensor_force``), exactly, from the step containing each sample;
        the cost grows with the samples, not with N.
    sensor_dt : float, optional
        The sampling interval, > 0; required with ``sensors``.
    sensor_end : float, optional
        The last time a sample may be taken (> 0); by default the end of the run.
    closed_form : bool
        Take an isolated binary collision (two free balls, or a ball and a wall, that
        no third body can reach while they touch) whole: its outcome and duration are
        exact (a damped one's from the pair's relative motion alone, integrated to
        1e-13), its interior is evaluated for snapshots and sensors, and it costs no
        steps of the other clusters. Only on a line without external forces. False
        integrates every collision (to compare the two).

    Returns
    -------
    Solution
    """
    from chainrun.solver._driver import run

    return run(
        line, times, t_end=t_end, rtol=rtol, max_events=max_events,
        on_snapshot=on_snapshot, on_progress=on_progress, sensors=sensors,
        sensor_dt=sensor_dt, sensor_end=sensor_end, closed_form=closed_form,
    )


def load_kernels() -> None:
    """Load the numba kernels now, from the cache or by compiling them.

    numba loads a kernel (or compiles it) on its first call, and the run making that
    call would count it in its ``Diagnostics.wall_time``: tenths of a second from a
    warm cache, tens of seconds without one, for a run that may itself take
    microseconds. Whoever reports a run's time calls this first
    (``chainrun.runner.simulate_run`` does), so that the time is the solve's alone; a
    first run on a machine says on stderr that it is compiling (see ``_jit``).
    """
    from chainrun._gc import start_up
    from chainrun.solver import _driver

    with start_up("kernels"):  # numba's registries and code: long-lived, no garbage
        _driver.load_kernels()
