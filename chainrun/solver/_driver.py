"""Drives the kernels between output times: the status loop, the sensors, the result.

The kernel (``_loop.advance``) runs until it needs Python: a snapshot is ready, its
event log is full, its arrays must grow, a stretch of steps has passed (progress), or
the run has ended. This module answers each of these and turns the final status into
a named ``Outcome``; the line's state for the kernels comes from ``_setup``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from chainrun.solver.result import (
    DEFAULT_RTOL,
    Diagnostics,
    Outcome,
    Solution,
    last_sample,
    sample_times,
    velocity_floor,
)
from chainrun.solver import _jit, _loop, _state
from chainrun.solver._setup import _grow, _line_state, _new_state, _Prepared
from chainrun.solver.model import Line, strikers
from chainrun.solver.physics import (
    baseline_energy, contact_law, energy_rounding, impulse, line_kinetic_energy,
    line_momentum, line_potential_energy,
)

_OUTCOMES = {
    _state.ST_TERMINAL: Outcome.TERMINAL,
    _state.ST_STOP_TIME: Outcome.STOP_TIME,
    _state.ST_EVENT_LIMIT: Outcome.EVENT_LIMIT,
    _state.ST_NON_FINITE: Outcome.NON_FINITE,
    _state.ST_STEP_UNDERFLOW: Outcome.STEP_UNDERFLOW,
}


def load_kernels(S: _state.State | None = None) -> None:
    """Compile the kernels, or load them from the cache, for states like ``S``.

    A run calls this before its clock starts, so that its wall time is the solver's.
    """
    if S is None:
        S = _new_state(2, 1, 1.5, DEFAULT_RTOL, None, None)
    _jit.prepare_all([(_loop.advance, (S,))])


def _evaluate(S: _state.State, task: int, t: float) -> None:
    """The state at (internal) time t, inside the last step or in free flight, into
    (S.ox, S.ov): every ball's (TASK_SNAPSHOT), or the balls of S.probe, in order
    (TASK_SAMPLE)."""
    S.ints[_state.I_TASK] = task
    S.fs[_state.F_TTASK] = t
    _loop.advance(S)


def _check_inputs(times, t_end, rtol, max_events):
    if not (math.isfinite(rtol) and 1e-15 <= rtol <= 1e-3):
        raise ValueError(f"rtol must be within [1e-15, 1e-3], got {rtol!r}")
    times = np.asarray(times, dtype=np.float64).reshape(-1)
    if times.size:
        if not np.all(np.isfinite(times)) or times[0] < 0 or np.any(np.diff(times) < 0):
            raise ValueError("times must be finite, non-negative and non-decreasing")
    if t_end is not None:
        if not (math.isfinite(t_end) and t_end > 0):
            raise ValueError(f"t_end must be a finite number > 0, got {t_end!r}")
        if times.size and times[-1] > t_end:
            raise ValueError(f"snapshot time {times[-1]} is after t_end = {t_end}")
    if max_events is not None and (int(max_events) != max_events or max_events < 1):
        raise ValueError(f"max_events must be a positive integer, got {max_events!r}")
    return times


def _check_sensors(sensors, sensor_dt, sensor_end, n):
    balls = np.asarray(sensors, dtype=np.int64).reshape(-1)
    if balls.size == 0:
        return balls, None, None
    if np.any(balls < 1) or np.any(balls > n) or np.unique(balls).size != balls.size:
        raise ValueError(f"sensors must be distinct ball numbers within 1..{n}, "
                         f"got {balls.tolist()}")
    if sensor_dt is None or not (math.isfinite(sensor_dt) and sensor_dt > 0):
        raise ValueError(f"sensor_dt must be a finite number > 0 with sensors, "
                         f"got {sensor_dt!r}")
    if sensor_end is not None and not (math.isfinite(sensor_end) and sensor_end > 0):
        raise ValueError(f"sensor_end must be a finite number > 0, got {sensor_end!r}")
    return balls, float(sensor_dt), sensor_end


#: Samples a sensor's buffers start with; they double as they fill.
_SAMPLE_ROWS = 1024


class _Sensors:
    """The samples of the sensor balls' neighbourhoods: internal positions (and
    velocities, for a damped law) of balls b-1, b, b+1 (a wall's included) at the
    times ``sample_times(dt, end)`` (``dt`` and ``end`` in the line's units, divided by
    ``tscale`` for the kernels), turned into the contact forces on each side of b. Kept
    in arrays, a row per sample."""

    def __init__(self, balls, dt, end, tscale, P: _Prepared):
        self.balls, self.dt, self.tscale, self.P = balls, dt, tscale, P
        self.end = math.inf if end is None else end
        if balls.size and math.isfinite(self.end):
            self.last, self.whole = last_sample(dt, self.end)
        else:
            self.last, self.whole = math.inf, False
        inner = balls - 1 + P.lw  # internal indices
        near = np.concatenate([inner - 1, inner, inner + 1])
        self.probe = np.unique(near[(near >= 0) & (near < P.nb)]).astype(np.int64)
        rows = _SAMPLE_ROWS if balls.size else 0
        self.rows = np.empty((rows, self.probe.size))
        self.vrows = np.empty((rows, self.probe.size))
        self.count = 0

    def next_time(self):
        """The next sample's time in the kernels' units, inf if there is none."""
        k = self.count
        if not self.balls.size or k > self.last:
            return math.inf
        t = self.end if (k == self.last and self.whole) else k * self.dt
        return t / self.tscale

    def take(self, positions, velocities):
        if self.count == self.rows.shape[0]:
            self.rows = np.concatenate([self.rows, np.empty_like(self.rows)])
            self.vrows = np.concatenate([self.vrows, np.empty_like(self.vrows)])
        self.rows[self.count] = positions
        self.vrows[self.count] = velocities
        self.count += 1

    def forces(self):
        P = self.P
        y, u = self.rows[:self.count], self.vrows[:self.count]
        where = {int(b): i for i, b in enumerate(self.probe)}
        out = np.zeros((y.shape[0], self.balls.size, 2))
        for s, ball in enumerate(self.balls - 1 + P.lw):
            for side, (a, b) in enumerate(((ball - 1, ball), (ball, ball + 1))):
                if a >= 0 and b < P.nb:
                    damping = dict(rate=u[:, where[a]] - u[:, where[b]], eta=P.eta[a],
                                   beta=P.beta[a]) if P.damped else {}
                    out[:, s, side] = contact_law(y[:, where[a]] - y[:, where[b]],
                                                  P.kappa[a], P.alpha[a], **damping)
        dt = 1.0 if self.dt is None else self.dt
        return sample_times(dt, self.end, self.count), out * P.scales.force


def run(line: Line, times=(), *, t_end=None, rtol=DEFAULT_RTOL, max_events=None,
        on_snapshot=None, on_progress=None, sensors=(), sensor_dt=None,
        sensor_end=None, closed_form=True) -> Solution:
    """See ``chainrun.solver.simulate``: the run in the units of the line's scales,
    its inputs and results converted at the edges."""
    if not isinstance(line, Line):
        raise TypeError(f"expected a chainrun.solver.Line, got {type(line).__name__}")
    times = _check_inputs(times, t_end, rtol, max_events)
    if t_end is None and not line.has_terminal_state:
        raise ValueError(f"this line has no terminal state "
                         f"({' and '.join(line.terminal_obstacles())}): give t_end")
    if line.n == 1 and line.left is None and line.right is None and line.drives:
        raise ValueError("a lone ball without walls touches nothing: its drive alone moves "
                         "it, with nothing to solve")
    sensor_balls, sensor_dt, sensor_end = _check_sensors(sensors, sensor_dt, sensor_end,
                                                         line.n)
    P = _Prepared(line)
    sc = P.scales
    tscale = sc.time
    S = _line_state(P, rtol, None if t_end is None else t_end / tscale, max_events,
                    closed_form)
    load_kernels(S)
    wall0 = time.perf_counter()
    n = line.n
    nt = times.size
    inner_times = times / tscale
    keep = on_snapshot is None
    positions = np.empty((nt, n)) if keep else None
    velocities = np.empty((nt, n)) if keep else None
    dissipated = np.zeros(nt)
    work = np.zeros(nt)

    def emit(i, t):
        x = P.positions(S.ox)
        v = P.velocities(S.ov)
        dissipated[i] = S.fs[_state.F_DOUT] * sc.energy
        work[i] = S.fs[_state.F_WOUT] * sc.energy
        if keep:
            positions[i] = x
            velocities[i] = v
        else:
            on_snapshot(i, float(t), x, v)

    ev_t, ev_j, ev_k = [], [], []

    def flush():
        m = int(S.ints[_state.I_NEV])
        ev_t.append(S.ev_t[:m] * tscale)
        ev_j.append(S.ev_j[:m] - P.lw)
        ev_k.append(S.ev_k[:m].copy())
        S.ints[_state.I_NEV] = 0

    sensing = _Sensors(sensor_balls, sensor_dt, sensor_end, tscale, P)
    S = S._replace(probe=sensing.probe)
    nout = 0

    def request():
        """Ask the kernel for the next snapshot (1) or sensor sample (2), the earlier."""
        t_snap = inner_times[nout] if nout < nt else math.inf
        t_sample = sensing.next_time()
        if t_sample > S.fs[_state.F_TEND]:
            t_sample = math.inf
        if t_snap == math.inf and t_sample == math.inf:
            S.ints[_state.I_HAVEOUT] = 0
        elif t_snap <= t_sample:
            S.fs[_state.F_TOUT] = t_snap
            S.ints[_state.I_HAVEOUT] = 1
        else:
            S.fs[_state.F_TOUT] = t_sample
            S.ints[_state.I_HAVEOUT] = 2

    request()
    while True:
        kind = int(S.ints[_state.I_HAVEOUT])
        status = _loop.advance(S)
        if status == _state.ST_OUTPUT:
            tout = float(S.fs[_state.F_TOUT])
            if kind == 1:
                emit(nout, times[nout])
                nout += 1
            if tout == sensing.next_time():
                if kind == 1:
                    sensing.take(S.ox[sensing.probe], S.ov[sensing.probe])
                else:
                    _evaluate(S, _state.TASK_SAMPLE, tout)
                    sensing.take(S.ox[:S.probe.size], S.ov[:S.probe.size])
            request()
            if on_progress is not None:
                on_progress(float(S.fs[_state.F_T]) * tscale)
        elif status == _state.ST_FLUSH:
            flush()
        elif status == _state.ST_GROW:
            S = _grow(S, int(S.ints[_state.I_NEED]))
        elif status == _state.ST_DEFECT:
            raise RuntimeError(
                f"internal error: contact states did not settle at "
                f"t = {float(S.fs[_state.F_T]) * tscale!r} "
                f"({_window_text(S, P)}); please report this with the config")
        elif status == _state.ST_YIELD:
            if on_progress is not None:
                on_progress(float(S.fs[_state.F_T]) * tscale)
        else:
            break
    flush()
    outcome = _OUTCOMES[status]
    t_final = float(S.fs[_state.F_T])
    # snapshots after the terminal state are free flight; the kernel evaluates them
    while status == _state.ST_TERMINAL and nout < nt:
        _evaluate(S, _state.TASK_SNAPSHOT, inner_times[nout])
        emit(nout, times[nout])
        nout += 1
    # samples up to the end of the run (its last instant included)
    while sensing.next_time() <= t_final:
        _evaluate(S, _state.TASK_SAMPLE, sensing.next_time())
        sensing.take(S.ox[:S.probe.size], S.ov[:S.probe.size])
    sensor_time, sensor_force = sensing.forces()
    _evaluate(S, _state.TASK_SNAPSHOT, t_final)
    y_final = S.ox.copy()
    v_final = S.ov.copy()
    wall = time.perf_counter() - wall0

    event_time = np.concatenate(ev_t)
    message = _message(outcome, int(S.ints[_state.I_EVTOTAL]), S, P)
    diagnostics = _diagnostics(P, S, y_final, v_final, t_final, wall, rtol,
                               int(event_time.size))
    per_contact = S.cp[_state.C_DISS] * sc.energy if P.damped else np.zeros(P.nb - 1)
    walls = np.zeros(2)
    if P.lw:
        walls[0] = per_contact[0]
    if P.rw:
        walls[1] = per_contact[P.nb - 2]
    alphas = np.concatenate([line.alpha, [w.alpha for w in line.walls if w is not None]])
    return Solution(
        n=n, k=strikers(line),
        alpha=float(alphas[0]) if alphas.size and np.all(alphas == alphas[0]) else math.nan,
        outcome=outcome, message=message.format(t=f"{t_final * tscale:.6g}"),
        message_template=message, end_time=t_final * tscale, terminal=outcome is Outcome.TERMINAL,
        final_position=P.positions(y_final), final_velocity=P.velocities(v_final),
        separation_time=S.sep_t[P.balls] * tscale,
        separation_velocity=S.sep_v[P.balls] * sc.velocity,
        event_time=event_time, event_contact=np.concatenate(ev_j),
        event_kind=np.concatenate(ev_k),
        times=times, positions=positions, velocities=velocities,
        diagnostics=diagnostics, sensor_balls=sensor_balls, sensor_time=sensor_time,
        sensor_force=sensor_force, line=line,
        dissipated=dissipated, dissipated_energy=float(S.fs[_state.F_DISS]) * sc.energy,
        drive_work=work, drive_energy=float(S.fs[_state.F_WORK]) * sc.energy,
        contact_dissipation=per_contact[P.lw:P.lw + n - 1].copy() if n > 1 else np.zeros(0),
        wall_dissipation=walls,
        wall_impulse=np.array([S.fs[_state.F_JL], -S.fs[_state.F_JR]]) * sc.mass * sc.velocity,
    )


def _diagnostics(P: _Prepared, S, y, v, t, wall, rtol, events) -> Diagnostics:
    """Conservation checks of the run just ended (final internal state y, v at time t),
    in the line's own units (``physics``).

    The momentum changes by the external forces', the drives' and the walls' impulses
    (``physics.impulse``); its error is relative to the momentum of the line's scales
    (absolute for the paper's line, whose scales are 1). Kinetic plus contact energy
    less the forces' work is conserved, relative to the impact energy (the strikers'
    kinetic energy and an initial overlap's, ``physics.impact_energy``; K/2 for the
    paper's line; for a line starting at rest, to its initial energy or the work, the
    larger); on a damped line the energy the damping dissipated counts in the
    balance, on a driven line the drives' work (relative to the energy in motion: the
    largest of the initial and final kinetic energy, the work and the contacts' energy
    gained).
    """
    line = P.line
    sc = P.scales
    x0, v0 = line.position, line.velocity
    x1, v1 = P.positions(y), P.velocities(v)
    m = line.mass
    t_end = t * sc.time
    walls = float(S.fs[_state.F_JL] - S.fs[_state.F_JR]) * sc.mass * sc.velocity
    p_exp = line_momentum(v0, m) + impulse(line, t_end, walls)
    p_err = abs(float(line_momentum(v1, m) - p_exp)) / (sc.mass * sc.velocity)
    k0 = float(line_kinetic_energy(v0, m))
    u0 = float(line_potential_energy(x0, line, 0.0))
    e0 = k0 + u0
    # what the damping dissipated is part of the balance, less what the drives did
    k1 = float(line_kinetic_energy(v1, m))
    u1 = float(line_potential_energy(x1, line, t_end))
    work = float(S.fs[_state.F_WORK]) * sc.energy
    e1 = k1 + u1 + float(S.fs[_state.F_DISS]) * sc.energy - work
    # relative to the energy of the impact (a precompressed line stores far more,
    # at rest), or for a line starting at rest to the energy it takes up
    if P.driven:
        scale = max(k0, k1, abs(work), abs(u1 - u0))
    else:
        # the impact energy: the strikers' and an initial overlap's (impact_energy)
        impact = k0 + u0 - baseline_energy(line)
        scale = impact if impact > 0.0 else max(abs(e0), abs(float(line.force @ (x1 - x0))))
    eproj = float(S.fs[_state.F_EPROJ]) * sc.energy
    if not scale > 0.0:
        scale = 1.0
    # the balance cannot be known closer than the rounding of its terms: on a
    # precompressed line, that of the stored energy through the positions' rounding
    eps = np.finfo(float).eps
    floor = (energy_rounding(x0, line, 0.0, u0) + energy_rounding(x1, line, t_end, u1)
             + eps * (k0 + k1 + abs(work) + abs(float(S.fs[_state.F_DISS]) * sc.energy)))
    return Diagnostics(
        steps=int(S.ints[_state.I_STEPS]),
        rejected_steps=int(S.ints[_state.I_REJ]),
        events=events,
        momentum_error=p_err,
        energy_error=abs(e1 - e0) / scale,
        energy_floor=floor / scale,
        energy_correction=eproj / scale,
        wall_time=wall,
        max_window=int(S.ints[_state.I_MAXWIN]),
        rtol=float(rtol),
        velocity_floor=velocity_floor(rtol),
        closed_form_collisions=int(S.ints[_state.I_NSEAL]),
    )


def _message(outcome: Outcome, events: int, S: _state.State, P: _Prepared) -> str:
    """The run's message, its end time left as ``{t}`` for the caller to write in
    the line's units (``Solution.message_with``)."""
    if outcome is Outcome.TERMINAL:
        return f"terminal state reached at t = {{t}} after {events} events"
    if outcome is Outcome.STOP_TIME:
        return f"stopped at t_end = {{t}} after {events} events"
    where = _window_text(S, P)
    if outcome is Outcome.EVENT_LIMIT:
        return f"event limit ({events}) reached at t = {{t}}, {where}"
    if outcome is Outcome.NON_FINITE:
        return f"state became non-finite at t = {{t}}, {where}"
    return f"step size underflow at t = {{t}}, {where}"


def _window_text(S: _state.State, P: _Prepared) -> str:
    ncl = int(S.ints[_state.I_NCL])
    if ncl == 0:
        return "no ball in contact"

    def ball(i):
        if i < P.lw:
            return "the left wall"
        if i >= P.lw + P.n:
            return "the right wall"
        return str(i - P.lw + 1)

    parts = [f"balls {ball(S.clo[c])}-{ball(S.chi[c])}" for c in range(min(ncl, 3))]
    more = f" and {ncl - 3} more clusters" if ncl > 3 else ""
    return "moving clusters: " + ", ".join(parts) + more
