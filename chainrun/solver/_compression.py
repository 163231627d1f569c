"""One contact's compression over the last step: its series, samples and bounds.

The event scan (``_events``) and the seasoning of fresh contacts (``_settle._season``)
ask where a contact's compression can go within a step without locating anything:
on a series step, from the series of the compression (``_contact_series``), sampled
(``_sample_series``) or bounded by its Bernstein coefficients (``_bernstein_range``);
on a DOP853 step, from the curvature at its ends (``_curvature_bound``).
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    B_ACC, C_EPS, DB, EPS, F_HLAST, F_TPREV, N_SERIES_SAMPLES, PT, _BERN, _free_at,
)


@kernel(inline="always")
def _series_at(T, s):
    """The polynomial sum_k T[k] s^k (Horner)."""
    y = T[PT]
    for k in range(PT - 1, -1, -1):
        y = y * s + T[k]
    return y


@kernel
def _contact_series(S, j):
    """The series of contact j's compression over the last (series) step into TD.

    A free ball's series is its parabola (a straight line without external force).
    """
    pa = S.bmap[j]
    pb = S.bmap[j + 1]
    TD, TX = S.TD, S.TX
    t0 = S.fs[F_TPREV]
    if pa >= 0:
        for k in range(PT + 1):
            TD[k] = TX[k, pa]
    else:
        for k in range(3, PT + 1):
            TD[k] = 0.0
        TD[0], TD[1] = _free_at(S, j, t0)
        TD[2] = 0.5 * S.bp[B_ACC, j]
    if pb >= 0:
        for k in range(PT + 1):
            TD[k] -= TX[k, pb]
    else:
        x, v = _free_at(S, j + 1, t0)
        TD[0] -= x
        TD[1] -= v
        TD[2] -= 0.5 * S.bp[B_ACC, j + 1]


@kernel
def _sample_series(S, ns, h):
    """TD's polynomial at s = h (i + 1) / ns, i < ns, into TS[1] (TS[0]: the s).

    All samples at once: independent Horner chains, which vectorise.
    """
    SS, YS, TD = S.TS[0], S.TS[1], S.TD
    for i in range(ns):
        SS[i] = (i + 1) / ns * h
        YS[i] = TD[PT]
    for k in range(PT - 1, -1, -1):
        tk = TD[k]
        for i in range(ns):
            YS[i] = YS[i] * SS[i] + tk


@kernel
def _bernstein_range(T, h, B):
    """Bounds of the polynomial sum_k T[k] s^k over s in [0, h] (B: scratch).

    The smallest and largest Bernstein coefficients of its terms up to degree DB
    (the values at the ends are the first and last), widened by the magnitude of the
    higher terms and by rounding. (R. T. Farouki, Computer Aided Geometric Design 29,
    2012: the Bernstein polynomial basis, a centennial retrospective.)
    """
    for i in range(DB + 1):
        B[i] = 0.0
    hk = 1.0
    tot = 0.0
    for k in range(DB + 1):
        a = T[k] * hk
        tot += abs(a)
        hk *= h
        for i in range(k, DB + 1):
            B[i] += _BERN[k, i] * a
    tail = 0.0
    for k in range(DB + 1, PT + 1):
        tail += abs(T[k]) * hk
        hk *= h
    lo = np.inf
    hi = -np.inf
    for i in range(DB + 1):
        lo = min(lo, B[i])
        hi = max(hi, B[i])
    r = tail + 64.0 * EPS * tot
    return lo - r, hi + r


@kernel
def _pressed_in_step(S, j):
    """Whether fresh contact j was pressed beyond eps_rel inside the last series step."""
    h = S.fs[F_HLAST]
    epsrel = S.cp[C_EPS, j]
    _contact_series(S, j)
    if _bernstein_range(S.TD, h, S.TS[0])[1] <= epsrel:
        return False
    ns = N_SERIES_SAMPLES
    _sample_series(S, ns, h)
    for i in range(ns):
        if S.TS[1, i] > epsrel:
            return True
    return False


@kernel
def _curvature_bound(S, j):
    """A bound on |c''| of contact j over the last (DOP853) step: the larger of |c''| at
    its two ends (the step is short)."""
    pa = S.bmap[j]
    pb = S.bmap[j + 1]
    ga = S.bp[B_ACC, j]
    gb = S.bp[B_ACC, j + 1]
    g0 = (S.A0[pa] if pa >= 0 else ga) - (S.A0[pb] if pb >= 0 else gb)
    g1 = (S.A[pa] if pa >= 0 else ga) - (S.A[pb] if pb >= 0 else gb)
    return max(abs(g0), abs(g1))


@kernel
def _stays_open(T, h, level, floor, D, B):
    """Whether an open contact whose compression is sum_k T[k] s^k can neither close nor
    engage for s in [0, h] (D, B: scratch).

    It closes only where its compression c reaches 0 at a rate of at least the floor,
    and engages only where c reaches its level (> 0). Upper bounds of c and of c' over
    [0, h] are the sums of their series' positive terms, and, where that of c' is not
    below the floor, the Bernstein bound of c' (_bernstein_range): behind a Hertz wave
    the ball just released and its cluster's first ball touch within rounding and part
    at rates far below the floor, and c' is a sum of large terms of both signs that
    cancel, which only the second bound sees.
    """
    cmax = T[0]
    cabs = abs(T[0])
    wmax = T[1]
    wabs = abs(T[1])
    hk1 = 1.0  # h^(k-1)
    for k in range(1, PT + 1):
        a = T[k] * hk1 * h
        cmax += max(a, 0.0)
        cabs += abs(a)
        if k >= 2:
            b = k * T[k] * hk1
            wmax += max(b, 0.0)
            wabs += abs(b)
        hk1 *= h
    cmax += 64.0 * EPS * cabs
    wmax += 64.0 * EPS * wabs
    if not cmax < level:
        return False
    if cmax < 0.0 or wmax < floor:
        return True
    for k in range(PT):
        D[k] = (k + 1) * T[k + 1]
    D[PT] = 0.0
    return _bernstein_range(D, h, B)[1] < floor
