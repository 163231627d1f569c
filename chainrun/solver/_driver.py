"""Drives the kernels between output times: state set-up, the status loop, the result.

The kernel (``_loop.advance``) runs until it needs Python: a snapshot is ready, its
event log is full, its arrays must grow, a stretch of steps has passed (progress), or
the run has ended. This module answers each of these and turns the final status into
a named ``Outcome``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from chainrun.solver import (
    DEFAULT_RTOL,
    Diagnostics,
    Outcome,
    Solution,
    velocity_floor,
)
from chainrun.solver import _jit, _loop, _state
from chainrun.solver.physics import contact_forces, kinetic_energy, momentum, potential_energy

_EVENT_BUFFER = 1 << 16
_INITIAL_WINDOW = 256

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
    _jit.prepare(_loop.advance, S)
    _jit.prepare(_loop._snapshot, S, 0.0)
    _jit.prepare(_loop._sample, S, 0.0, np.zeros(1, np.int64), np.zeros(1))


def release_compression(alpha: float, floor: float) -> float:
    """Compression whose stored energy equals a relative speed of ``floor``.

    Solves ``4 c^(alpha+1) / (alpha+1) = floor^2``: contacts pressed less than this,
    and moving slower than the floor, cannot produce a speed above the floor.
    """
    return ((alpha + 1.0) * floor * floor / 4.0) ** (1.0 / (alpha + 1.0))


def _check_inputs(n, k, alpha, times, t_end, rtol, max_events):
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ValueError(f"n must be an integer >= 1, got {n!r}")
    if isinstance(k, bool) or int(k) != k or not 1 <= k <= n:
        raise ValueError(f"k must be an integer with 1 <= k <= n ({n}), got {k!r}")
    if not (math.isfinite(alpha) and alpha >= 1.0):
        raise ValueError(f"alpha must be a finite number >= 1, got {alpha!r}")
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
    return int(n), int(k), float(alpha), times


def _alloc_window(cap: int) -> dict:
    return dict(
        cb=np.zeros(cap, np.int64),
        X=np.zeros(cap), V=np.zeros(cap), A=np.zeros(cap),
        X0=np.zeros(cap), V0=np.zeros(cap), A0=np.zeros(cap), XS=np.zeros(cap),
        FS=np.zeros(cap), KV=np.zeros((_state._NSE, cap)),
        FX=np.zeros((7, cap)), FV=np.zeros((7, cap)), DM=np.full(cap, -1, np.int64),
        TX=np.zeros((_state.PT + 1, cap)),
        TW=np.zeros(-(-cap // _state.SERIES_TILE) * _state.TILE_STRIDE),
        TR=np.zeros(cap),
        TD=np.zeros(_state.PT + 1), TS=np.zeros((2, _state.N_SERIES_SAMPLES)),
    )


def _new_state(n, k, alpha, rtol, t_end, max_events) -> _state.State:
    ncont = max(n - 1, 1)
    floor = velocity_floor(rtol)
    bv = np.zeros(n)
    bv[:k] = 1.0
    cst = np.full(ncont, _state.DORMANT, np.int8)
    fs = np.zeros(_state.F_NFLOAT)
    ints = np.zeros(_state.I_NINT, np.int64)
    ccap = n // 2 + 2
    clo = np.zeros(ccap, np.int64)
    chi = np.zeros(ccap, np.int64)
    if k < n:
        # the last impacting ball meets the first ball at rest: the one live contact
        cst[k - 1] = _state.ACTIVE
        clo[0], chi[0] = k - 1, k
        ints[_state.I_NCL] = 1
        ints[_state.I_DIRTY] = 1
    fs[_state.F_H] = 1e-3
    fs[_state.F_TEND] = math.inf if t_end is None else float(t_end)
    fs[_state.F_TOL] = rtol
    fs[_state.F_FLOOR] = floor
    fs[_state.F_EPSREL] = release_compression(alpha, floor)
    fs[_state.F_ALPHA] = alpha
    fs[_state.F_LDORM] = _state.FORCE_DORMANT ** (1.0 / alpha)
    fs[_state.F_LLOCATE] = _state.FORCE_LOCATE ** (1.0 / alpha)
    ints[_state.I_MODE] = 0 if alpha == 1.0 else (1 if alpha == 1.5 else 2)
    ints[_state.I_MAXEV] = -1 if max_events is None else int(max_events)
    return _state.State(
        bx=np.zeros(n), bv=bv, bt=np.zeros(n),
        sep_t=np.full(n, np.nan), sep_v=np.full(n, np.nan),
        bmap=np.full(n, -1, np.int64),
        cst=cst, lvl=np.zeros(ncont), stamp=np.zeros(ncont, np.int64),
        clo=clo, chi=chi, coff=np.zeros(ccap, np.int64), cen=np.zeros(ccap),
        **_alloc_window(min(n, _INITIAL_WINDOW)),
        hp_t=np.zeros(n), hp_j=np.zeros(n, np.int64), hp_s=np.zeros(n, np.int64),
        ev_t=np.zeros(_EVENT_BUFFER), ev_j=np.zeros(_EVENT_BUFFER, np.int64),
        ev_k=np.zeros(_EVENT_BUFFER, np.int8),
        ox=np.zeros(n), ov=np.zeros(n),
        freed=np.zeros(2 * n + 8, np.int64), jbuf=np.zeros(n, np.int64),
        fs=fs, ints=ints,
    )


def _grow(S: _state.State, need: int) -> _state.State:
    n = S.bx.shape[0]
    cap = min(n, max(need, 2 * S.X.shape[0]))
    window = _alloc_window(cap)
    m = int(S.ints[_state.I_M])
    window["cb"][:m] = S.cb[:m]
    return S._replace(**window)


def _check_sensors(sensors, sensor_dt, n):
    balls = np.asarray(sensors, dtype=np.int64).reshape(-1)
    if balls.size == 0:
        return balls, None
    if np.any(balls < 1) or np.any(balls > n) or np.unique(balls).size != balls.size:
        raise ValueError(f"sensors must be distinct ball numbers within 1..{n}, "
                         f"got {balls.tolist()}")
    if sensor_dt is None or not (math.isfinite(sensor_dt) and sensor_dt > 0):
        raise ValueError(f"sensor_dt must be a finite number > 0 with sensors, "
                         f"got {sensor_dt!r}")
    return balls, float(sensor_dt)


class _Sensors:
    """The samples of the sensor balls' neighbourhoods: positions of balls b-1, b, b+1
    at t = 0, dt, 2 dt, ..., turned into the contact forces on each side of b."""

    def __init__(self, balls, dt, n, alpha):
        self.balls, self.dt, self.n, self.alpha = balls, dt, n, alpha
        near = np.concatenate([balls - 2, balls - 1, balls])  # 0-based b-1, b, b+1
        self.probe = np.unique(near[(near >= 0) & (near < n)]).astype(np.int64)
        self.buffer = np.empty(self.probe.size)
        self.times, self.rows = [], []
        self.count = 0

    def next_time(self):
        return self.count * self.dt if self.balls.size else math.inf

    def take(self, t, positions):
        self.times.append(t)
        self.rows.append(np.array(positions, dtype=float))
        self.count += 1

    def forces(self):
        x = np.array(self.rows).reshape(len(self.rows), self.probe.size)
        where = {int(b): i for i, b in enumerate(self.probe)}
        out = np.zeros((x.shape[0], self.balls.size, 2))
        for s, ball in enumerate(self.balls - 1):
            for side, (a, b) in enumerate(((ball - 1, ball), (ball, ball + 1))):
                if a >= 0 and b < self.n:
                    out[:, s, side] = contact_forces(
                        np.stack([x[:, where[a]], x[:, where[b]]], axis=-1), self.alpha)[:, 0]
        return np.array(self.times), out


def run(n, k, alpha, times=(), *, t_end=None, rtol=DEFAULT_RTOL, max_events=None,
        on_snapshot=None, on_progress=None, sensors=(), sensor_dt=None) -> Solution:
    """See ``chainrun.solver.simulate``."""
    n, k, alpha, times = _check_inputs(n, k, alpha, times, t_end, rtol, max_events)
    sensor_balls, sensor_dt = _check_sensors(sensors, sensor_dt, n)
    S = _new_state(n, k, alpha, rtol, t_end, max_events)
    load_kernels(S)
    wall0 = time.perf_counter()
    nt = times.size
    keep = on_snapshot is None
    positions = np.empty((nt, n)) if keep else None
    velocities = np.empty((nt, n)) if keep else None

    def emit(i, t):
        if keep:
            positions[i] = S.ox
            velocities[i] = S.ov
        else:
            on_snapshot(i, float(t), S.ox, S.ov)

    ev_t, ev_j, ev_k = [], [], []

    def flush():
        m = int(S.ints[_state.I_NEV])
        ev_t.append(S.ev_t[:m].copy())
        ev_j.append(S.ev_j[:m].copy())
        ev_k.append(S.ev_k[:m].copy())
        S.ints[_state.I_NEV] = 0

    sensing = _Sensors(sensor_balls, sensor_dt, n, alpha)
    nout = 0

    def request():
        """Ask the kernel for the next snapshot (1) or sensor sample (2), the earlier."""
        t_snap = times[nout] if nout < nt else math.inf
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
                    sensing.take(tout, S.ox[sensing.probe])
                else:
                    _loop._sample(S, tout, sensing.probe, sensing.buffer)
                    sensing.take(tout, sensing.buffer)
            request()
            if on_progress is not None:
                on_progress(float(S.fs[_state.F_T]))
        elif status == _state.ST_FLUSH:
            flush()
        elif status == _state.ST_GROW:
            need = int(S.ints[_state.I_NEED])
            if need <= 0:
                raise RuntimeError(
                    f"internal error: contact states did not settle at "
                    f"t = {S.fs[_state.F_T]!r} "
                    f"({_window_text(S)}); please report this with the config")
            S = _grow(S, need)
        elif status == _state.ST_YIELD:
            if on_progress is not None:
                on_progress(float(S.fs[_state.F_T]))
        else:
            break
    flush()
    outcome = _OUTCOMES[status]
    t_final = float(S.fs[_state.F_T])
    # snapshots after the terminal state are free flight; the kernel evaluates them
    while status == _state.ST_TERMINAL and nout < nt:
        _loop._snapshot(S, times[nout])
        emit(nout, times[nout])
        nout += 1
    # samples up to the end of the run (its last instant included)
    while sensing.next_time() <= t_final:
        _loop._sample(S, sensing.next_time(), sensing.probe, sensing.buffer)
        sensing.take(sensing.next_time(), sensing.buffer)
    sensor_time, sensor_force = sensing.forces()
    _loop._snapshot(S, t_final)
    x_final = S.ox.copy()
    v_final = S.ov.copy()
    wall = time.perf_counter() - wall0

    p_err = abs(float(momentum(v_final)) - k)
    e0 = 0.5 * k
    e1 = float(kinetic_energy(v_final) + potential_energy(x_final, alpha))
    event_time = np.concatenate(ev_t)
    message = _message(outcome, t_final, int(S.ints[_state.I_EVTOTAL]), S)
    diagnostics = Diagnostics(
        steps=int(S.ints[_state.I_STEPS]),
        rejected_steps=int(S.ints[_state.I_REJ]),
        events=int(event_time.size),
        momentum_error=p_err,
        energy_error=abs(e1 - e0) / e0,
        energy_correction=float(S.fs[_state.F_EPROJ]) / e0,
        wall_time=wall,
        max_window=int(S.ints[_state.I_MAXWIN]),
        rtol=float(rtol),
        velocity_floor=velocity_floor(rtol),
    )
    return Solution(
        n=n, k=k, alpha=alpha, outcome=outcome, message=message,
        end_time=t_final, terminal=outcome is Outcome.TERMINAL,
        final_position=x_final, final_velocity=v_final,
        separation_time=S.sep_t.copy(), separation_velocity=S.sep_v.copy(),
        event_time=event_time, event_contact=np.concatenate(ev_j),
        event_kind=np.concatenate(ev_k),
        times=times, positions=positions, velocities=velocities,
        diagnostics=diagnostics, sensor_balls=sensor_balls, sensor_time=sensor_time,
        sensor_force=sensor_force,
    )


def run_line(line, times=(), **kw) -> Solution:
    """See ``chainrun.solver.simulate_line``."""
    if not line.is_paper:
        raise NotImplementedError("general lines are not wired into the kernels yet")
    k = int(np.count_nonzero(line.velocity))
    return run(line.n, k, float(line.alpha[0]) if line.n > 1 else 1.5, times, **kw)


def _message(outcome: Outcome, t: float, events: int, S: _state.State) -> str:
    if outcome is Outcome.TERMINAL:
        return f"terminal state reached at t = {t:.6g} after {events} events"
    if outcome is Outcome.STOP_TIME:
        return f"stopped at t_end = {t:.6g} after {events} events"
    where = _window_text(S)
    if outcome is Outcome.EVENT_LIMIT:
        return f"event limit ({events}) reached at t = {t:.6g}, {where}"
    if outcome is Outcome.NON_FINITE:
        return f"state became non-finite at t = {t:.6g}, {where}"
    return f"step size underflow at t = {t:.6g}, {where}"


def _window_text(S: _state.State) -> str:
    ncl = int(S.ints[_state.I_NCL])
    if ncl == 0:
        return "no ball in contact"
    parts = [f"balls {S.clo[c] + 1}-{S.chi[c] + 1}" for c in range(min(ncl, 3))]
    more = f" and {ncl - 3} more clusters" if ncl > 3 else ""
    return "moving clusters: " + ", ".join(parts) + more
