"""The drives in the kernels: prescribed motions of walls and forces on balls.

A drive (``drive.Drive``) is a function u(t), analytic on each of its pieces: a sum of
terms ``p(s) sin(omega s + phi)``, s the time since the piece began, p of degree <= 5,
kept past the State's scalar slots (``_state``: a line without drives pays nothing).
A moving wall's position is its place plus u(t) (``DRIVE_POSITION``); a driven ball's
acceleration gains u(t), its force over its mass (``DRIVE_FORCE``). Both enter the steppers as accelerations known in time: a
wall, of inverse mass 0, gets u''(t), so its position in a step is that of u to the
step's accuracy, and it is set to u exactly at every step's ends (``_drive_ends``).

A driven ball is never free: it is always in the window, alone in a cluster of its
own when no contact joins it to another (``_pinned``), so every contact it makes or
breaks is found by the step's event scan, as at any cluster's edge. Every step starts
in one piece of each drive and ends at the next piece's start (``_drive_begin``), so
the series and the stages see a function analytic over the whole step:

* the Taylor series: u's own series at the step's start (``_drive_series``, exact:
  the polynomial's Taylor coefficients times those of the sine) added to the
  positions' at each order (``_drive_terms``);
* DOP853: u at each stage's time (``_drive_stage``).

The work the drives do, ``int F_L w_L' dt - int F_R w_R' dt + sum_i int d_i v_i dt``
(a wall's force on the line times its velocity, a driven ball's force times its own),
is summed over each step as the damping's dissipation is: with DOP853's weights over
its stages, or, on a series step, as the integral of the product of the force's and
the velocity's series (``_series_work``), exact to the series' order.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    DRIVE_POSITION, DV_BALL, DV_HI, DV_KIND, DV_ROW, F_NFLOAT, I_DCUR, I_DQ, I_DT, I_LWL,
    I_MODE, I_NDRIVE, I_NINT, I_PCQ, I_PCT, I_RWL, MODE_LINEAR, PT, _tw,
)
# the fields of a term: the polynomial's coefficients c0..c5, omega, phi
from chainrun.solver.drive import TERM


# ---- where a drive's numbers are (see _state: past the scalar slots) ------------------


@kernel(inline="always")
def _dv(S, d, field):
    """Field DV_* of drive d."""
    return S.ints[I_NINT + DV_ROW * d + field]


@kernel(inline="always")
def _piece(S, d):
    """The piece of drive d in force."""
    return S.ints[S.ints[I_DCUR] + 2 * d]


@kernel(inline="always")
def _place(S, d):
    """The compact index of drive d's ball."""
    return S.ints[S.ints[I_DCUR] + 2 * d + 1]


@kernel(inline="always")
def _dm(S, d):
    """The mass drive d drives (a force), or its wall's place (a position)."""
    return S.fs[F_NFLOAT + d]


@kernel(inline="always")
def _dvs(S, d):
    """The index in fs of drive d's stage velocity."""
    return F_NFLOAT + S.ints[I_NDRIVE] + d


@kernel(inline="always")
def _dt(S, d, k):
    """The index in fs of drive d's term of order k of the positions' series."""
    return S.ints[I_DT] + (PT + 1) * d + k


@kernel(inline="always")
def _pinned(S, b):
    """Whether ball b is driven: it is never free."""
    for d in range(S.ints[I_NDRIVE]):
        if _dv(S, d, DV_BALL) == b:
            return True
    return False


@kernel
def _drive_at(S, d, t):
    """(u, u', u'') of drive d at time t, on its piece in force."""
    seg = _piece(S, d)
    x = t - S.fs[S.ints[I_PCT] + seg]
    u = 0.0
    du = 0.0
    ddu = 0.0
    q0 = S.ints[S.ints[I_PCQ] + 2 * seg]
    q1 = S.ints[S.ints[I_PCQ] + 2 * seg + 1]
    for q in range(q0, q1):
        o = S.ints[I_DQ] + TERM * q
        c0 = S.fs[o]
        c1 = S.fs[o + 1]
        c2 = S.fs[o + 2]
        c3 = S.fs[o + 3]
        c4 = S.fs[o + 4]
        c5 = S.fs[o + 5]
        om = S.fs[o + 6]
        p0 = ((((c5 * x + c4) * x + c3) * x + c2) * x + c1) * x + c0
        p1 = (((5.0 * c5 * x + 4.0 * c4) * x + 3.0 * c3) * x + 2.0 * c2) * x + c1
        p2 = ((20.0 * c5 * x + 12.0 * c4) * x + 6.0 * c3) * x + 2.0 * c2
        th = om * x + S.fs[o + 7]
        sn = np.sin(th)
        cs = np.cos(th)
        u += p0 * sn
        du += p1 * sn + p0 * om * cs
        ddu += p2 * sn + 2.0 * p1 * om * cs - p0 * om * om * sn
    return u, du, ddu


@kernel
def _drive_series(S, t):
    """Each drive's terms of the positions' series at time t, orders 2..PT (_dt).

    u's Taylor coefficients u_k at t: on each term, those of the polynomial at t
    (p_i, i <= 5) times those of the sine, omega^k / k! sin(theta + k pi / 2), summed
    as a product of series. A wall's position gains u_k at order k; a driven ball's,
    u_k / ((k + 1)(k + 2)) at order k + 2 (its acceleration's series).
    """
    fs = S.fs
    for d in range(S.ints[I_NDRIVE]):
        r0 = _dt(S, d, 0)
        for k in range(PT + 1):
            fs[r0 + k] = 0.0
        seg = _piece(S, d)
        x = t - fs[S.ints[I_PCT] + seg]
        q0 = S.ints[S.ints[I_PCQ] + 2 * seg]
        q1 = S.ints[S.ints[I_PCQ] + 2 * seg + 1]
        for q in range(q0, q1):
            o = S.ints[I_DQ] + TERM * q
            c0 = fs[o]
            c1 = fs[o + 1]
            c2 = fs[o + 2]
            c3 = fs[o + 3]
            c4 = fs[o + 4]
            c5 = fs[o + 5]
            om = fs[o + 6]
            # the polynomial's Taylor coefficients at x (repeated synthetic division)
            p0 = ((((c5 * x + c4) * x + c3) * x + c2) * x + c1) * x + c0
            p1 = (((5.0 * c5 * x + 4.0 * c4) * x + 3.0 * c3) * x + 2.0 * c2) * x + c1
            p2 = ((10.0 * c5 * x + 6.0 * c4) * x + 3.0 * c3) * x + c2
            p3 = (10.0 * c5 * x + 4.0 * c4) * x + c3
            p4 = 5.0 * c5 * x + c4
            p5 = c5
            th = om * x + fs[o + 7]
            sn = np.sin(th)
            cs = np.cos(th)
            f = 1.0  # omega^k / k!
            for k in range(PT + 1):
                r = k % 4
                sk = f * (sn if r == 0 else cs if r == 1 else -sn if r == 2 else -cs)
                fs[r0 + k] += p0 * sk
                if k + 1 <= PT:
                    fs[r0 + k + 1] += p1 * sk
                if k + 2 <= PT:
                    fs[r0 + k + 2] += p2 * sk
                if k + 3 <= PT:
                    fs[r0 + k + 3] += p3 * sk
                if k + 4 <= PT:
                    fs[r0 + k + 4] += p4 * sk
                if k + 5 <= PT:
                    fs[r0 + k + 5] += p5 * sk
                f *= om / (k + 1)
        if _dv(S, d, DV_KIND) != DRIVE_POSITION:
            for k in range(PT - 2, -1, -1):
                fs[r0 + k + 2] = fs[r0 + k] / ((k + 1) * (k + 2))
        fs[r0] = 0.0
        fs[r0 + 1] = 0.0


@kernel
def _drive_terms(TX, r, DT, DC):
    """Add each drive's term of order r (DT, PT + 1 a drive) to its ball's row r of the
    series (DC: each drive's piece and its ball's compact index)."""
    for d in range(DC.shape[0] // 2):
        TX[r, DC[2 * d + 1]] += DT[(PT + 1) * d + r]


@kernel
def _drive_stage(S, row, F, t, wgt, add):
    """At time t: add each drive's acceleration to its ball's entry of ``row`` (if
    ``add``), and return ``wgt`` times the drives' power, from the forces of the
    contact lanes F (a wall's) and the stage velocities (a driven ball's, _dvs)."""
    power = 0.0
    for d in range(S.ints[I_NDRIVE]):
        u, du, ddu = _drive_at(S, d, t)
        p = _place(S, d)
        if _dv(S, d, DV_KIND) == DRIVE_POSITION:
            if add:
                row[p] += ddu
            if wgt != 0.0:
                if _dv(S, d, DV_BALL) == 0:
                    lane = S.ints[I_LWL]
                    if lane >= 0:
                        power += F[lane] * du
                else:
                    lane = S.ints[I_RWL]
                    if lane >= 0:
                        power -= F[lane] * du
        else:
            if add:
                row[p] += u
            if wgt != 0.0:
                power += _dm(S, d) * u * S.fs[_dvs(S, d)]
    return wgt * power


@kernel
def _drive_band(S, row, t, qa, qb):
    """Add the accelerations of the drives whose balls are compact balls qa..qb to
    ``row`` at time t (an extra dense stage on a band of balls)."""
    for d in range(S.ints[I_NDRIVE]):
        p = _place(S, d)
        if qa <= p <= qb:
            u, du, ddu = _drive_at(S, d, t)
            row[p] += ddu if _dv(S, d, DV_KIND) == DRIVE_POSITION else u


@kernel
def _drive_ends(S, t):
    """Put each moving wall exactly where its motion has it at time t (the step's end):
    its place plus u, velocity u', acceleration u''."""
    for d in range(S.ints[I_NDRIVE]):
        if _dv(S, d, DV_KIND) == DRIVE_POSITION:
            u, du, ddu = _drive_at(S, d, t)
            p = _place(S, d)
            S.X[p] = _dm(S, d) + u
            S.V[p] = du
            S.A[p] = ddu


@kernel
def _drive_begin(S, t):
    """At a step's start t: each drive on its piece containing t (a driven ball's
    acceleration moved from the piece just left to this one), the walls where their
    motions have them; returns the next breakpoint (inf if none)."""
    tb = np.inf
    pct = S.ints[I_PCT]
    for d in range(S.ints[I_NDRIVE]):
        seg = _piece(S, d)
        hi = _dv(S, d, DV_HI)
        if seg + 1 < hi and S.fs[pct + seg + 1] <= t:
            old = _drive_at(S, d, t)[0]
            while seg + 1 < hi and S.fs[pct + seg + 1] <= t:
                seg += 1
            S.ints[S.ints[I_DCUR] + 2 * d] = seg
            if _dv(S, d, DV_KIND) != DRIVE_POSITION:
                S.A[_place(S, d)] += _drive_at(S, d, t)[0] - old
        if seg + 1 < hi:
            tb = min(tb, S.fs[pct + seg + 1])
    _drive_ends(S, t)
    return tb


@kernel
def _drive_place(S):
    """After the window is packed: each drive's compact index."""
    for d in range(S.ints[I_NDRIVE]):
        S.ints[S.ints[I_DCUR] + 2 * d + 1] = S.bmap[_dv(S, d, DV_BALL)]


@kernel
def _series_work(S, h):
    """The drives' work over [0, h] of a series step, from the series: the integral
    of the product of the force's series (a wall's contact lane, or a driven ball's
    drive; to order PT - 2) and the velocity's (the wall's, or the ball's; to order
    PT - 1), every product kept: where the force starts at a high order (a ramp's start)
    a product cut at order PT - 2 would drop terms far above the series' truncation."""
    W = S.TW
    f0 = PT + 1  # row of the forces' f_0
    linear = S.ints[I_MODE] == MODE_LINEAR  # (its force is kappa c: the rows c_k)
    total = 0.0
    for d in range(S.ints[I_NDRIVE]):
        p = _place(S, d)
        sign = 1.0
        lane = -1
        if _dv(S, d, DV_KIND) == DRIVE_POSITION:
            if _dv(S, d, DV_BALL) == 0:
                lane = S.ints[I_LWL]
            else:
                lane = S.ints[I_RWL]
                sign = -1.0
            if lane < 0:
                continue
        mk = S.TR[lane] if lane >= 0 else 0.0
        w = 0.0
        hi = h  # h^(i + 1)
        for i in range(PT - 1):
            if lane >= 0:
                fi = W[_tw(lane, i)] * mk if linear else W[_tw(lane, f0 + i)]
            else:
                fi = _dm(S, d) * S.fs[_dt(S, d, i + 2)] * ((i + 1) * (i + 2))
            if fi != 0.0:
                # sum_j v_j h^j / (i + j + 1), v_j = (j + 1) TX[j + 1]: the integral of
                # f_i s^i times the velocity's series, over h^(i + 1)
                acc = 0.0
                for j in range(PT - 1, -1, -1):
                    acc = acc * h + (j + 1) * S.TX[j + 1, p] / (i + j + 1)
                w += fi * acc * hi
            hi *= h
        total += sign * w
    return total
