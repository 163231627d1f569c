"""Cluster bookkeeping: which balls move together, and their compact arrays.

The clusters are a small list sorted by their first ball (``clo``, ``chi``). A
contact that becomes active joins the clusters or balls on its two sides
(``_activate``); one that becomes inactive splits its cluster and frees the balls
left alone (``_deactivate``). After any change ``_rebuild`` packs the clusters' balls
into the compact arrays that the steppers integrate, and schedules the freed balls'
collisions with their free neighbours (``_heap``). A sealed collision (``_pairs``)
that a cluster or a freed ball could reach is taken into the integration
(``_unseal``). A driven ball (``_drive``) is never freed: left alone, it is a cluster
of its own.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._drive import _drive_place, _drive_stage, _pinned
from chainrun.solver._forces import _rhs, _span_accelerations
from chainrun.solver._heap import _schedule_pair
from chainrun.solver._jit import kernel
from chainrun.solver._pairs import (
    _damped_seal, _fractions, _sealed_at, _sealed_contact, _sealed_lost,
)
from chainrun.solver._projection import _cluster_energy, _project_energy
from chainrun.solver._state import (
    ACTIVE, B_ACC, B_IM, B_MASS, C_ALPHA, C_BETA, C_DISS, C_ETA, C_HELD, C_KAPPA, F_ALPHA,
    F_DISS, F_JL, F_JR, F_T, I_DAMPED, I_DENSE, I_DIRTY, I_DRIVEN, I_DSTAMP, I_LWALL, I_LWL,
    I_M, I_MAXWIN, I_MODE, I_NCL, I_NFREED, I_RWALL, I_RWL, I_SEALED, I_UNIT, OPEN, SEALED,
    SL_PH, SL_V, SL_W, W_ACC, W_ALPHA, W_BETA, W_ETA, W_HELD, W_IM, W_MASS, _find_cluster,
    _free_at,
)


@kernel
def _sync(S):
    """Write the compact state back to the balls (all at the current time), before a
    change of structure: each cluster that the change removes is projected back to its
    energy then (``_remove_cluster``)."""
    t = S.fs[F_T]
    for p in range(S.ints[I_M]):
        b = S.cb[p]
        S.bx[b] = S.X[p]
        S.bv[b] = S.V[p]
        S.bt[b] = t


@kernel
def _remove_cluster(S, c):
    """Take cluster c off the list (merged, split or left alone). One packed into the
    compact arrays has its energy projected back to its value when it formed
    (``_projection``), and its balls take the projected velocities (they are synced)."""
    o = S.coff[c]
    if o >= 0 and _project_energy(S, c):
        for b in range(S.clo[c], S.chi[c] + 1):
            S.bv[b] = S.V[o + b - S.clo[c]]
    n = S.ints[I_NCL]
    for i in range(c, n - 1):
        S.clo[i] = S.clo[i + 1]
        S.chi[i] = S.chi[i + 1]
        S.coff[i] = S.coff[i + 1]
        S.cen[i] = S.cen[i + 1]
    S.ints[I_NCL] = n - 1


@kernel
def _insert_cluster(S, lo, hi):
    """Put cluster lo..hi on the list, not yet packed (coff -1: ``_rebuild`` packs it
    and measures its energy)."""
    n = S.ints[I_NCL]
    if n >= S.clo.shape[0]:
        return False
    i = n
    while i > 0 and S.clo[i - 1] > lo:
        S.clo[i] = S.clo[i - 1]
        S.chi[i] = S.chi[i - 1]
        S.coff[i] = S.coff[i - 1]
        S.cen[i] = S.cen[i - 1]
        i -= 1
    S.clo[i] = lo
    S.chi[i] = hi
    S.coff[i] = -1
    S.ints[I_NCL] = n + 1
    return True


@kernel(inline="always")
def _touch_ball(S, b):
    """Invalidate predictions involving ball b."""
    if b - 1 >= 0:
        S.stamp[b - 1] += 1
    if b < S.stamp.shape[0]:
        S.stamp[b] += 1


@kernel
def _free_ball(S, b):
    S.sep_t[b] = S.fs[F_T]
    S.sep_v[b] = S.bv[b]
    S.bmap[b] = -1
    _touch_ball(S, b)
    n = S.ints[I_NFREED]
    if n < S.freed.shape[0]:
        S.freed[n] = b
        S.ints[I_NFREED] = n + 1


@kernel
def _alone(S, b):
    """Ball b has lost its last contact: it flies freely, or, driven, stays integrated
    as a cluster of its own (its separation is recorded alike)."""
    if S.ints[I_DRIVEN] == 1 and _pinned(S, b):
        S.sep_t[b] = S.fs[F_T]
        S.sep_v[b] = S.bv[b]
        return _insert_cluster(S, b, b)
    _free_ball(S, b)
    return True


@kernel
def _activate(S, j, state):
    """Make contact j active, joining the clusters/balls on both sides."""
    S.cst[j] = state
    if S.ints[I_DAMPED] == 1:
        S.cp[C_HELD, j] = 0.0
    cl = _find_cluster(S, j)
    cr = _find_cluster(S, j + 1)
    lo = j
    hi = j + 1
    if cl >= 0:
        lo = S.clo[cl]
    else:
        _touch_ball(S, j)
    if cr >= 0:
        hi = S.chi[cr]
        _remove_cluster(S, cr)
    else:
        _touch_ball(S, j + 1)
    if cl >= 0:
        _remove_cluster(S, cl)
    ok = _insert_cluster(S, lo, hi)
    S.ints[I_DIRTY] = 1
    return ok


@kernel
def _deactivate(S, j, level):
    """Make contact j inactive (engages again beyond ``level``), splitting its cluster."""
    S.cst[j] = OPEN
    S.lvl[j] = level
    if S.ints[I_DAMPED] == 1:
        S.cp[C_HELD, j] = 0.0
    c = _find_cluster(S, j)
    if c < 0:
        return True
    lo = S.clo[c]
    hi = S.chi[c]
    _remove_cluster(S, c)
    ok = True
    if j > lo:
        ok = ok and _insert_cluster(S, lo, j)
    else:
        ok = _alone(S, j) and ok
    if j + 1 < hi:
        ok = ok and _insert_cluster(S, j + 1, hi)
    else:
        ok = _alone(S, j + 1) and ok
    S.ints[I_DIRTY] = 1
    return ok


@kernel
def _unseal(S, j):
    """Integrate sealed contact j from now: its balls take their exact state at this
    instant, and the contact becomes an active one of a new cluster (it was logged
    closed when sealed)."""
    t = S.fs[F_T]
    xl, vl = _sealed_at(S, j, j, t)
    xr, vr = _sealed_at(S, j, j + 1, t)
    S.bx[j] = xl
    S.bv[j] = vl
    S.bt[j] = t
    S.bx[j + 1] = xr
    S.bv[j + 1] = vr
    S.bt[j + 1] = t
    # the impulse a wall gave so far: the momentum its ball has gained since it came
    # in (the integration adds the rest)
    v = S.sl[SL_V, j]
    w = S.sl[SL_W, j]
    fl, fr = _fractions(S, j)
    if j == 0 and S.ints[I_LWALL] == 1:
        S.fs[F_JL] += S.bp[B_MASS, j + 1] * (vr - (v - fr * w))
    if j + 1 == S.bx.shape[0] - 1 and S.ints[I_RWALL] == 1:
        S.fs[F_JR] += S.bp[B_MASS, j] * ((v + fl * w) - vl)
    # a damped contact: the energy dissipated so far, and its force held at 0 past
    # its unload (the integration dissipates the rest)
    held = False
    if _damped_seal(S, j):
        lost = _sealed_lost(S, j, t)
        S.cp[C_DISS, j] += lost
        S.fs[F_DISS] += lost
        held = S.sl[SL_PH, j] != 0.0
    S.cst[j] = OPEN
    S.ints[I_SEALED] -= 1
    ok = _activate(S, j, ACTIVE)
    if held:
        S.cp[C_HELD, j] = 1.0
    return ok


@kernel
def _unseal_at_end(S):
    """At the run's end, take back a sealed contact with a wall, so that the impulse
    the wall has given so far is counted, and on a damped line every sealed contact,
    so that the energy dissipated so far is (a sealed contact counts them when it
    ends)."""
    nc = S.cst.shape[0]
    if S.ints[I_SEALED] > 0 and S.ints[I_DAMPED] == 1:
        for j in range(nc):
            if S.cst[j] == SEALED:
                _unseal(S, j)
    if S.ints[I_LWALL] == 1 and S.cst[0] == SEALED:
        _unseal(S, 0)
    if S.ints[I_RWALL] == 1 and S.cst[nc - 1] == SEALED:
        _unseal(S, nc - 1)


@kernel
def _unseal_near_clusters(S):
    """Integrate the sealed contacts next to a cluster: the cluster's edge ball is
    not in free flight, and only a free neighbour can be kept clear of a pair."""
    again = S.ints[I_SEALED] > 0
    while again:
        again = False
        for c in range(S.ints[I_NCL]):
            for b in (S.clo[c] - 1, S.chi[c] + 1):
                if b < 0 or b >= S.bx.shape[0]:
                    continue
                js = _sealed_contact(S, b)
                if js >= 0:
                    _unseal(S, js)
                    again = True
                    break
            if again:
                break


@kernel(inline="always")
def _rebuild(S):
    """Pack the clusters' balls into the compact arrays; 0 if done, else the size needed.

    A cluster packed before keeps its accelerations and the energy it formed with; a
    new one (``coff`` -1) has them computed: an event costs the clusters it touches.
    On a damped or driven line every acceleration is computed again (a damped contact
    switched to or from its held force, or a drive's term, changes them in place).
    """
    if S.ints[I_SEALED] > 0:
        _unseal_near_clusters(S)
    ncl = S.ints[I_NCL]
    m = 0
    for c in range(ncl):
        m += S.chi[c] - S.clo[c] + 1
    if m > S.X.shape[0]:
        return m
    for p in range(S.ints[I_M]):
        S.bmap[S.cb[p]] = -1
        S.A0[p] = S.A[p]  # (the clusters kept move in the compact arrays)
    t = S.fs[F_T]
    p = 0
    for c in range(ncl):
        old = S.coff[c]
        S.coff[c] = p
        if old < 0:
            S.cen[c] = np.nan  # (measured below, once its lanes are set)
        for b in range(S.clo[c], S.chi[c] + 1):
            S.cb[p] = b
            S.X[p], S.V[p] = _free_at(S, b, t)
            if old >= 0:
                S.A[p] = S.A0[old + b - S.clo[c]]
            S.bmap[b] = p
            S.WP[W_IM, p] = S.bp[B_IM, b]
            S.WP[W_ACC, p] = S.bp[B_ACC, b]
            S.WP[W_MASS, p] = S.bp[B_MASS, b]
            p += 1
    S.ints[I_M] = m
    if m > S.ints[I_MAXWIN]:
        S.ints[I_MAXWIN] = m
    # contact lanes: their stiffness inside a cluster, 0 from a cluster's last ball to
    # the next's first, with their exponents (a lane without force, and the series'
    # spare lanes, need only a finite one)
    damped = S.ints[I_DAMPED] == 1
    for p in range(m):
        S.TR[p] = 0.0
        S.WP[W_ALPHA, p] = 1.0
        S.WP[W_ETA, p] = 0.0
        S.WP[W_BETA, p] = 0.0
        S.WP[W_HELD, p] = 0.0
    for c in range(ncl):
        for p in range(S.coff[c], S.coff[c] + S.chi[c] - S.clo[c]):
            j = S.cb[p]
            S.TR[p] = S.cp[C_KAPPA, j]
            S.WP[W_ALPHA, p] = S.cp[C_ALPHA, j]
            if damped:  # (cp has the damping's rows on a damped line only)
                S.WP[W_ETA, p] = S.cp[C_ETA, j]
                S.WP[W_BETA, p] = S.cp[C_BETA, j]
                S.WP[W_HELD, p] = S.cp[C_HELD, j]
    # the lanes to the walls, whose forces the steps sum into the walls' impulses: a
    # wall's lane where its contact is in its cluster (a moving wall may be alone)
    last = S.bx.shape[0] - 1
    pl = S.bmap[0]
    pr = S.bmap[last] - 1
    S.ints[I_LWL] = pl if S.ints[I_LWALL] == 1 and pl >= 0 and S.TR[pl] != 0.0 else -1
    S.ints[I_RWL] = pr if S.ints[I_RWALL] == 1 and pr >= 0 and S.TR[pr] != 0.0 else -1
    whole = damped or S.ints[I_DRIVEN] == 1
    for c in range(ncl):
        if np.isnan(S.cen[c]):
            S.cen[c] = _cluster_energy(S, c)
            if not whole:
                _span_accelerations(S.X, S.FS, S.TR, S.WP, S.A, S.coff[c],
                                    S.coff[c] + S.chi[c] - S.clo[c], S.ints[I_MODE],
                                    S.fs[F_ALPHA], S.ints[I_UNIT] == 1)
    if whole:
        _rhs(S, S.X, S.V, S.A)
    if S.ints[I_DRIVEN] == 1:
        _drive_place(S)
        _drive_stage(S, S.A, S.FS, t, 0.0, True)
    S.ints[I_DIRTY] = 0
    S.ints[I_DENSE] = 0
    S.ints[I_DSTAMP] += 1
    # balls that just lost their last contact may be on course to hit a free neighbour
    # (or to reach a sealed pair, which then joins the integration: packed again)
    for i in range(S.ints[I_NFREED]):
        b = S.freed[i]
        for j in (b - 1, b):
            js = _schedule_pair(S, j)
            if js >= 0:
                _unseal(S, js)
    S.ints[I_NFREED] = 0
    return 0
