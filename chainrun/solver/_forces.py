"""The force law of the kernels: contact forces, accelerations and contact energy.

Between events the active set is fixed, so the right-hand side is smooth: an active
contact j carries ``kappa_j f(c)`` with ``f(c) = c |c|^(alpha_j-1)``, which is the
force for ``c > 0`` and its odd continuation beyond (for alpha = 1 exactly linear), so
a step that ends on an opening sees no kink. ``mode`` picks the law's loop
(``_state.MODE_*``): every contact linear, every contact Hertz, every contact one
other alpha, or each its own. A ball's acceleration is its net contact force over its
mass, plus that of its external force; a wall's inverse mass is 0.

A damped lane (damping eta > 0) adds ``eta |c|^beta w``, w the rate of its compression,
and its force is held at 0 from where that sum would pull: the switches are events
(``_events._unload_event``), so inside a step the force is smooth.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    C_ALPHA, C_KAPPA, F_ALPHA, I_DAMPED, I_M, I_MODE, I_UNIT, MODE_HERTZ, MODE_LINEAR, MODE_MIXED,
    MODE_POWER, W_ACC, W_ALPHA, W_BETA, W_ETA, W_HELD, W_IM,
)


@kernel(inline="always")
def _force(c, mode, alpha):
    """The force law of unit stiffness, odd-continued: c |c|^(alpha-1)."""
    if mode == MODE_LINEAR:
        return c
    elif mode == MODE_HERTZ:
        return c * np.sqrt(abs(c))
    else:
        if c == 0.0:
            return 0.0
        return c * _power(abs(c), alpha - 1.0)


@kernel(inline="always")
def _power(a, e):
    """a^e for a >= 0 and e >= 0: the named laws' exponents (Hertz's 1/2 in the force,
    Tsuji's 1/4, 1 and 0) by square roots, as the force passes of a fixed law take them,
    so that the contact an event scan evaluates is the one the step integrated (and
    without pow, which costs several times a square root); any other by pow."""
    if e == 0.5:
        return np.sqrt(a)
    if e == 0.25:
        return np.sqrt(np.sqrt(a))
    if e == 1.0:
        return a
    if e == 0.0:
        return 1.0
    return a ** e


@kernel
def _forces(X, F, MK, AL, o, e, mode, alpha):
    """Forces of the contact lanes o..e-1 at positions X into F[o:e], times MK.

    MK holds each lane's stiffness, and 0 on a lane from a cluster's last ball to the
    next cluster's first (see _rebuild); AL each lane's exponent (MODE_MIXED). One
    loop per law, each with its law fixed, so that the loop vectorises.
    """
    if mode == MODE_LINEAR:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], MODE_LINEAR, alpha) * MK[p]
    elif mode == MODE_HERTZ:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], MODE_HERTZ, alpha) * MK[p]
    elif mode == MODE_POWER:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], MODE_POWER, alpha) * MK[p]
    else:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], MODE_MIXED, AL[p]) * MK[p]


@kernel
def _accelerations(X, F, MK, WP, out, m, mode, alpha, unit):
    """Accelerations of the m compact balls at positions X into out (forces into F).

    One pass over the window's m - 1 contact lanes, clusters and all, gaps masked: the
    loops are as long as the window, and vectorise, where loops per cluster are as
    short as the clusters (a line broken by many impacting balls has hundreds of them).
    ``unit``: every mass 1 and no external force, where the forces are the
    accelerations.
    """
    _span_accelerations(X, F, MK, WP, out, 0, m - 1, mode, alpha, unit)


@kernel(inline="always")
def _span_accelerations(X, F, MK, WP, out, o, e, mode, alpha, unit):
    """Accelerations of compact balls o..e at positions X into out (forces of lanes
    o..e-1 into F), nothing pushing from beyond o or e: the whole window
    (``_accelerations``), or one cluster that formed (``_clusters._rebuild``). The
    ends are peeled so that the loop has no branch."""
    if e == o:  # a lone driven ball: no contact (its drive is added after)
        out[o] = 0.0 if unit else WP[W_ACC, o]
        return
    _forces(X, F, MK, WP[W_ALPHA], o, e, mode, alpha)
    if unit:
        out[o] = -F[o]
        for p in range(o + 1, e):
            out[p] = F[p - 1] - F[p]
        out[e] = F[e - 1]
    else:
        IM = WP[W_IM]
        GA = WP[W_ACC]
        out[o] = -F[o] * IM[o] + GA[o]
        for p in range(o + 1, e):
            out[p] = (F[p - 1] - F[p]) * IM[p] + GA[p]
        out[e] = F[e - 1] * IM[e] + GA[e]


@kernel(inline="always")
def _series_terms(TX, r, G, IM, nc, s, unit):
    """Row r of the balls' series from their contact lanes' force terms G[0:nc] (one
    order), times s: (G[p-1] - G[p]) s / m_p, the ends peeled so that the pass has no
    branch (``unit``: every mass 1). The series' counterpart of _accelerations."""
    if nc == 0:  # (a lone ball: no force)
        TX[r, 0] = 0.0
    elif unit:
        TX[r, 0] = (0.0 - G[0]) * s
        for p in range(1, nc):
            TX[r, p] = (G[p - 1] - G[p]) * s
        TX[r, nc] = (G[nc - 1] - 0.0) * s
    else:
        TX[r, 0] = (0.0 - G[0]) * s * IM[0]
        for p in range(1, nc):
            TX[r, p] = (G[p - 1] - G[p]) * s * IM[p]
        TX[r, nc] = (G[nc - 1] - 0.0) * s * IM[nc]


@kernel(inline="always")
def _damping(c, w, beta):
    """|c|^beta w: the damping force of unit damping (the named laws' beta = 0, 1/2 and,
    for Hertz, Tsuji's 1/4 without a pow)."""
    return _power(abs(c), beta) * w


@kernel(inline="always")
def _load(kappa, alpha, eta, beta, c, w):
    """kappa c|c|^(alpha-1) + eta |c|^beta w: a damped contact's force before it is held
    at 0 (negative: it would pull)."""
    return kappa * _force(c, MODE_MIXED, alpha) + eta * _damping(c, w, beta)


@kernel(inline="always")
def _stored(S, j, c):
    """The elastic energy kappa c^(alpha+1) / (alpha+1) of contact j at compression c
    (0 apart)."""
    if not c > 0.0:
        return 0.0
    a = S.cp[C_ALPHA, j]
    return S.cp[C_KAPPA, j] * c ** (a + 1.0) / (a + 1.0)


@kernel
def _damped_forces(X, V, F, MK, WP, DS, wgt, m, mode, alpha):
    """Forces of the m - 1 contact lanes at positions X and velocities V into F.

    A damped lane bearing its load carries kappa f(c) + eta |c|^beta w, a lane held at
    0 (W_HELD) nothing: the switch between the two, where the load changes sign, is an
    event (_events._unload_event), so within a step each lane's force is smooth, and
    the stages of a step that ends on the switch see its smooth continuation, as for
    an opening (the force never pulls beyond that step). When ``wgt`` is not 0, a lane
    bearing its load adds its damping's power eta |c|^beta w^2 times ``wgt`` (h times a
    weight of the step's quadrature) to DS: summed over the stages of a step with
    DOP853's weights, the energy it dissipated over the step, to the method's order.
    (A lane held at 0 dissipates the elastic energy it still stores as its compression
    goes: _output._commit_dissipation counts that exactly, from the step's ends.)

    Where the law and the damping's exponent are the window's own (a Hertz line under
    Tsuji's or Kuwabara and Kono's law, a linear one under a dashpot), the pass is one
    loop with both fixed and no branch, which vectorises; each lane's arithmetic is the
    same as the general loop's, so the forces are the same to the bit.
    """
    nc = m - 1
    beta = _window_beta(WP[W_ETA], WP[W_BETA], nc)
    if mode == MODE_HERTZ and beta == 0.25:
        _damped_lanes(X, V, F, MK, WP, DS, wgt, 0, nc, MODE_HERTZ, alpha, 0.25)
    elif mode == MODE_HERTZ and beta == 0.5:
        _damped_lanes(X, V, F, MK, WP, DS, wgt, 0, nc, MODE_HERTZ, alpha, 0.5)
    elif mode == MODE_LINEAR and beta == 0.0:
        _damped_lanes(X, V, F, MK, WP, DS, wgt, 0, nc, MODE_LINEAR, alpha, 0.0)
    else:
        _damped_lanes(X, V, F, MK, WP, DS, wgt, 0, nc, mode, alpha, -1.0)


@kernel
def _damped_band(X, V, F, MK, WP, o, e, mode, alpha):
    """Forces of the contact lanes o..e-1 at (X, V) into F, as ``_damped_forces`` gives
    them (the same operations lane by lane; no power summed): a band of a few balls
    (``_generated._dense_ball``)."""
    _damped_lanes(X, V, F, MK, WP, F, 0.0, o, e, mode, alpha, -1.0)


@kernel(inline="always")
def _window_beta(ETA, BETA, nc):
    """The damping exponent of the damped lanes of the window, if they share one (-1 if
    none is damped, -2 if they differ)."""
    beta = -1.0
    for p in range(nc):
        if ETA[p] != 0.0:
            if beta == -1.0:
                beta = BETA[p]
            elif BETA[p] != beta:
                return -2.0
    return beta


@kernel(inline="always")
def _damped_lanes(X, V, F, MK, WP, DS, wgt, o, e, mode, alpha, beta):
    """The forces of lanes o..e-1 of ``_damped_forces``, the law fixed by ``mode`` and
    the damping's exponent by ``beta`` (-1: each lane's own); DS is not touched where
    ``wgt`` is 0. Every lane's terms are evaluated and the results chosen, not branched
    to, so that with both fixed the loop has no branch."""
    AL, ETA, BETA, HELD = WP[W_ALPHA], WP[W_ETA], WP[W_BETA], WP[W_HELD]
    power = wgt != 0.0
    for p in range(o, e):
        eta = ETA[p]
        c = X[p] - X[p + 1]
        fe = _force(c, mode, AL[p] if mode == MODE_MIXED else alpha) * MK[p]
        w = V[p] - V[p + 1]
        fd = eta * _damping(c, w, BETA[p] if beta < 0.0 else beta)
        bearing = eta != 0.0 and HELD[p] == 0.0
        F[p] = fe if eta == 0.0 else (fe + fd if bearing else 0.0)
        if power:
            DS[p] = DS[p] + wgt * fd * w if bearing else DS[p]


@kernel
def _damped_accelerations(X, V, F, MK, WP, DS, wgt, out, m, mode, alpha):
    """Accelerations of the m compact balls at (X, V) into out, on a damped line (see
    _damped_forces; forces into F)."""
    _damped_forces(X, V, F, MK, WP, DS, wgt, m, mode, alpha)
    nc = m - 1
    IM = WP[W_IM]
    GA = WP[W_ACC]
    if nc <= 0:  # (no cluster: nothing moves under a force; a lone driven ball: its
        if nc == 0:  # drive is added after)
            out[0] = GA[0]
        return
    out[0] = -F[0] * IM[0] + GA[0]
    for p in range(1, nc):
        out[p] = (F[p - 1] - F[p]) * IM[p] + GA[p]
    out[nc] = F[nc - 1] * IM[nc] + GA[nc]


@kernel
def _rhs(S, Xs, Vs, out):
    """Accelerations of the compact balls at positions ``Xs`` (and velocities ``Vs``,
    on a damped line) into ``out``."""
    if S.ints[I_DAMPED] == 1:
        _damped_accelerations(Xs, Vs, S.FS, S.TR, S.WP, S.FS, 0.0, out, S.ints[I_M],
                              S.ints[I_MODE], S.fs[F_ALPHA])
    else:
        _accelerations(Xs, S.FS, S.TR, S.WP, out, S.ints[I_M], S.ints[I_MODE],
                       S.fs[F_ALPHA], S.ints[I_UNIT] == 1)


@kernel(inline="always")
def _potential(c, mode, alpha):
    """|c|^(alpha+1)/(alpha+1): the energy of an active contact's (odd-continued) force
    of unit stiffness."""
    a = abs(c)
    if mode == MODE_LINEAR:
        return 0.5 * a * a
    elif mode == MODE_HERTZ:
        return 0.4 * a * a * np.sqrt(a)
    return a ** (alpha + 1.0) / (alpha + 1.0)
