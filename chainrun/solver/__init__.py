"""The event-driven solver: the public types and the ``simulate`` drivers.

This package owns the dynamics and nothing else: it turns a line of balls (``Line``:
masses, contacts, walls, forces; the paper's N, K, alpha is ``Line.paper``), output
times and an accuracy into arrays, and never touches files. ``model`` defines the line and the
scales it is solved in; ``physics`` the force law and the conserved quantities for
the store and the analysis; ``_driver`` converts the line to those scales, runs the
numba kernels between output times, maps their integer status codes to named
outcomes, and hands snapshots to an observer hook. The kernels, each module importing
only those above it::

    _jit          how kernels are compiled, cached and loaded
    _state        the State arrays, their scalar slots and parameter rows, status
                  codes, shared constants, free flight
    _forces       the force law: contact forces, accelerations, contact energy
    _drive        the drives (moving walls, forces in time): series, stages, work
    _generated    DOP853 stages and Taylor-series sums as straight-line code, written
                  whole by ``_codegen`` (``python -m chainrun.solver._codegen``)
    _steppers     one step (Taylor series or DOP853), positions inside the last step
    _compression  one contact's compression over a step: its series, samples, bounds
    _heap         predicted collisions of free balls
    _projection   each cluster's internal energy, restored at changes of structure
    _clusters     which balls move together, packed into the compact arrays
    _events       locating the first contact event in a step
    _loop         the step loop: ``advance``, the one entry point

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

import enum
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from chainrun.solver.drive import Drive, Sine
from chainrun.solver.model import Line, Scales, Wall

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

#: Default relative accuracy of a step (velocities are of order 1 in paper units).
DEFAULT_RTOL = 1e-12


class EventKind(enum.IntEnum):
    """What happened to a contact at a logged event.

    Every contact starts closed (the balls touch). ``OPEN`` and ``CLOSE`` are located
    zero crossings of the compression; ``RELEASE`` and ``ENGAGE`` are the noise-floor
    rules (see ``velocity_floor``): a contact whose compression, rate and load are all
    below the floor is released, and a released contact re-engages when pressed beyond
    the floor's compression. ``UNLOAD`` and ``RELOAD`` are a damped contact's: its force
    reaches 0 while it is still compressed (the collision ends there, and the force is
    held at 0 until the compression is gone) or rises from 0 again before (a third ball
    pushes).
    """

    UNLOAD = -3
    RELEASE = -2
    OPEN = -1
    CLOSE = 1
    ENGAGE = 2
    RELOAD = 3


class Outcome(enum.Enum):
    """How a run ended. Only ``TERMINAL`` and ``STOP_TIME`` are successes."""

    TERMINAL = "terminal"
    STOP_TIME = "stop_time"
    EVENT_LIMIT = "event_limit"
    NON_FINITE = "non_finite"
    STEP_UNDERFLOW = "step_underflow"

    @property
    def ok(self) -> bool:
        return self in (Outcome.TERMINAL, Outcome.STOP_TIME)


@dataclass(frozen=True)
class Diagnostics:
    """Cost and accuracy of one run.

    momentum_error is relative to the momentum of the line's scales (absolute on the
    paper's line, whose initial momentum is K), with the external forces', the drives'
    and the walls' impulses accounted, and energy_error to its initial kinetic energy
    (K/2 on the paper's line), with the external forces' work, the drives' and the
    damping's dissipation accounted (``_driver._diagnostics``). Each cluster's internal energy is projected
    back to its conserved value at every change of structure (see
    ``_projection._project_energy``); energy_correction is the sum of those corrections,
    relative like energy_error, the honest measure of the integration error that the
    projection removes. closed_form_collisions counts the isolated binary collisions
    taken whole (in closed form, or a damped pair's own relative motion) rather than
    integrated with the clusters (``_pairs``).
    """

    steps: int
    rejected_steps: int
    events: int
    momentum_error: float
    energy_error: float
    energy_correction: float
    wall_time: float
    max_window: int
    rtol: float
    velocity_floor: float
    closed_form_collisions: int = 0


@dataclass(frozen=True)
class Solution:
    """The result of one run.

    Attributes
    ----------
    n, k : int
    alpha : float
    outcome : Outcome
    message : str
        One line for a person, naming the time and place of any failure.
    end_time : float
        The terminal time (the last event before which no collision can happen
        again), or the stop time when stopped by ``t_end``.
    terminal : bool
        Whether the terminal state was reached.
    final_position, final_velocity : ndarray, shape (N,)
        State at ``end_time``.
    separation_time, separation_velocity : ndarray, shape (N,)
        Time and velocity at which each ball last lost its last contact; NaN for a
        ball that never did (it never moved, or never left a compressed cluster).
    event_time : ndarray, shape (E,)
    event_contact : ndarray of int64, shape (E,)
        Contact j joins balls j and j+1 (0-based).
    event_kind : ndarray of int8, shape (E,)
        ``EventKind`` values.
    times : ndarray, shape (T,)
        The snapshot times.
    positions, velocities : ndarray, shape (T, N), or None
        Snapshots, when no ``on_snapshot`` observer consumed them.
    diagnostics : Diagnostics
    sensor_balls : ndarray of int64, shape (S,)
        The sensor balls, numbered from 1 (empty without sensors).
    sensor_time : ndarray, shape (M,)
        The sample times: 0, dt, 2 dt, ... up to ``end_time`` (or ``sensor_end``).
    sensor_force : ndarray, shape (M, S, 2)
        The contact forces on each sensor ball at each sample, on its side towards
        ball 1 and on its far side (0 at the line's ends, unless a wall is there); an
        embedded sensor measures their mean. Exact at each sample, from the step that
        contains it.
    line : Line
        The line that was run. Every result is in its units; ``n``, ``k`` and
        ``alpha`` are its number of balls, its strikers (``model.strikers``) and its
        contacts' exponent (NaN if they differ).
    dissipated : ndarray, shape (T,)
        The energy dissipated by the damping by each snapshot time (0 on an elastic
        line).
    dissipated_energy : float
        The energy dissipated by ``end_time``.
    contact_dissipation : ndarray, shape (N-1,)
        The energy each contact dissipated by ``end_time``.
    wall_dissipation : ndarray, shape (2,)
        The same for the left and the right wall (0 where there is none).
    wall_impulse : ndarray, shape (2,)
        The impulse the left and the right wall gave the line by ``end_time`` (+x
        towards ball N: the left wall's >= 0, the right's <= 0), integrated along the
        run; the momentum check accounts for it.
    drive_work : ndarray, shape (T,)
        The work the drives (moving walls, forces prescribed in time) did on the line
        by each snapshot time (0 on a line without them): ``kinetic + contact +
        dissipated = initial + drive_work``.
    drive_energy : float
        The same by ``end_time``.
    """

    n: int
    k: int
    alpha: float
    outcome: Outcome
    message: str
    end_time: float
    terminal: bool
    final_position: np.ndarray
    final_velocity: np.ndarray
    separation_time: np.ndarray
    separation_velocity: np.ndarray
    event_time: np.ndarray
    event_contact: np.ndarray
    event_kind: np.ndarray
    times: np.ndarray
    positions: np.ndarray | None
    velocities: np.ndarray | None
    diagnostics: Diagnostics = field(repr=False)
    sensor_balls: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64),
                                     repr=False)
    sensor_time: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    sensor_force: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)),
                                     repr=False)
    line: Line | None = field(default=None, repr=False)
    dissipated: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    dissipated_energy: float = 0.0
    contact_dissipation: np.ndarray = field(default_factory=lambda: np.zeros(0),
                                            repr=False)
    wall_dissipation: np.ndarray = field(default_factory=lambda: np.zeros(2), repr=False)
    wall_impulse: np.ndarray = field(default_factory=lambda: np.zeros(2), repr=False)
    drive_work: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    drive_energy: float = 0.0


#: The floor never goes below the rounding noise of order-one velocities: behind a
#: Hertz wave, balls at rest carry velocities of +-5e-16 whatever the tolerance, and
#: a floor inside that noise turns it into an endless stream of collisions.
FLOOR_MIN = 1e-13


def velocity_floor(rtol: float) -> float:
    """The approach speed below which a collision does not count: max(rtol, 1e-13).

    Velocities are of order 1 in paper units, so a step accurate to ``rtol`` cannot
    resolve relative speeds below about ``rtol``, nor can any computation resolve
    them below the rounding noise (``FLOOR_MIN``). Behind a Hertz wave, rounding
    leaves velocities near 1e-15 whose "collisions" would go on until t ~ 1e10.
    Pairs approaching slower than the floor are not collisions, and a contact whose
    compression rate and load are below it and whose stored energy could not produce
    it is released. Ignoring them changes a final velocity by at most about the floor.
    """
    return max(float(rtol), FLOOR_MIN)


SnapshotHook = Callable[[int, float, np.ndarray, np.ndarray], None]
ProgressHook = Callable[[float], None]


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
