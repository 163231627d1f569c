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

from chainrun.solver.result import (
    DEFAULT_RTOL,
    Diagnostics,
    Outcome,
    Solution,
    velocity_floor,
)
from chainrun.solver import _jit, _loop, _state
from chainrun.solver.model import Line, _alike, strikers
from chainrun.solver.physics import (
    contact_law, contact_load, impulse, line_kinetic_energy, line_momentum,
    line_potential_energy,
)

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
    _jit.prepare_all([(_loop.advance, (S,))])


def _evaluate(S: _state.State, task: int, t: float) -> None:
    """The state at (internal) time t, inside the last step or in free flight, into
    (S.ox, S.ov): every ball's (TASK_SNAPSHOT), or the balls of S.probe, in order
    (TASK_SAMPLE)."""
    S.ints[_state.I_TASK] = task
    S.fs[_state.F_TTASK] = t
    _loop.advance(S)


def release_compression(alpha, floor, stiffness, inverse_mass):
    """Compression whose stored energy equals a relative speed of ``floor``.

    Solves ``2 kappa c^(alpha+1) / ((alpha+1) mu) = floor^2`` (mu the pair's reduced
    mass, 1 / inverse_mass: 1/2 for two unit balls): contacts pressed less than this,
    and moving slower than the floor, cannot produce a speed above the floor.
    """
    return ((alpha + 1.0) * floor * floor / (2.0 * inverse_mass * stiffness)) ** (
        1.0 / (alpha + 1.0))


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


class _Prepared:
    """A ``Line`` in the units of its scales, walls made balls of infinite mass.

    Internal ball i is the line's ball i - lw (lw = 1 with a left wall, whose ball is
    internal ball 0; a right wall's is the last); internal contact j is the line's
    contact j - lw (the left wall's is -1, the right wall's n - 1). Gaps become
    offsets of the reference positions: internal positions are ``y = x + s`` with
    ``s`` the gaps summed from the left, so that every compression is a plain
    difference ``y_j - y_{j+1}`` in the kernels. For the paper's line every scale is 1,
    every offset 0, and the arrays are the paper's to the bit.
    """

    def __init__(self, line: Line):
        self.line = line
        kappa, alpha, gap = line.contact_params()
        sc = self.scales = line.scales((kappa, alpha, gap))
        n = self.n = line.n
        self.lw = 1 if line.left is not None else 0
        self.rw = 1 if line.right is not None else 0
        nb = self.nb = n + self.lw + self.rw
        balls = self.balls = slice(self.lw, self.lw + n)
        self.alpha = alpha
        # kappa L^alpha is a force, in units of M L / T^2; a long line of one kind is
        # converted with one scalar factor (and no copy where that is 1)
        if _alike(alpha):
            factor = (sc.length ** (float(alpha[0]) - 1.0) * sc.time * sc.time / sc.mass
                      if alpha.size else 1.0)
            self.kappa = kappa if factor == 1.0 else kappa * factor
        else:
            self.kappa = kappa * (sc.length ** (alpha - 1.0) * sc.time * sc.time / sc.mass)
        self.mass = np.zeros(nb)
        self.mass[balls] = line.mass if sc.mass == 1.0 else line.mass / sc.mass
        self.im = np.zeros(nb)
        np.divide(1.0, self.mass[balls], out=self.im[balls])
        self.acc = np.zeros(nb)  # (untouched pages cost nothing where there is no force)
        self.forced = bool(np.any(line.force))
        if self.forced:
            self.acc[balls] = line.force / sc.force / self.mass[balls]
        self.offset = np.zeros(nb)
        gapped = bool(np.any(gap))
        if gapped:
            self.offset[1:] = np.cumsum(gap / sc.length)
        self.y0 = self.offset.copy() if gapped else np.zeros(nb)
        self.flat = not gapped and not np.any(line.position) and not self.forced
        if np.any(line.position):
            self.y0[balls] += line.position / sc.length
        self.v0 = np.zeros(nb)
        self.v0[balls] = line.velocity if sc.velocity == 1.0 else line.velocity / sc.velocity
        # damping eta makes eta |c|^beta w a force, in units of M L / T^2
        self.damped = line.is_damped
        if self.damped:
            eta, self.beta = line.damping_params()
            self.eta = eta * (sc.length ** self.beta * sc.velocity / sc.force)
        self._prepare_drives(line)
        if self.driven:
            self.flat = False
        self.unit = (not self.forced and not self.damped and not self.driven and nb == n
                     and bool(np.all(self.mass == 1.0)))
        a = alpha
        if a.size == 0 or (_alike(a) and a[0] == 1.0):
            self.mode, self.alpha0 = _state.MODE_LINEAR, 1.0
        elif _alike(a) and a[0] == 1.5:
            self.mode, self.alpha0 = _state.MODE_HERTZ, 1.5
        elif _alike(a):
            self.mode, self.alpha0 = _state.MODE_POWER, float(a[0])
        else:
            self.mode, self.alpha0 = _state.MODE_MIXED, math.nan

    def _prepare_drives(self, line: Line) -> None:
        """The drives as the kernels take them (``_drive``): per drive its internal
        ball, kind and pieces, in the units of the scales. A moving wall starts where
        its motion has it, at its motion's velocity; a driven ball's drive is an
        acceleration, its force over its mass."""
        sc = self.scales
        found = []  # (internal ball, kind, drive, value scale, dm)
        for b, wall in ((0, line.left), (self.nb - 1, line.right)):
            if wall is not None and wall.motion is not None:
                found.append((b, _state.DRIVE_POSITION, wall.motion, sc.length,
                              self.offset[b]))
        for ball, drive in line.drives:
            b = ball + self.lw
            found.append((b, _state.DRIVE_FORCE, drive, sc.force * self.mass[b],
                          self.mass[b]))
        self.driven = bool(found)
        dv = np.zeros((len(found), _state.DV_ROW), np.int64)
        dm = np.zeros(len(found))
        starts, ranges, terms = [], [], []
        for d, (b, kind, drive, scale, extra) in enumerate(found):
            t0, pieces = drive.pieces(sc.time, scale)
            dv[d] = (b, kind, len(starts), len(starts) + t0.size)
            dm[d] = extra
            for start, rows in zip(t0, pieces):
                q = sum(r.shape[0] for r in terms)
                starts.append(start)
                ranges.append((q, q + rows.shape[0]))
                terms.append(rows)
            if kind == _state.DRIVE_POSITION:
                self.y0[b] += float(drive(0.0)) / sc.length
                self.v0[b] = float(drive(0.0, 1)) * sc.time / sc.length
        self.dv, self.dm = dv, dm
        self.pc_t = np.array(starts, dtype=float)
        self.pc_q = np.array(ranges, dtype=np.int64).reshape(-1, 2)
        self.dq = (np.concatenate(terms) if terms else np.zeros((0, 8))).astype(float)

    def positions(self, y: np.ndarray) -> np.ndarray:
        """The line's displacements, in its units, from internal positions."""
        sc = self.scales
        return (y[self.balls] - self.offset[self.balls]) * sc.length

    def velocities(self, v: np.ndarray) -> np.ndarray:
        return v[self.balls] * self.scales.velocity


def _alloc_window(cap: int) -> dict:
    lanes = -(-cap // _state.SERIES_TILE) * _state.SERIES_TILE
    return dict(
        cb=np.zeros(cap, np.int64),
        X=np.zeros(cap), V=np.zeros(cap), A=np.zeros(cap),
        X0=np.zeros(cap), V0=np.zeros(cap), A0=np.zeros(cap), XS=np.zeros(lanes),
        FS=np.zeros(cap), KV=np.zeros((_state.KV_DS + 1, cap)),
        FX=np.zeros((7, cap)), FV=np.zeros((7, cap)), DM=np.full(cap, -1, np.int64),
        WP=np.zeros((_state.W_HELD + 1, lanes)),
        TX=np.zeros((_state.PT + 1, cap)),
        TW=np.zeros(lanes * _state.TILE_ROWS),
        TR=np.zeros(cap),
        TD=np.zeros(_state.PT + 1), TS=np.zeros((2, _state.N_SERIES_SAMPLES)),
    )


def _initial_contacts(P: _Prepared, cp: np.ndarray, floor: float):
    """Each contact's state at t = 0, its engage level, and the clusters.

    Compressed, or touching and closing (or pressed by external forces): active, in a
    cluster. Touching at rest relative to each other: dormant. Apart, or touching and
    parting: open, and, if the pair closes, its collision is predicted.
    """
    y, v = P.y0, P.v0
    w = v[:-1] - v[1:]
    cst = np.full(w.size, _state.DORMANT, np.int8)
    if P.flat:  # every contact touching, no force: only the velocities decide
        active = w > 0.0
        cst[w < 0.0] = _state.OPEN
    else:
        c = y[:-1] - y[1:]
        a = P.acc[:-1] - P.acc[1:]
        touching = c == 0.0
        active = (c > 0.0) | (touching & ((w > 0.0) | ((w == 0.0) & (a > 0.0))))
        cst[~active & ~(touching & (w == 0.0) & (a == 0.0))] = _state.OPEN
    cst[active] = _state.ACTIVE
    opened = np.flatnonzero(cst == _state.OPEN)
    lvl = np.zeros(w.size)
    if opened.size:
        yl, yr = y[opened], y[opened + 1]
        rounding = 64.0 * _state.EPS * np.maximum(1.0, np.abs(yl) + np.abs(yr))
        lvl[opened] = np.maximum(yl - yr, 0.0) + np.maximum(cp[_state.C_EPS][opened],
                                                           rounding)
    # clusters: maximal runs of active contacts
    edges = np.flatnonzero(np.diff(active.view(np.int8), prepend=0, append=0))
    starts, ends = edges[0::2], edges[1::2]  # ends: one past the run's last contact
    if not opened.size:
        return cst, lvl, starts, ends, opened
    free = np.ones(P.nb, bool)
    for lo, hi in zip(starts, ends):
        free[lo:hi + 1] = False
    near = np.unique(np.concatenate([opened, opened + 1]))
    return cst, lvl, starts, ends, near[free[near]]


def _level(force, kappa, alpha):
    """The compression where a contact's force reaches ``force``."""
    return (force / kappa) ** (1.0 / alpha)


def _uniform(f, *args):
    """``f`` of per-contact arrays, evaluated once in scalars where every contact is
    alike: numpy's vector powers may differ from the scalar ones in the last bit, by
    CPU, and the thresholds of the paper's line are the same on every machine."""
    arrays = [a for a in args if isinstance(a, np.ndarray)]
    if all(np.all(a == a[0]) for a in arrays):
        one = [float(a[0]) if isinstance(a, np.ndarray) else a for a in args]
        return np.full(arrays[0].size, f(*one))
    return f(*args)


def _new_state(n, k, alpha, rtol, t_end, max_events) -> _state.State:
    """The state of the paper's line (for the kernels' tests and their compilation)."""
    return _line_state(_Prepared(Line.paper(n, k, alpha)), rtol, t_end, max_events)


def _line_state(P: _Prepared, rtol, t_end, max_events, closed_form=True) -> _state.State:
    nb = P.nb
    ncont = max(nb - 1, 1)
    floor = velocity_floor(rtol)
    cp = np.zeros(((_state.C_DISS if P.damped else _state.C_LOC) + 1, ncont))
    if nb > 1:
        cp[_state.C_KAPPA] = P.kappa
        cp[_state.C_ALPHA] = P.alpha
        if P.damped:
            cp[_state.C_ETA] = P.eta
            cp[_state.C_BETA] = P.beta
        im = P.im[:-1] + P.im[1:]
        cp[_state.C_EPS] = _uniform(release_compression, P.alpha, floor, P.kappa, im)
        cp[_state.C_DORM] = _uniform(_level, _state.FORCE_DORMANT, P.kappa, P.alpha)
        cp[_state.C_LOC] = _uniform(_level, _state.FORCE_LOCATE, P.kappa, P.alpha)
        cst, lvl, starts, ends, freed0 = _initial_contacts(P, cp, floor)
        if P.damped:
            # a damped contact active at t = 0 whose load would pull starts held at 0
            y, v = P.y0, P.v0
            c = y[:-1] - y[1:]
            load = contact_load(c, v[:-1] - v[1:], P.kappa, P.alpha, P.eta, P.beta)
            cp[_state.C_HELD] = ((cst != _state.OPEN) & (P.eta > 0.0) & (load < 0.0))
    else:
        cst, lvl = np.full(1, _state.DORMANT, np.int8), np.zeros(1)
        starts = ends = freed0 = np.zeros(0, np.int64)
    if P.driven:
        # a driven ball is never free: alone, it is a cluster of its own
        pinned = np.unique(P.dv[:, _state.DV_BALL])
        inside = np.zeros(nb, bool)
        for lo, hi in zip(starts, ends):
            inside[lo:hi + 1] = True
        alone = pinned[~inside[pinned]]
        starts = np.concatenate([starts, alone]).astype(np.int64)
        ends = np.concatenate([ends, alone]).astype(np.int64)
        order = np.argsort(starts, kind="stable")
        starts, ends = starts[order], ends[order]
        freed0 = freed0[~np.isin(freed0, pinned)]
    nd = P.dv.shape[0]
    bp = np.zeros((3, nb))
    bp[_state.B_MASS] = P.mass
    bp[_state.B_IM] = P.im
    bp[_state.B_ACC] = P.acc
    # the drives, past the scalar slots (_state); nothing on a line without drives
    ndp = P.pc_t.size
    fs = np.concatenate([np.zeros(_state.F_NFLOAT), P.dm, np.zeros(nd), P.pc_t,
                         P.dq.reshape(-1), np.zeros((_state.PT + 1) * nd)])
    dcur = np.stack([P.dv[:, _state.DV_LO], np.full(nd, -1, np.int64)], axis=1)
    ints = np.concatenate([np.zeros(_state.I_NINT, np.int64), P.dv.reshape(-1),
                           dcur.reshape(-1), P.pc_q.reshape(-1)]).astype(np.int64)
    ints[_state.I_NDRIVE] = nd
    ints[_state.I_DCUR] = _state.I_NINT + _state.DV_ROW * nd
    ints[_state.I_PCQ] = ints[_state.I_DCUR] + 2 * nd
    ints[_state.I_PCT] = _state.F_NFLOAT + 2 * nd
    ints[_state.I_DQ] = ints[_state.I_PCT] + ndp
    ints[_state.I_DT] = ints[_state.I_DQ] + P.dq.size
    ccap = nb // 2 + 2 + nd
    clo = np.zeros(ccap, np.int64)
    chi = np.zeros(ccap, np.int64)
    clo[:starts.size] = starts
    chi[:ends.size] = ends
    ints[_state.I_NCL] = starts.size
    freed = np.zeros(2 * nb + 8, np.int64)
    freed[:freed0.size] = freed0
    ints[_state.I_NFREED] = freed0.size
    ints[_state.I_DIRTY] = 1 if starts.size or freed0.size else 0
    fs[_state.F_H] = 1e-3
    fs[_state.F_HCAP] = math.inf
    fs[_state.F_TEND] = math.inf if t_end is None else float(t_end)
    fs[_state.F_TOL] = rtol
    fs[_state.F_FLOOR] = floor
    fs[_state.F_ALPHA] = P.alpha0
    ints[_state.I_MODE] = P.mode
    ints[_state.I_UNIT] = 1 if P.unit else 0
    ints[_state.I_FORCED] = 1 if P.forced else 0
    ints[_state.I_DAMPED] = 1 if P.damped else 0
    ints[_state.I_DRIVEN] = 1 if P.driven else 0
    # isolated collisions taken whole: free flight in straight lines
    ints[_state.I_PAIRS] = 1 if closed_form and not P.forced else 0
    ints[_state.I_LWALL] = P.lw
    ints[_state.I_RWALL] = P.rw
    ints[_state.I_LWL] = ints[_state.I_RWL] = -1
    ints[_state.I_XEND] = 1
    ints[_state.I_MAXEV] = -1 if max_events is None else int(max_events)
    return _state.State(
        bx=P.y0.copy(), bv=P.v0.copy(), bt=np.zeros(nb),
        sep_t=np.full(nb, np.nan), sep_v=np.full(nb, np.nan),
        bmap=np.full(nb, -1, np.int64), bp=bp,
        cst=cst, lvl=lvl, stamp=np.zeros(ncont, np.int64), cp=cp,
        sl=np.zeros((_state.NSL_DAMPED if P.damped else _state.NSL, ncont)),
        clo=clo, chi=chi, coff=np.zeros(ccap, np.int64), cen=np.zeros(ccap),
        **_alloc_window(min(nb, _INITIAL_WINDOW)),
        # every contact can be predicted twice (from the freed balls on either side),
        # and every other one can be a sealed collision's end
        hp_t=np.zeros(3 * nb), hp_j=np.zeros(3 * nb, np.int64),
        hp_s=np.zeros(3 * nb, np.int64),
        ev_t=np.zeros(_EVENT_BUFFER), ev_j=np.zeros(_EVENT_BUFFER, np.int64),
        ev_k=np.zeros(_EVENT_BUFFER, np.int8),
        ox=np.zeros(nb), ov=np.zeros(nb), probe=np.zeros(0, np.int64),
        freed=freed, jbuf=np.zeros(nb, np.int64),
        fs=fs, ints=ints,
    )


def _grow(S: _state.State, need: int) -> _state.State:
    n = S.bx.shape[0]
    cap = min(n, max(need, 2 * S.X.shape[0]))
    window = _alloc_window(cap)
    m = int(S.ints[_state.I_M])
    window["cb"][:m] = S.cb[:m]
    return S._replace(**window)


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
    velocities, for a damped law) of balls b-1, b, b+1 (a wall's included) at t = 0,
    dt, 2 dt, ... up to ``end`` (in the units of the scales), turned into the contact
    forces on each side of b. Kept in arrays, a row per sample."""

    def __init__(self, balls, dt, end, P: _Prepared):
        self.balls, self.dt, self.P = balls, dt, P
        self.end = math.inf if end is None else end
        inner = balls - 1 + P.lw  # internal indices
        near = np.concatenate([inner - 1, inner, inner + 1])
        self.probe = np.unique(near[(near >= 0) & (near < P.nb)]).astype(np.int64)
        rows = _SAMPLE_ROWS if balls.size else 0
        self.rows = np.empty((rows, self.probe.size))
        self.vrows = np.empty((rows, self.probe.size))
        self.count = 0

    def next_time(self):
        t = self.count * self.dt if self.balls.size else math.inf
        return t if t <= self.end else math.inf

    def take(self, t, positions, velocities):
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
        return self.dt * np.arange(self.count) * P.scales.time, out * P.scales.force


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

    sensing = _Sensors(sensor_balls, None if sensor_dt is None else sensor_dt / tscale,
                       None if sensor_end is None else sensor_end / tscale, P)
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
                    sensing.take(tout, S.ox[sensing.probe], S.ov[sensing.probe])
                else:
                    _evaluate(S, _state.TASK_SAMPLE, tout)
                    sensing.take(tout, S.ox[:S.probe.size], S.ov[:S.probe.size])
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
        sensing.take(sensing.next_time(), S.ox[:S.probe.size], S.ov[:S.probe.size])
    sensor_time, sensor_force = sensing.forces()
    _evaluate(S, _state.TASK_SNAPSHOT, t_final)
    y_final = S.ox.copy()
    v_final = S.ov.copy()
    wall = time.perf_counter() - wall0

    event_time = np.concatenate(ev_t)
    message = _message(outcome, t_final * tscale, int(S.ints[_state.I_EVTOTAL]), S, P)
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
        outcome=outcome, message=message,
        end_time=t_final * tscale, terminal=outcome is Outcome.TERMINAL,
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
    less the forces' work is conserved, relative to the initial kinetic energy (K/2
    for the paper's line; for a line starting at rest, to its initial energy or the
    work, the larger); on a damped line the energy the damping dissipated counts in the
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
        scale = k0 if k0 > 0.0 else max(abs(e0), abs(float(line.force @ (x1 - x0))))
    eproj = float(S.fs[_state.F_EPROJ]) * sc.energy
    if not scale > 0.0:
        scale = 1.0
    return Diagnostics(
        steps=int(S.ints[_state.I_STEPS]),
        rejected_steps=int(S.ints[_state.I_REJ]),
        events=events,
        momentum_error=p_err,
        energy_error=abs(e1 - e0) / scale,
        energy_correction=eproj / scale,
        wall_time=wall,
        max_window=int(S.ints[_state.I_MAXWIN]),
        rtol=float(rtol),
        velocity_floor=velocity_floor(rtol),
        closed_form_collisions=int(S.ints[_state.I_NSEAL]),
    )


def _message(outcome: Outcome, t: float, events: int, S: _state.State,
             P: _Prepared) -> str:
    if outcome is Outcome.TERMINAL:
        return f"terminal state reached at t = {t:.6g} after {events} events"
    if outcome is Outcome.STOP_TIME:
        return f"stopped at t_end = {t:.6g} after {events} events"
    where = _window_text(S, P)
    if outcome is Outcome.EVENT_LIMIT:
        return f"event limit ({events}) reached at t = {t:.6g}, {where}"
    if outcome is Outcome.NON_FINITE:
        return f"state became non-finite at t = {t:.6g}, {where}"
    return f"step size underflow at t = {t:.6g}, {where}"


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
