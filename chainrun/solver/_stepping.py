"""One accepted step of the clusters, ending on the earliest event found in it.

``_step_to_event`` chooses the method (the Taylor series where it reaches further than
DOP853's next step), tries steps until one passes its error test or an event cuts it
(``_trial``), lands on the event by redoing the step to end there, refined by Newton on
the step itself (``_land``), and counts what the step did (``_commit_step``). Its
return is ``_state.AGAIN`` (go round ``advance``'s loop) or a status.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._drive import _drive_begin, _series_work
from chainrun.solver._events import _find_event, _grazes, _load_rate, _rounding
from chainrun.solver._jit import kernel
from chainrun.solver._output import _commit_dissipation
from chainrun.solver._state import (
    AFTER_EVENT, AGAIN, B_ACC, C_ETA, EPS, EV_OPEN, EV_RELOAD, EV_UNLOAD, F_H, F_HCAP,
    F_HLAST, F_JL, F_JR, F_JSL, F_JSR, F_T, F_TPREV, F_WORK, F_WSTEP, GO_ON, I_DAMPED,
    I_DEFJ, I_DRIVEN, I_EVJ, I_EVK, I_JUMP, I_M, I_NCL, I_POST, I_REJ, I_STEPS, I_TAY,
    I_XEND, PT, SERIES_CLUSTERS, ST_NON_FINITE, ST_STEP_UNDERFLOW, _free_at,
)
from chainrun.solver._steppers import (
    _ball_at, _branch_step, _step, _step_pair, _taylor, _taylor_error,
)


#: a window of at most this many balls takes the first iterate of a landing whole: a
#: step at two balls reaches 13 balls each way (``_generated._step_band``), as far as
#: such a window's step, which is kept where Newton needs no second iterate
WHOLE_LANDING = 32


@kernel(inline="always")
def _save_start(S):
    for p in range(S.ints[I_M]):
        S.X0[p] = S.X[p]
        S.V0[p] = S.V[p]
        S.A0[p] = S.A[p]


@kernel
def _restore_start(S):
    for p in range(S.ints[I_M]):
        S.X[p] = S.X0[p]
        S.V[p] = S.V0[p]
        S.A[p] = S.A0[p]


@kernel(inline="always")
def _end_ball(S, b, t):
    p = S.bmap[b]
    if p >= 0:
        return S.X[p], S.V[p], S.A[p]
    x, v = _free_at(S, b, t)
    return x, v, S.bp[B_ACC, b]


@kernel(inline="always")
def _step_to_event(S, t, tstop):
    """One accepted step of the clusters from t, ending at the earliest event found in
    it (``_land``), or at tstop (the next collision or the stop time) or a drive's
    breakpoint. Returns AGAIN, or a status where no step can be taken."""
    tbrk = _drive_begin(S, t) if S.ints[I_DRIVEN] == 1 else np.inf
    _save_start(S)
    # the series where it reaches further than DOP853's next step, else DOP853
    h = S.fs[F_H]
    # (not on a damped line, whose forces depend on the velocities)
    ht = _taylor(S) if S.ints[I_NCL] <= SERIES_CLUSTERS and S.ints[I_DAMPED] == 0 \
        else 0.0
    tay = ht >= h
    S.ints[I_TAY] = 1 if tay else 0
    if tay:
        h = min(ht, S.fs[F_HCAP])
    tclip = min(tstop, tbrk)
    clipped = False
    if t + h >= tclip:
        h = tclip - t
        clipped = True
    S.fs[F_TPREV] = t
    S.ints[I_JUMP] = 0
    st, h, err, clipped, th, j, kind, lev = _trial(S, t, h, clipped, tay)
    if st != GO_ON:
        S.ints[I_DEFJ] = -1
        return st
    if tay:
        hnext = S.fs[F_H]  # DOP853's proposal stands; the series sizes its own steps
    else:
        hnext = h * (10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0)))
    if j >= 0:
        st = _land(S, t, h, err, hnext, th, j, kind, lev, tay)
        if st != GO_ON:
            S.ints[I_DEFJ] = -1  # (the step is taken again, and scanned again)
            return st
    else:
        S.fs[F_T] = tclip if clipped else t + h
        if not tay:
            S.fs[F_H] = max(hnext, S.fs[F_H]) if clipped else hnext
    _commit_step(S, tay)
    return AGAIN


@kernel(inline="always")
def _trial(S, t, h, clipped, tay):
    """Try steps from t, shrinking h until one passes its error test or an event cuts it.

    Returns (GO_ON or a status, h, its error / tolerance, whether h still ends at the
    clip, and the earliest event in the step: its fraction th of h, contact j (-1:
    none), kind and level).
    """
    order = PT if tay else 8
    th = 0.0
    j = -1
    kind = 0
    lev = 0.0
    while True:
        S.fs[F_HLAST] = h
        if tay:
            # the series' truncation is known from h alone, and the event scan reads
            # the few balls it needs from their series: the window is evaluated at
            # h only if no event cuts the step (else at the event, by the landing)
            err = _taylor_error(S, h)
            S.ints[I_XEND] = 0
        else:
            err = _step(S, h)
        # a DOP853 step is scanned on its dense output, where its error is finite
        # (one call for both methods: the scan is inlined)
        if tay or np.isfinite(err):
            th, j, kind, lev = _find_event(S)
        if tay and j < 0:
            if h > 64.0 * EPS * max(1.0, abs(t)) and _grazes(S, h):
                # past a graze the series is not to be trusted (_grazes): halve
                # until the step ends before the compression's minimum or keeps
                # it above half its start
                h *= 0.5
                S.ints[I_REJ] += 1
                clipped = False
                continue
            err = _step(S, h)
        if not np.isfinite(err):
            if h < 1e-12 * max(1.0, abs(t)) or not np.isfinite(h):
                # (an infinite step: a cluster whose forces all vanish, grown
                # without bound, would never end)
                return ST_NON_FINITE, h, err, clipped, th, j, kind, lev
            h *= 0.2
            S.ints[I_REJ] += 1
            clipped = False
            continue
        if err <= 1.0:
            return GO_ON, h, err, clipped, th, j, kind, lev
        S.ints[I_REJ] += 1
        if j >= 0:
            # a step over a contact's change of state fails its error test where the
            # force is not smooth; the event cuts the step anyway: go and land on it
            # (the landing step passes the test, or is halved and retried)
            return GO_ON, h, err, clipped, th, j, kind, lev
        h *= max(0.2, 0.9 * err ** (-1.0 / order))
        clipped = False
        if h < 8.0 * EPS * max(1.0, abs(t)):
            return ST_STEP_UNDERFLOW, h, err, clipped, th, j, kind, lev


@kernel
def _land(S, t, h, err, hnext, th, j, kind, lev, tay):
    """Redo the step of h to end on the event found at th h (contact j's kind at level
    lev), refined by Newton on the step itself. Returns GO_ON landed (the event waits
    in I_EVJ, I_EVK), AGAIN where the step is to be tried again shorter (the state
    restored to its start), or ST_STEP_UNDERFLOW.

    A DOP853 step's iterates are taken at the event's two balls alone (``_step_pair``,
    the same numbers there as the window's step), and the step it lands on is then
    taken whole, with its error test: one step of the window for each event (a
    damped contact's unload takes four iterates on average). In a window no larger
    than the pair's bands (``WHOLE_LANDING``) the first iterate is the window's step,
    which is then kept if Newton needs no other. A series step's iterates are
    evaluations of its series over the window."""
    hev = th * h
    if kind == EV_OPEN and err > 1.0 and not tay and (
            S.ints[I_DAMPED] == 0 or S.cp[C_ETA, j] == 0.0):
        # a step that ends on an opening ends on a branch point of the force, and fails
        # its error test where it is longer than _branch_step allows: rather than try
        # it, step halfway towards the opening (as after a landing that failed)
        _, vl = _ball_at(S, j, th)
        _, vr = _ball_at(S, j + 1, th)
        if hev > max(_branch_step(S, j, vr - vl, True), 64.0 * EPS * max(1.0, abs(t))):
            _restore_start(S)
            S.fs[F_H] = 0.5 * hev
            return AGAIN
    landing = 0  # 1 landed, 2 the step failed its error test, 3 Newton gave up
    nit = 0
    whole = True  # whether the last step taken was the whole window's
    while landing == 0:
        if tay or (nit == 0 and S.ints[I_M] <= WHOLE_LANDING):
            if not (_step(S, hev) <= 1.0):
                landing = 2
                break
        else:
            # Newton's iterates need the event's two balls alone; the step that is
            # kept is taken whole below
            _step_pair(S, hev, j)
            whole = False
        xl, vl, al = _end_ball(S, j, t + hev)
        xr, vr, ar = _end_ball(S, j + 1, t + hev)
        if kind == EV_UNLOAD or kind == EV_RELOAD:
            res, w, tol = _load_rate(S, j, xl - xr, vl - vr, al - ar)
        else:
            res = (xl - xr) - lev
            w = vl - vr
            tol = _rounding(abs(xl) + abs(xr))
        if abs(res) <= tol or w == 0.0:
            landing = 1
            break
        dh = -res / w
        nit += 1
        if abs(dh) > 0.5 * hev or nit == 6:
            landing = 3  # the step stays the last one taken (at this hev)
            break
        hev += dh
    if landing == 3 and err > 1.0:
        # an event seen only on a failed step, and not there on a good one:
        # shrink the step as for any failed step
        _restore_start(S)
        S.fs[F_H] = h * max(0.2, 0.9 * err ** (-1.0 / (PT if tay else 8)))
        if tay:
            S.fs[F_HCAP] = S.fs[F_H]
        return AGAIN
    if landing != 2 and not whole and not (_step(S, hev) <= 1.0):
        landing = 2
    if landing == 2:
        # the shorter step failed its error test: halve it and look again
        # (a series step too: capped, or it would take the same step again)
        _restore_start(S)
        S.fs[F_H] = 0.5 * hev
        if tay:
            S.fs[F_HCAP] = 0.5 * hev
        S.ints[I_REJ] += 1
        if hev < 8.0 * EPS * max(1.0, abs(t)):
            return ST_STEP_UNDERFLOW
        return AGAIN
    S.fs[F_HLAST] = hev
    S.fs[F_T] = t + hev
    S.ints[I_EVJ] = j
    S.ints[I_EVK] = kind
    # shorter than the step just cut short: its error estimate spoke for a
    # stretch that crossed the event, smoother than what follows it (after a
    # contact opens, the balls it leaves change fastest)
    S.fs[F_H] = min(hnext, AFTER_EVENT * h)
    return GO_ON


@kernel(inline="always")
def _commit_step(S, tay):
    """Count what the accepted step did: the energy it dissipated, the drives' work, the
    walls' impulses; its post-step work waits for the next pass (I_POST)."""
    if S.ints[I_DAMPED] == 1:
        _commit_dissipation(S)
    if S.ints[I_DRIVEN] == 1:
        if tay:
            S.fs[F_WSTEP] = _series_work(S, S.fs[F_HLAST])
        S.fs[F_WORK] += S.fs[F_WSTEP]
    S.fs[F_JL] += S.fs[F_JSL]
    S.fs[F_JR] += S.fs[F_JSR]
    S.ints[I_STEPS] += 1
    S.ints[I_POST] = 1
    S.fs[F_HCAP] = np.inf
