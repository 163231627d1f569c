"""A line made ready for the kernels: its scales, its state arrays and their growth.

``_Prepared`` holds a ``Line`` in the units of its scales (``Line.scales()``) and the
rows the kernels read (balls, contacts, walls as contacts with a ball of infinite mass,
drives); ``_line_state`` builds the ``State`` of a run from it, with the contacts that
start closed and their levels; ``_grow`` makes room when the window of integrated balls
outgrows its arrays. ``_driver`` runs what this builds.
"""

from __future__ import annotations

import math

import numpy as np

from chainrun.solver import _state
from chainrun.solver.model import Line, _alike
from chainrun.solver.physics import contact_load
from chainrun.solver.result import velocity_floor

_EVENT_BUFFER = 1 << 16
_INITIAL_WINDOW = 256

def release_compression(alpha, floor, stiffness, inverse_mass):
    """Compression whose stored energy equals a relative speed of ``floor``.

    Solves ``2 kappa c^(alpha+1) / ((alpha+1) mu) = floor^2`` (mu the pair's reduced
    mass, 1 / inverse_mass: 1/2 for two unit balls): contacts pressed less than this,
    and moving slower than the floor, cannot produce a speed above the floor.
    """
    return ((alpha + 1.0) * floor * floor / (2.0 * inverse_mass * stiffness)) ** (
        1.0 / (alpha + 1.0))


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
        # (a column past the lanes: the series' tiles read one past their last, and
        # with a power of two of columns, 512 and more, the rows of TX would lie a
        # multiple of 4 KiB apart, and a load from one row wait on the stores to the
        # next, which the CPU takes for the same place)
        TX=np.zeros((_state.PT + 1, lanes + 1)),
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
    ints[_state.I_DEFJ] = -1
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
        clo=clo, chi=chi, coff=np.full(ccap, -1, np.int64), cen=np.zeros(ccap),
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
    # the packing and accelerations of the clusters that did not change are kept
    # (_clusters._rebuild)
    for name in ("cb", "X", "V", "A"):
        window[name][:m] = getattr(S, name)[:m]
    return S._replace(**window)
