"""A step's consequences for the contacts: their states set from their motion.

After every accepted step (``_post_step``): the fresh contacts pressed beyond eps_rel
are seasoned, the event the step ended on is applied, quiet contacts are released,
dormant ones at a cluster's edge engage, and after a change of structure every event
due at that instant is applied until the states agree with the motion (``_settle``).
A contact's state is set from its event, never from the sign of its compression, which
is within rounding of 0 there (see ``_state``'s contact states).
"""

from __future__ import annotations

from chainrun.solver._clusters import _activate, _deactivate, _sync, _unseal_near_clusters
from chainrun.solver._compression import _pressed_in_step
from chainrun.solver._events import _load_rate, _log, _rounding
from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    ACTIVE, B_ACC, B_IM, C_ALPHA, C_DORM, C_EPS, C_ETA, C_HELD, C_KAPPA, DORMANT, EPS,
    EV_CLOSE, EV_ENGAGE, EV_OPEN, EV_RELEASE, EV_RELOAD, EV_UNLOAD, FRESH, F_FLOOR, F_H, F_T,
    F_TDEF, HI_ROW, I_DAMPED, I_DEFJ, I_DIRTY, I_EVJ, I_EVK, I_FORCED, I_JUMP, I_M, I_NCL,
    I_NEV, I_SEALED, I_TAY, OPEN, W_HELD, _flight, _free_at, _tw,
)
from chainrun.solver._steppers import _ball_now, _branch_step


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


@kernel(inline="always")
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
        _closing_cap(S, j)
        ok = _activate(S, j, ACTIVE)
        _log(S, t, j, EV_CLOSE)
    else:
        dormant = S.cst[j] == DORMANT
        ok = _activate(S, j, FRESH if dormant else ACTIVE)
        if not dormant:  # a dormant contact was closed already: nothing to log
            _log(S, t, j, EV_ENGAGE)
    return ok


#: ``_apply_event`` as a call, for the places that apply an event now and then (a
#: contact found due while settling, a damped contact's load switched, an unload that
#: opens): a copy inlined there would cost compile time and save nothing. The step's
#: own event, one per event of every line, keeps its copy (a call passes the State's
#: arrays part by part, about 100 ns).
_apply_event_call = kernel(getattr(_apply_event, "py_func", _apply_event))


@kernel(inline="always")
def _closing_cap(S, j):
    """Cap the next step where contact j closes now: the first step from a compression
    of 0 is sized for the closing (``_steppers._branch_step``). Not where a contact
    engages: a dormant one at a wave's front is pressed already (each of a clean wave's
    balls engages so, and the cap's arithmetic would cost it more than it saves), a
    slow press is slow."""
    _, vl, _ = _ball_now(S, j)
    _, vr, _ = _ball_now(S, j + 1)
    S.fs[F_H] = min(S.fs[F_H], _branch_step(S, j, vl - vr, False))


@kernel(inline="always")
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


@kernel(inline="always")
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


@kernel(inline="always")
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


@kernel(inline="always")
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
                    if not _apply_event_call(S, j, kind):
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
            w = S.V[p] - S.V[p + 1]
            held = S.cp[C_HELD, j] != 0.0
            if not held and w >= 0.0:
                continue  # bearing and pressing: a load of terms >= 0 cannot be below 0
            g, dg, _r = _load_rate(S, j, cj, w, S.A[p] - S.A[p + 1])
            if (held and g > 0.0 and dg > 0.0) or (not held and g < 0.0 and dg < 0.0):
                if S.ev_t.shape[0] - S.ints[I_NEV] < 1:
                    return  # (the log is full: the next pass switches it)
                _apply_event_call(S, j, EV_UNLOAD if not held else EV_RELOAD)


@kernel(inline="always")
def _post_step(S):
    """After an accepted step or jump: season contacts, then apply its event or release contacts."""
    if S.ints[I_JUMP] == 0 and S.ints[I_M] > 0:
        _season(S)
    parted = False
    jd = S.ints[I_DEFJ]
    if jd >= 0:
        # a held contact whose compression crossed 0 inside the step, and stayed below
        # (_events._find_event): it opens, logged at its crossing, before the step's
        # own event at the step's end
        S.ints[I_DEFJ] = -1
        _sync(S)
        if S.cst[jd] == ACTIVE and _due(S, jd) == EV_OPEN:
            if not _deactivate(S, jd, _engage_level(S, jd)):
                return False
            _log(S, S.fs[F_TDEF], jd, EV_OPEN)
            parted = True
    k = S.ints[I_EVK]
    if k != 0:
        S.ints[I_EVK] = 0
        if not parted:  # (synced then; the compact arrays no longer match the clusters)
            _sync(S)
        j = S.ints[I_EVJ]
        if not _apply_event(S, j, k):
            return False
        if k == EV_UNLOAD and _due(S, j) == EV_OPEN:
            # the load vanished with the compression (in a slow collision, whose
            # damping goes as c^beta): it opens now, or its balls, held without force,
            # would part with no crossing left for a step to find
            if not _apply_event_call(S, j, EV_OPEN):
                return False
    elif S.ints[I_M] > 0 and not parted:  # (parted: _settle, on the clusters now)
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
