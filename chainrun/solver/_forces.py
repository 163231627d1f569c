"""The force law of the kernels: contact forces, accelerations and contact energy.

Between events the active set is fixed, so the right-hand side is smooth: an active
contact j carries ``kappa_j f(c)`` with ``f(c) = c |c|^(alpha_j-1)``, which is the
force for ``c > 0`` and its odd continuation beyond (for alpha = 1 exactly linear), so
a step that ends on an opening sees no kink. ``mode`` picks the law's loop
(``_state.MODE_*``): every contact linear, every contact Hertz, every contact one
other alpha, or each its own. A ball's acceleration is its net contact force over its
mass, plus that of its external force; a wall's inverse mass is 0.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    F_ALPHA, I_M, I_MODE, I_UNIT, MODE_HERTZ, MODE_LINEAR, MODE_MIXED, MODE_POWER,
    W_ACC, W_ALPHA, W_IM,
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
        return c * abs(c) ** (alpha - 1.0)


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
    nc = m - 1
    _forces(X, F, MK, WP[W_ALPHA], 0, nc, mode, alpha)
    if unit:
        out[0] = -F[0]
        for p in range(1, nc):
            out[p] = F[p - 1] - F[p]
        out[nc] = F[nc - 1]
    else:
        IM = WP[W_IM]
        GA = WP[W_ACC]
        out[0] = -F[0] * IM[0] + GA[0]
        for p in range(1, nc):
            out[p] = (F[p - 1] - F[p]) * IM[p] + GA[p]
        out[nc] = F[nc - 1] * IM[nc] + GA[nc]


@kernel
def _rhs(S, Xs, out):
    """Accelerations of the compact balls at positions ``Xs`` into ``out``."""
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
