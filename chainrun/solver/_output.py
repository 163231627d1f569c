"""Inside the last step: the state, the energy dissipated and the drives' work at any
time between its ends.

A snapshot or a sensor sample at a time inside the last step is read from that step
(its series, or DOP853's dense output built for the balls asked for), and a free ball's
from its flight (``_snapshot``, ``_sample``); the energy the damped contacts dissipated
and the drives' work by then come from quadratures of their power on the same
interpolant (``_dissipated_at``, ``_work_at``). ``_commit_dissipation`` adds what a
step just accepted dissipated. ``_loop`` calls these between steps, never inside one.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._drive import _dm, _drive_at, _dv, _series_work
from chainrun.solver._events import _contact_at
from chainrun.solver._forces import _damping, _force, _stored
from chainrun.solver._jit import kernel
from chainrun.solver._pairs import _sealed_at, _sealed_contact, _sealed_lost
from chainrun.solver._state import (
    C_ALPHA, C_BETA, C_DISS, C_ETA, C_HELD, C_KAPPA, DRIVE_POSITION, DV_BALL, DV_KIND,
    F_DISS, F_DOUT, F_HLAST, F_T, F_TPREV, F_WORK, F_WOUT, F_WSTEP, I_DAMPED, I_DRIVEN,
    I_JUMP, I_LWL, I_M, I_NDRIVE, I_RWL, I_SEALED, I_TAY, KV_DS, MODE_MIXED, SEALED, W_ETA,
    W_HELD, _free_at,
)
from chainrun.solver._steppers import _ball_at, _dense, _dense_at, _poly, _taylor_at


@kernel(inline="always")
def _output_phase(S, tout):
    """Where tout falls in the last step, as a fraction of it (1: at or after its end,
    or the balls flew freely since)."""
    t = S.fs[F_T]
    hl = S.fs[F_HLAST]
    if tout < t and S.ints[I_JUMP] == 0 and hl > 0.0:
        return max((tout - S.fs[F_TPREV]) / hl, 0.0)
    return 1.0


@kernel(inline="always")
def _state_at(S, b, tout, th):
    """(x, v) of ball b at tout, th = _output_phase(S, tout): from the last step's
    series or interpolant (built for this ball if need be), or in free flight."""
    p = S.bmap[b]
    if p >= 0:
        if th >= 1.0:
            return S.X[p], S.V[p]
        if S.ints[I_TAY] == 1:
            return _taylor_at(S, p, th * S.fs[F_HLAST])
        _dense_at(S, p)
        return _poly(S.FX, S.X0[p], p, th), _poly(S.FV, S.V0[p], p, th)
    if S.ints[I_SEALED] > 0:
        js = _sealed_contact(S, b)
        if js >= 0:
            return _sealed_at(S, js, b, tout)
    return _free_at(S, b, tout)


# nodes and weights of 8-point Gauss-Legendre quadrature on [0, 1]
_GAUSS_X = np.array([0.019855071751231856, 0.10166676129318664, 0.2372337950418355,
                     0.4082826787521751, 0.5917173212478249, 0.7627662049581645,
                     0.8983332387068134, 0.9801449282487681])
_GAUSS_W = np.array([0.05061426814518813, 0.11119051722668724, 0.15685332293894363,
                     0.18134189168918100, 0.18134189168918100, 0.15685332293894363,
                     0.11119051722668724, 0.05061426814518813])


@kernel
def _dissipated_at(S, th):
    """The energy dissipated up to t_prev + th * h_last (the last step is counted in
    F_DISS already): less what the damped lanes dissipate over the rest of the step,
    by Gauss-Legendre quadrature of their power on its dense output (no kink inside a
    step), or, for a lane held at 0, exactly (_commit_dissipation)."""
    total = S.fs[F_DISS]
    if th >= 1.0:
        return total
    span = (1.0 - th) * S.fs[F_HLAST]
    m = S.ints[I_M]
    for p in range(m - 1):
        if S.WP[W_ETA, p] == 0.0:
            continue
        j = S.cb[p]
        if S.WP[W_HELD, p] != 0.0:
            total -= _stored(S, j, _contact_at(S, j, th)[0]) - _stored(S, j, S.X[p] - S.X[p + 1])
            continue
        eta = S.cp[C_ETA, j]
        beta = S.cp[C_BETA, j]
        for i in range(_GAUSS_X.shape[0]):
            c, w, _s = _contact_at(S, j, th + (1.0 - th) * _GAUSS_X[i])
            total -= span * _GAUSS_W[i] * eta * _damping(c, w, beta) * w
    return total


@kernel
def _commit_dissipation(S):
    """Add the energy the damped lanes dissipated over the step just accepted to their
    contacts' and the line's totals: the quadrature of their damping's power (DS, see
    _forces._damped_forces), or, for a lane held at 0, the elastic energy it lost as
    its compression went, exactly (its power -kappa c^alpha c' is a derivative)."""
    DS = S.KV[KV_DS]
    step = 0.0
    for p in range(S.ints[I_M] - 1):
        if S.WP[W_ETA, p] != 0.0:
            j = S.cb[p]
            if S.WP[W_HELD, p] != 0.0:
                d = _stored(S, j, S.X0[p] - S.X0[p + 1]) - _stored(S, j, S.X[p] - S.X[p + 1])
            else:
                d = DS[p]
            S.cp[C_DISS, j] += d
            step += d
    S.fs[F_DISS] += step


@kernel
def _drive_power(S, th):
    """The drives' power at t_prev + th * h_last, inside the last step: a moving wall's
    contact force times its velocity (the force its law gives, from the compression on
    the step's dense output or series), a driven ball's drive times its velocity."""
    t = S.fs[F_TPREV] + th * S.fs[F_HLAST]
    power = 0.0
    for d in range(S.ints[I_NDRIVE]):
        u, du, _ddu = _drive_at(S, d, t)
        b = _dv(S, d, DV_BALL)
        if _dv(S, d, DV_KIND) == DRIVE_POSITION:
            left = b == 0
            lane = S.ints[I_LWL] if left else S.ints[I_RWL]
            if lane < 0:
                continue
            j = 0 if left else S.cst.shape[0] - 1
            c, w, _s = _contact_at(S, j, th)
            f = S.cp[C_KAPPA, j] * _force(c, MODE_MIXED, S.cp[C_ALPHA, j])
            if S.ints[I_DAMPED] == 1 and S.cp[C_ETA, j] != 0.0:
                f = 0.0 if S.cp[C_HELD, j] != 0.0 else \
                    f + S.cp[C_ETA, j] * _damping(c, w, S.cp[C_BETA, j])
            power += f * du if left else -f * du
        else:
            power += _dm(S, d) * u * _ball_at(S, b, th)[1]
    return power


@kernel
def _work_at(S, th):
    """The drives' work up to t_prev + th * h_last (F_WORK counts the last step whole):
    on a series step from its series (_series_work), on a DOP853 step by Gauss-Legendre
    quadrature of their power on its dense output."""
    if th >= 1.0:
        return S.fs[F_WORK]
    base = S.fs[F_WORK] - S.fs[F_WSTEP]
    span = th * S.fs[F_HLAST]
    if S.ints[I_TAY] == 1:
        return base + _series_work(S, span)
    total = 0.0
    for i in range(_GAUSS_X.shape[0]):
        total += _GAUSS_W[i] * _drive_power(S, th * _GAUSS_X[i])
    return base + span * total


@kernel
def _snapshot(S, tout):
    """Fill (ox, ov) with the state at tout, inside the last step or in free flight,
    fs[F_DOUT] with the energy dissipated by then, and fs[F_WOUT] with the drives'
    work."""
    th = _output_phase(S, tout)
    if th < 1.0 and S.ints[I_TAY] == 0:
        _dense(S)  # the whole window's interpolant at once
    for b in range(S.bx.shape[0]):
        S.ox[b], S.ov[b] = _state_at(S, b, tout, th)
    if S.ints[I_DRIVEN] == 1:
        S.fs[F_WOUT] = _work_at(S, th)
    if S.ints[I_DAMPED] == 1:
        S.fs[F_DOUT] = _dissipated_at(S, th)
        if S.ints[I_SEALED] > 0:  # (a sealed contact counts its own when it ends)
            for j in range(S.cst.shape[0]):
                if S.cst[j] == SEALED:
                    S.fs[F_DOUT] += _sealed_lost(S, j, tout)


@kernel
def _sample(S, tout):
    """Positions and velocities at tout of the balls listed in S.probe (0-based) into
    ox, ov, in their order: a snapshot of those balls alone, at a cost in their
    number, not in N."""
    th = _output_phase(S, tout)
    for i in range(S.probe.shape[0]):
        S.ox[i], S.ov[i] = _state_at(S, S.probe[i], tout, th)
