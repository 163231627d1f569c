"""The heap of predicted collisions between free balls.

Free pairs approaching at >= floor are predicted analytically (``_schedule_pair``)
and kept in a binary heap ordered by time. An entry is invalidated lazily: it carries
its contact's stamp, and any change to either ball bumps the stamp
(``_clusters._touch_ball``), so a stale entry is dropped when it reaches the top.
The ends of sealed collisions (``_pairs``) share the heap: their entries carry
j + N - 1 for contact j, and its stamp.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._pairs import _clear_of, _sealed_contact
from chainrun.solver._state import (
    B_ACC, F_FLOOR, F_T, I_NHEAP, I_SEALED, SEALED, SL_T0, SL_TAU, _find_cluster, _free_at,
)


@kernel(inline="always")
def _entry_contact(S, e):
    """The contact a heap entry's hp_j names (a sealed collision's end or a meeting)."""
    nc = S.cst.shape[0]
    return e - nc if e >= nc else e


@kernel
def _heap_push(S, t, j):
    n = S.ints[I_NHEAP]
    if n >= S.hp_t.shape[0]:
        _heap_compact(S)
        n = S.ints[I_NHEAP]
        if n >= S.hp_t.shape[0]:
            return
    i = n
    S.hp_t[i] = t
    S.hp_j[i] = j
    S.hp_s[i] = S.stamp[_entry_contact(S, j)]
    S.ints[I_NHEAP] = n + 1
    while i > 0:
        q = (i - 1) // 2
        if S.hp_t[q] <= S.hp_t[i]:
            break
        _heap_swap(S, i, q)
        i = q


@kernel(inline="always")
def _heap_swap(S, a, b):
    S.hp_t[a], S.hp_t[b] = S.hp_t[b], S.hp_t[a]
    S.hp_j[a], S.hp_j[b] = S.hp_j[b], S.hp_j[a]
    S.hp_s[a], S.hp_s[b] = S.hp_s[b], S.hp_s[a]


@kernel(inline="always")
def _sift_down(S, i, n):
    """Move entry i of a heap of n entries down to its place."""
    while True:
        l = 2 * i + 1
        if l >= n:
            break
        r = l + 1
        c = l
        if r < n and S.hp_t[r] < S.hp_t[l]:
            c = r
        if S.hp_t[i] <= S.hp_t[c]:
            break
        _heap_swap(S, i, c)
        i = c


@kernel
def _heap_pop(S):
    n = S.ints[I_NHEAP] - 1
    S.ints[I_NHEAP] = n
    if n == 0:
        return
    _heap_swap(S, 0, n)
    _sift_down(S, 0, n)


@kernel
def _heap_valid_top(S):
    """Drop stale entries; return whether a valid entry is on top."""
    while S.ints[I_NHEAP] > 0:
        if S.hp_s[0] == S.stamp[_entry_contact(S, S.hp_j[0])]:
            return True
        _heap_pop(S)
    return False


@kernel
def _heap_compact(S):
    n = S.ints[I_NHEAP]
    k = 0
    for i in range(n):
        j = S.hp_j[i]
        if S.hp_s[i] == S.stamp[_entry_contact(S, j)]:
            S.hp_t[k] = S.hp_t[i]
            S.hp_j[k] = j
            S.hp_s[k] = S.hp_s[i]
            k += 1
    S.ints[I_NHEAP] = k
    # re-heapify
    for i in range(k // 2 - 1, -1, -1):
        _sift_down(S, i, k)


@kernel(inline="always")
def _schedule_pair(S, j):
    """Predict the collision of free balls j, j+1, if they ever meet approaching at >= floor.

    Without external forces their gap closes at a constant rate; with them it is a
    parabola, c(s) = c + w s + a s^2 / 2 (even for balls parting now: pressed together,
    they meet again), and the collision is where it crosses 0 upwards (roots by the
    stable form of the quadratic formula). A meeting slower than the floor is no
    collision, unless the balls are pressed together (a > 0), when it is one; balls
    overlapped and pressed together before their overlap ends meet now.

    A ball in a sealed collision meets its neighbour only after it ends, when the
    pair is scheduled again; until then the neighbour must stay clear of the pair.
    Returns the sealed contact it may reach, to be integrated from now, or -1.
    """
    if j < 0 or j >= S.cst.shape[0] or S.bmap.shape[0] < 2 or S.cst[j] == SEALED:
        return -1
    if _find_cluster(S, j) >= 0 or _find_cluster(S, j + 1) >= 0:
        return -1
    t = S.fs[F_T]
    if S.ints[I_SEALED] > 0:
        for b, a in ((j, j + 1), (j + 1, j)):
            js = _sealed_contact(S, b)
            if js >= 0:
                if _clear_of(S, js, a, t, S.sl[SL_T0, js] + S.sl[SL_TAU, js]):
                    return -1
                return js
    floor = S.fs[F_FLOOR]
    ga = S.bp[B_ACC, j]
    gb = S.bp[B_ACC, j + 1]
    if ga == 0.0 and gb == 0.0:
        w = S.bv[j] - S.bv[j + 1]
        if not (w >= floor):
            return -1
        c = (S.bx[j] + S.bv[j] * (t - S.bt[j])) - (S.bx[j + 1] + S.bv[j + 1] * (t - S.bt[j + 1]))
        tc = t - c / w if c < 0.0 else t
        _heap_push(S, tc, j)
        return -1
    xl, vl = _free_at(S, j, t)
    xr, vr = _free_at(S, j + 1, t)
    c = xl - xr
    w = vl - vr
    a = ga - gb
    if c >= 0.0 and (w >= floor or (w >= 0.0 and a > 0.0)):
        _heap_push(S, t, j)
        return -1
    if a == 0.0:  # (the same acceleration: they close at a constant rate)
        if c < 0.0 and w >= floor:
            _heap_push(S, t - c / w, j)
        return -1
    d = w * w - 2.0 * a * c
    q = -0.5 * (w + np.copysign(np.sqrt(d), w))  # roots q / (a/2) and c / q
    if not (d >= 0.0 and q != 0.0):
        if c >= 0.0 and a > 0.0:
            _heap_push(S, t, j)  # overlapped, and pressed together before they part
        return -1  # the gap never closes
    r1 = q / (0.5 * a)
    r2 = c / q
    # the gap closes where it crosses 0 upwards: through the larger root when the
    # relative acceleration presses the balls together, else the smaller
    s = max(r1, r2) if a > 0.0 else min(r1, r2)
    if not (s >= 0.0 and (w + a * s >= floor or a > 0.0)):
        return -1
    _heap_push(S, t + s, j)
    return -1
