"""The step loop: ``advance``, which runs the solver and evaluates its state.

The kernels own the numerics and nothing else: they never see files or Python
objects, and report through integer status codes (``_state.ST_*``) that ``_driver``
maps to named outcomes. ``advance`` is the one entry point that Python calls (cached,
see ``_jit``); everything else is a ``kernel`` linked into it. One entry point is one
compiled library to load at start-up: a snapshot or a sample of a few balls
(``_output._snapshot``, ``_sample``) is a task ``advance`` runs when ``ints[I_TASK]``
asks.

One pass of the loop rebuilds the compact arrays after a change of structure
(``_clusters``), takes snapshots due inside the last step, applies the event or
releases that the last step ended on (``_post_step``, ``_settle``), jumps over free
flight to the next predicted collision (``_heap``), or takes one accepted step
(``_steppers``) that ends on the earliest event found in it (``_events``). A predicted
collision that nothing else can reach while it lasts is taken whole (in closed form,
or a damped pair's own relative motion), and its end waits in the heap (``_binary``,
``_pairs``, ``_pair_damped``): it costs no steps and does not hold back the
clusters' step size.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._binary import _seal, _sealed_end
from chainrun.solver._clusters import (
    _activate, _deactivate, _rebuild, _sync, _unseal_at_end, _unseal_near_clusters,
)
from chainrun.solver._compression import _pressed_in_step
from chainrun.solver._drive import _drive_begin, _series_work
from chainrun.solver._events import _find_event, _grazes, _load_rate, _log, _rounding
from chainrun.solver._heap import _heap_pop, _heap_valid_top
from chainrun.solver._jit import entry, kernel
from chainrun.solver._output import _commit_dissipation, _sample, _snapshot
from chainrun.solver._state import (
    ACTIVE, AFTER_EVENT, B_ACC, B_IM, C_ALPHA, C_DORM, C_EPS, C_ETA, C_HELD, C_KAPPA, DORMANT,
    EPS, EV_CLOSE, EV_ENGAGE, EV_OPEN, EV_RELEASE, EV_RELOAD, EV_UNLOAD, FRESH, F_FLOOR, F_H,
    F_HCAP, F_HLAST, F_JL, F_JR, F_JSL, F_JSR, F_T, F_TEND, F_TOUT, F_TPREV, F_TSAME, F_TTASK,
    F_WORK, F_WSTEP, HI_ROW, I_DAMPED, I_DIRTY, I_DRIVEN, I_EVJ, I_EVK, I_EVTOTAL, I_FORCED,
    I_HAVEOUT, I_JUMP, I_M, I_MAXEV, I_NCL, I_NEED, I_NEV, I_NSAME, I_NSEAL, I_PAIRS, I_POST,
    I_REJ, I_SEALED, I_STEPS, I_TASK, I_TAY, I_XEND, OPEN, PT, SERIES_CLUSTERS, ST_DEFECT,
    ST_EVENT_LIMIT, ST_FLUSH, ST_GROW, ST_NON_FINITE, ST_OUTPUT, ST_STEP_UNDERFLOW,
    ST_STOP_TIME, ST_TERMINAL, ST_YIELD, TASK_RUN, TASK_SNAPSHOT, W_HELD, YIELD_STEPS, _flight,
    _free_at, _tw,
)
from chainrun.solver._steppers import _ball_now, _step, _taylor, _taylor_error


@kernel
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


@kernel
def _engage_level(S, j):
    """Compression beyond which contact j, made inactive now, engages again.

    Its present compression plus eps_rel, and never within rounding of it (at tiny
    rtol eps_rel is below the rounding of the positions, and a level inside the
    rounding would flip the contact back and forth).
    """
    t = S.fs[F_T]
    xl = _free_at(S, j, t)[0]
    xr = _free_at(S, j + 1, t)[0]
    return max(xl - xr, 0.0) + max(S.cp[C_EPS, j], 4.0 * _rounding(abs(xl) + abs(xr)))


@kernel
def _apply_event(S, j, kind):
    """Set contact j's state from the event just reached (positions are synced)."""
    t = S.fs[F_T]
    if kind == EV_UNLOAD or kind == EV_RELOAD:
        # a kink of a damped force: the contact stays active, its force held at 0
        # (or not) by the law itself
        held = 1.0 if kind == EV_UNLOAD else 0.0
        S.cp[C_HELD, j] = held
        p = S.bmap[j]
        if p >= 0:
            S.WP[W_HELD, p] = held
        _log(S, t, j, kind)
        return True
    if kind == EV_OPEN or kind == EV_RELEASE:
        ok = _deactivate(S, j, _engage_level(S, j))
        _log(S, t, j, kind)
    elif kind == EV_CLOSE:
        ok = _activate(S, j, ACTIVE)
        _log(S, t, j, EV_CLOSE)
    else:
        dormant = S.cst[j] == DORMANT
        ok = _activate(S, j, FRESH if dormant else ACTIVE)
        if not dormant:  # a dormant contact was closed already: nothing to log
            _log(S, t, j, EV_ENGAGE)
    return ok


@kernel
def _season(S):
    """Season the fresh contacts pressed beyond eps_rel in the last step (made ACTIVE).

    After every accepted step, whatever else it brings: a wave presses a fresh contact
    and passes on within a few steps, each of which may end on an event or an
    engagement at the front.
    """
    tay = S.ints[I_TAY] == 1 and S.ints[I_JUMP] == 0
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        lo = S.clo[c]
        for j in range(lo, S.chi[c]):
            if S.cst[j] == FRESH:
                p = o + j - lo
                epsrel = S.cp[C_EPS, j]
                if S.X[p] - S.X[p + 1] > epsrel:
                    S.cst[j] = ACTIVE
                elif tay and S.TW[_tw(p, HI_ROW)] > epsrel and _pressed_in_step(S, j):
                    # pressed beyond eps_rel inside the step (a candidate only if its
                    # bound over the step, from the event scan, reaches eps_rel)
                    S.cst[j] = ACTIVE


@kernel
def _release_quiet(S):
    """Release the contacts below the floor.

    A seasoned contact is released when its relative motion and stored energy could
    not produce a speed above the floor (w^2 + 2 kappa c^(alpha+1) / ((alpha+1) mu) <
    floor^2, mu the pair's reduced mass: 1/2 for the paper's balls, a ball's mass
    against a wall) and its neighbours do not load it (|c''| < floor). A fresh contact (at the front of a
    wave, never pressed beyond eps_rel) is released only when pulled apart beyond
    the rounding of its positions; it carried no force above the floor.
    """
    floor = S.fs[F_FLOOR]
    nrel = 0
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        lo = S.clo[c]
        for j in range(lo, S.chi[c]):
            p = o + j - lo
            st = S.cst[j]
            cj = S.X[p] - S.X[p + 1]
            if st == FRESH:
                if cj < -_rounding(abs(S.X[p]) + abs(S.X[p + 1])):
                    S.jbuf[nrel] = j
                    nrel += 1
            elif st == ACTIVE and cj < S.cp[C_EPS, j]:
                w = S.V[p] - S.V[p + 1]
                if abs(w) >= floor or abs(S.A[p] - S.A[p + 1]) >= floor:
                    continue
                cp = cj if cj > 0.0 else 0.0
                a = S.cp[C_ALPHA, j]
                im = S.bp[B_IM, j] + S.bp[B_IM, j + 1]
                if w * w + 2.0 * im * S.cp[C_KAPPA, j] * cp ** (a + 1.0) / (a + 1.0) < floor * floor:
                    S.jbuf[nrel] = j
                    nrel += 1
    if nrel == 0:
        return True
    _sync(S)
    t = S.fs[F_T]
    for i in range(nrel):
        j = S.jbuf[i]
        if not _deactivate(S, j, _engage_level(S, j)):
            return False
        _log(S, t, j, EV_RELEASE)
    return True


@kernel(inline="always")
def _pressed_back(S, j, c, w):
    """Whether the pair of contact j, overlapped by c > 0 (within rounding) and parting
    at w < 0, is pressed back together before its compression reaches 0: the two balls
    alone in their cluster, their external forces pressing them (a > 0) and the
    compression's parabola c + w s + a s^2 / 2 with no root. Opened, such a pair would
    stay overlapped as free balls, with no crossing of 0 for a collision to be
    predicted at (``_heap._schedule_pair``): it stays in contact instead."""
    if not (c > 0.0 and S.ints[I_FORCED] == 1):
        return False
    if (j > 0 and S.cst[j - 1] != OPEN) or (j + 1 < S.cst.shape[0] and S.cst[j + 1] != OPEN):
        return False
    a = S.bp[B_ACC, j] - S.bp[B_ACC, j + 1]
    return a > 0.0 and w * w < 2.0 * a * c


@kernel(inline="always")
def _due(S, j):
    """The event contact j is due at this instant, if its state disagrees with its motion.

    Several contacts can reach their levels at the same instant (a mirror-symmetric
    line opens two at once); the step lands on one, and the others sit within rounding
    of their level, possibly just past it, where no crossing will ever be seen.
    """
    t = S.fs[F_T]
    dl, vl = _flight(S, j, t)
    dr, vr = _flight(S, j + 1, t)
    xl = S.bx[j] + dl
    xr = S.bx[j + 1] + dr
    c = xl - xr
    w = vl - vr
    # the rounding of a free ball's x + v (t - tref) comes from its terms, not its value;
    # and t itself is resolved only to EPS t, in which balls closing at w move w EPS t:
    # a gap that closes within that is closed now (else it opens and closes forever)
    r = _rounding(abs(xl) + abs(xr) + abs(dl) + abs(dr)) + 4.0 * EPS * abs(t) * abs(w)
    st = S.cst[j]
    if st == ACTIVE:
        if c < -r or (c <= r and w < 0.0 and not _pressed_back(S, j, c, w)):
            return EV_OPEN
    elif st == FRESH:
        if c < -r:
            return EV_RELEASE
    elif st == DORMANT:
        if c >= S.cp[C_DORM, j]:
            return EV_ENGAGE
        if c <= -S.cp[C_EPS, j]:
            return EV_RELEASE
    else:
        if c >= -r and w >= S.fs[F_FLOOR]:
            return EV_CLOSE
        if c >= S.lvl[j]:
            return EV_ENGAGE
    return 0


@kernel
def _dormant_due(S):
    """Whether a dormant contact at a cluster's edge has been pressed (or pulled) past its levels."""
    ncont = S.cst.shape[0]
    for c in range(S.ints[I_NCL]):
        for j in (S.clo[c] - 1, S.chi[c]):
            if j < 0 or j >= ncont or S.cst[j] != DORMANT:
                continue
            xl, vl, al = _ball_now(S, j)
            xr, vr, ar = _ball_now(S, j + 1)
            cj = xl - xr
            if cj >= S.cp[C_DORM, j] or cj <= -S.cp[C_EPS, j]:
                return True
    return False


@kernel
def _settle(S):
    """After a change of structure, apply every event due at this instant (positions synced)."""
    ncont = S.cst.shape[0]
    budget = 4 * (S.ints[I_M] + 2 * S.ints[I_NCL] + 4)
    changed = True
    while changed:
        changed = False
        budget -= 1
        if budget < 0:
            return False  # contacts flipping back and forth: a defect, reported by the driver
        # a sealed collision next to a cluster is integrated from now on: its balls'
        # free-flight lines are not their motion
        if S.ints[I_SEALED] > 0:
            _unseal_near_clusters(S)
        for c in range(S.ints[I_NCL]):
            j0 = max(S.clo[c] - 1, 0)
            j1 = min(S.chi[c], ncont - 1)
            for j in range(j0, j1 + 1):
                kind = _due(S, j)
                if kind != 0:
                    if not _apply_event(S, j, kind):
                        return False
                    changed = True
                    break
            if changed:
                break
    return True


@kernel
def _loads_due(S):
    """Switch the damped contacts whose load is on the wrong side of 0 and moving away
    from it: held at 0 but pushing and rising, or bearing it but pulling and falling.

    A step that lands on an unload (or a reload) ends within rounding of the load's 0,
    on either side; where the load turns there, touching 0 and going back, no crossing
    is left for the next step to find, and the contact would stay held while it
    pushes. The load's rate at the step's end says which way it goes.
    """
    for c in range(S.ints[I_NCL]):
        lo = S.clo[c]
        o = S.coff[c] - lo
        for j in range(lo, S.chi[c]):
            if S.cp[C_ETA, j] == 0.0:
                continue
            p = o + j
            cj = S.X[p] - S.X[p + 1]
            if not cj > 0.0:
                continue
            g, dg, _r = _load_rate(S, j, cj, S.V[p] - S.V[p + 1], S.A[p] - S.A[p + 1])
            held = S.cp[C_HELD, j] != 0.0
            if (held and g > 0.0 and dg > 0.0) or (not held and g < 0.0 and dg < 0.0):
                if S.ev_t.shape[0] - S.ints[I_NEV] < 1:
                    return  # (the log is full: the next pass switches it)
                _apply_event(S, j, EV_UNLOAD if not held else EV_RELOAD)


@kernel
def _post_step(S):
    """After an accepted step or jump: season contacts, then apply its event or release contacts."""
    if S.ints[I_JUMP] == 0 and S.ints[I_M] > 0:
        _season(S)
    k = S.ints[I_EVK]
    if k != 0:
        S.ints[I_EVK] = 0
        _sync(S)
        j = S.ints[I_EVJ]
        if not _apply_event(S, j, k):
            return False
        if k == EV_UNLOAD and _due(S, j) == EV_OPEN:
            # the load vanished with the compression (in a slow collision, whose
            # damping goes as c^beta): it opens now, or its balls, held without force,
            # would part with no crossing left for a step to find
            if not _apply_event(S, j, EV_OPEN):
                return False
    elif S.ints[I_M] > 0:
        if _dormant_due(S):
            _sync(S)
            S.ints[I_DIRTY] = 1
        elif not _release_quiet(S):
            return False
    if S.ints[I_DIRTY] == 1:
        return _settle(S)
    if S.ints[I_DAMPED] == 1 and S.ints[I_JUMP] == 0 and S.ints[I_M] > 0:
        _loads_due(S)  # (the compact arrays are current: no change of structure)
    return True


@kernel(inline="always")
def _end_ball(S, b, t):
    p = S.bmap[b]
    if p >= 0:
        return S.X[p], S.V[p], S.A[p]
    x, v = _free_at(S, b, t)
    return x, v, S.bp[B_ACC, b]


#: what the parts of one pass of ``advance`` tell it besides a status (ST_* >= 0): go
#: round the loop again, go on to the next part, or go round after a step's worth of work
#: (a sealed collision, counted against YIELD_STEPS like a step)
AGAIN = -1
GO_ON = -2
COUNTED = -3


@entry
def advance(S):
    """Run until something needs the driver; return a status code (ST_*).

    The driver sets ``fs[F_TOUT]`` and ``ints[I_HAVEOUT] = 1`` to ask for the next
    snapshot (2 for a sample of a few balls, which it then asks for as a task),
    empties the event log on ST_FLUSH, grows the compact arrays on ST_GROW (to
    ``ints[I_NEED]``) and calls again; ST_DEFECT reports contact states that do not
    settle. With ``ints[I_TASK]`` set, the call evaluates the state at ``fs[F_TTASK]``
    instead (TASK_SNAPSHOT: every ball into ox, ov; TASK_SAMPLE: the balls of probe)
    and returns ST_OUTPUT.

    Each pass: what the last step left (``_after_step``), a collision due now
    (``_collide``), the stop time, free flight to the next collision (``_fly``), or
    one step of the clusters (``_step_to_event``).
    """
    task = S.ints[I_TASK]
    if task != TASK_RUN:
        S.ints[I_TASK] = TASK_RUN
        if task == TASK_SNAPSHOT:
            _snapshot(S, S.fs[F_TTASK])
        else:
            _sample(S, S.fs[F_TTASK])
        return ST_OUTPUT
    nsteps = 0
    while True:
        st = _after_step(S)
        if st == AGAIN:
            continue
        if st != GO_ON:
            return st
        t = S.fs[F_T]
        tend = S.fs[F_TEND]
        tcol = _next_collision(S, t)
        if tcol <= t:
            st = _collide(S, t)
            if st == COUNTED:
                nsteps += 1
                if nsteps > YIELD_STEPS:
                    return ST_YIELD
            elif st != AGAIN:
                return st
            continue
        if t >= tend:
            _unseal_at_end(S)
            return ST_STOP_TIME
        if S.ints[I_NCL] == 0:
            if tcol == np.inf and S.ints[I_FORCED] == 0:
                return ST_TERMINAL  # (under external forces, free flight to tend)
            _fly(S, t, min(tcol, tend))
            continue
        nsteps += 1
        if nsteps > YIELD_STEPS:
            return ST_YIELD
        st = _step_to_event(S, t, min(tcol, tend))
        if st != AGAIN:
            return st


@kernel(inline="always")
def _after_step(S):
    """What the last step (or jump, or collision) left: the compact arrays packed again
    after a change of structure, a snapshot due inside the step (before its event
    reshapes the clusters), its event applied (``_post_step``); the event limit.

    Returns a status for the driver, AGAIN after applying the step's event, or GO_ON.
    """
    while S.ints[I_DIRTY] == 1:  # (a rebuild can take a sealed pair in: again)
        need = _rebuild(S)
        if need > 0:
            S.ints[I_NEED] = need
            return ST_GROW
    # (I_HAVEOUT 2: a sample of a few balls, which the driver takes with _sample)
    if S.ints[I_HAVEOUT] != 0 and S.fs[F_TOUT] <= S.fs[F_T]:
        if S.ints[I_HAVEOUT] == 1:
            _snapshot(S, S.fs[F_TOUT])
        S.ints[I_HAVEOUT] = 0
        return ST_OUTPUT
    if S.ints[I_POST] == 1:
        if S.ev_t.shape[0] - S.ints[I_NEV] < S.ints[I_M] + 4:
            return ST_FLUSH
        S.ints[I_POST] = 0
        if not _post_step(S):
            return ST_DEFECT
        return AGAIN
    if S.ints[I_MAXEV] >= 0 and S.ints[I_EVTOTAL] >= S.ints[I_MAXEV]:
        _unseal_at_end(S)
        return ST_EVENT_LIMIT
    return GO_ON


@kernel(inline="always")
def _next_collision(S, t):
    """The time of the next predicted collision of free balls (or a sealed one's end),
    inf if none; t itself if it is within the resolution of t (as _due takes it): the
    mirror image of a collision at this instant, its time rounded otherwise, is at this
    instant; a step that short moves no ball, and a contact closed now would neither
    press nor part in it."""
    if not _heap_valid_top(S):
        return np.inf
    tcol = S.hp_t[0]
    if tcol <= t + 4.0 * EPS * abs(t):
        return t
    return tcol


@kernel(inline="always")
def _collide(S, t):
    """Take the collision due at t off the heap: a sealed collision ends, or one begins
    (``_binary``), and COUNTED is returned; else the contact closes after this pass
    (AGAIN). Collisions at one instant close each contact at most a few times; more
    means states flipping back and forth, a defect reported (as by _settle) rather than
    run forever."""
    if S.ev_t.shape[0] - S.ints[I_NEV] < 2:
        return ST_FLUSH
    if t == S.fs[F_TSAME]:
        S.ints[I_NSAME] += 1
        if S.ints[I_NSAME] > 4 * S.cst.shape[0] + 64:
            return ST_DEFECT
    else:
        S.fs[F_TSAME] = t
        S.ints[I_NSAME] = 0
    j = S.hp_j[0]
    _heap_pop(S)
    nc = S.cst.shape[0]
    if j >= nc or (S.ints[I_PAIRS] == 1 and _seal(S, j)):
        if j >= nc:
            _sealed_end(S, j - nc)
        else:
            S.ints[I_NSEAL] += 1
        return COUNTED
    S.ints[I_EVJ] = j
    S.ints[I_EVK] = EV_CLOSE
    S.ints[I_POST] = 1
    return AGAIN


@kernel(inline="always")
def _fly(S, t, tn):
    """No cluster: every ball flies freely to tn, the next collision or the stop time."""
    S.fs[F_TPREV] = t
    S.fs[F_HLAST] = tn - t
    S.fs[F_T] = tn
    S.ints[I_JUMP] = 1


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
        return st
    if tay:
        hnext = S.fs[F_H]  # DOP853's proposal stands; the series sizes its own steps
    else:
        hnext = h * (10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 8.0)))
    if j >= 0:
        st = _land(S, t, h, err, hnext, th, j, kind, lev, tay)
        if st != GO_ON:
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
        if tay:
            # the series' truncation is known from h alone, and the event scan reads
            # the few balls it needs from their series: the window is evaluated at
            # h only if no event cuts the step (else at the event, by the landing)
            S.fs[F_HLAST] = h
            err = _taylor_error(S, h)
            S.ints[I_XEND] = 0
            th, j, kind, lev = _find_event(S)
            if j < 0 and h > 64.0 * EPS * max(1.0, abs(t)) and _grazes(S, h):
                # past a graze the series is not to be trusted (_grazes): halve
                # until the step ends before the compression's minimum or keeps
                # it above half its start
                h *= 0.5
                S.ints[I_REJ] += 1
                clipped = False
                continue
            if j < 0:
                err = _step(S, h)
        else:
            err = _step(S, h)
            S.fs[F_HLAST] = h
        if not np.isfinite(err):
            if h < 1e-12 * max(1.0, abs(t)) or not np.isfinite(h):
                # (an infinite step: a cluster whose forces all vanish, grown
                # without bound, would never end)
                return ST_NON_FINITE, h, err, clipped, th, j, kind, lev
            h *= 0.2
            S.ints[I_REJ] += 1
            clipped = False
            continue
        if not tay:
            th, j, kind, lev = _find_event(S)
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


@kernel(inline="always")
def _land(S, t, h, err, hnext, th, j, kind, lev, tay):
    """Redo the step of h to end on the event found at th h (contact j's kind at level
    lev), refined by Newton on the step itself. Returns GO_ON landed (the event waits
    in I_EVJ, I_EVK), AGAIN where the step is to be tried again shorter (the state
    restored to its start), or ST_STEP_UNDERFLOW."""
    hev = th * h
    landing = 0  # 1 landed, 2 the step failed its error test, 3 Newton gave up
    nit = 0
    while landing == 0:
        if not (_step(S, hev) <= 1.0):
            landing = 2
            break
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
            landing = 3  # the state stays that of the last step taken
            break
        hev += dh
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
    if landing == 3 and err > 1.0:
        # an event seen only on a failed step, and not there on a good one:
        # shrink the step as for any failed step
        _restore_start(S)
        S.fs[F_H] = h * max(0.2, 0.9 * err ** (-1.0 / (PT if tay else 8)))
        if tay:
            S.fs[F_HCAP] = S.fs[F_H]
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
