"""The force law of the kernels: contact forces, accelerations and contact energy.

Between events the active set is fixed, so the right-hand side is smooth: an active
contact carries ``f(c) = c |c|^(alpha-1)``, which is the force for ``c > 0`` and its
odd continuation beyond (for alpha = 1 exactly linear), so a step that ends on an
opening sees no kink. ``mode`` picks the law's loop: 0 for alpha = 1, 1 for Hertz
(alpha = 1.5), 2 for any other alpha.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._jit import kernel
from chainrun.solver._state import F_ALPHA, I_M, I_MODE


@kernel(inline="always")
def _force(c, mode, alpha):
    if mode == 0:
        return c
    elif mode == 1:
        return c * np.sqrt(abs(c))
    else:
        if c == 0.0:
            return 0.0
        return c * abs(c) ** (alpha - 1.0)


@kernel
def _forces(X, F, MK, o, e, mode, alpha):
    """Forces of the contact lanes o..e-1 at positions X into F[o:e], masked by MK.

    One loop per law, each with its law fixed, so that the loop vectorises. A lane
    from a cluster's last ball to the next cluster's first carries none (MK = 0, see
    _rebuild).
    """
    if mode == 0:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], 0, alpha) * MK[p]
    elif mode == 1:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], 1, alpha) * MK[p]
    else:
        for p in range(o, e):
            F[p] = _force(X[p] - X[p + 1], mode, alpha) * MK[p]


@kernel
def _accelerations(X, F, MK, out, m, mode, alpha):
    """Accelerations of the m compact balls at positions X into out (forces into F).

    One pass over the window's m - 1 contact lanes, clusters and all, gaps masked: the
    loops are as long as the window, and vectorise, where loops per cluster are as
    short as the clusters (a line broken by many impacting balls has hundreds of them).
    """
    nc = m - 1
    _forces(X, F, MK, 0, nc, mode, alpha)
    out[0] = -F[0]
    for p in range(1, nc):
        out[p] = F[p - 1] - F[p]
    out[nc] = F[nc - 1]


@kernel
def _rhs(S, Xs, out):
    """Accelerations of the compact balls at positions ``Xs`` into ``out``."""
    _accelerations(Xs, S.FS, S.TR, out, S.ints[I_M], S.ints[I_MODE], S.fs[F_ALPHA])


@kernel(inline="always")
def _potential(c, mode, alpha):
    """|c|^(alpha+1)/(alpha+1): the energy of an active contact's (odd-continued) force."""
    a = abs(c)
    if mode == 0:
        return 0.5 * a * a
    elif mode == 1:
        return 0.4 * a * a * np.sqrt(a)
    return a ** (alpha + 1.0) / (alpha + 1.0)
