"""The solver's results and their vocabulary: outcomes, event kinds, diagnostics, the
``Solution`` a run returns, the velocity floor, and the hooks a run calls.

Plain data, imported by the driver (``_driver``) that fills them and re-exported by the
package: no kernel and no formula of a line lives here.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from chainrun.solver.model import Line

#: Default relative accuracy of a step (velocities are of order 1 in paper units).
DEFAULT_RTOL = 1e-12
#: An end within this fraction of a sample interval of a whole number of them is that
#: number (5 ms every 5 us: 0.005 / 5e-6 is 999.9999999999999 in floating point)
_WHOLE_SAMPLES = 1e-9


def last_sample(dt: float, end: float) -> tuple[int, bool]:
    """The index of the last force sample at or before ``end`` on the grid 0, dt, 2 dt,
    ..., and whether ``end`` is that sample (a whole number of ``dt`` up to rounding)."""
    ratio = end / dt
    whole = round(ratio)
    if abs(ratio - whole) <= _WHOLE_SAMPLES * max(1.0, ratio):
        return int(whole), True
    return math.floor(ratio), False


def sample_times(dt: float, end: float, count: int | None = None) -> np.ndarray:
    """The force sensors' sample times: k dt for k = 0, 1, ... up to ``end``
    (``last_sample``), or the first ``count`` of them.

    In the units of ``dt``, computed there (never through a line's scales): every run
    with the same ``dt`` has the same times to the last bit, whatever its line, so that
    the runs of a sweep share one time axis. Where ``end`` is a whole number of ``dt``
    up to rounding, the last sample is at ``end`` itself: 5 ms every 5 us is 1001
    samples, the last at 0.005.
    """
    last, whole = last_sample(dt, end) if math.isfinite(end) else (math.inf, False)
    n = last + 1 if count is None else count
    times = dt * np.arange(n, dtype=np.float64)
    if whole and n == last + 1:
        times[-1] = end
    return times


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
    and the walls' impulses accounted, and energy_error to its impact energy (the
    strikers' kinetic energy and an initial overlap's: K/2 on the paper's line), with the external forces' work, the drives' and the
    damping's dissipation accounted (``_driver._diagnostics``). Each cluster's internal energy is projected
    back to its conserved value at every change of structure (see
    ``_projection._project_energy``); energy_correction is the sum of those corrections,
    relative like energy_error, the honest measure of the integration error that the
    projection removes. closed_form_collisions counts the isolated binary collisions
    taken whole (in closed form, or a damped pair's own relative motion) rather than
    integrated with the clusters (``_pairs``). energy_floor, relative like energy_error,
    is what the rounding of the balance's terms leaves uncertain
    (``physics.energy_rounding``): an energy_error near it is rounding, not the solver's
    error (a precompressed line stores far more energy than a small drive moves).
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
    energy_floor: float = 0.0


@dataclass(frozen=True)
class Solution:
    """The result of one run.

    Attributes
    ----------
    n, k : int
    alpha : float
    outcome : Outcome
    message : str
        One line for a person, naming the time and place of any failure (the time as
        a bare number: ``message_with`` writes it with a unit).
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
    message_template: str = field(default="", repr=False)

    def message_with(self, time_text: Callable[[float], str]) -> str:
        """``message`` with its time written by ``time_text`` (``1.19308 ms`` for a
        line in SI units, where ``message`` says ``0.00119308``)."""
        if not self.message_template:
            return self.message
        return self.message_template.format(t=time_text(self.end_time))


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
