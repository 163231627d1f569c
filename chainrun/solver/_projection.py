"""Energy projection: each cluster's internal energy, restored when its structure changes.

A cluster's internal energy (kinetic energy about its mean velocity, plus the
potential of its contacts, less the work of its external forces beyond what moves its
centre of mass) is conserved exactly between changes of structure;
``_project_energy`` puts back what the integration lost, and adds the corrections up
as a measure of the integration error (``Diagnostics.energy_correction``).
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._forces import _potential
from chainrun.solver._jit import kernel
from chainrun.solver._state import (
    F_ALPHA, F_EPROJ, I_DAMPED, I_DRIVEN, I_MODE, I_UNIT, MODE_MIXED, W_ACC, W_ALPHA,
    W_IM, W_MASS,
)


@kernel(inline="always")
def _mean_velocity(S, o, e):
    """The mass-weighted mean velocity of compact balls o..e: 0 if one is a wall (an
    infinite mass at rest)."""
    u = 0.0
    msum = 0.0
    for p in range(o, e + 1):
        if S.WP[W_IM, p] == 0.0:
            return 0.0
        u += S.WP[W_MASS, p] * S.V[p]
        msum += S.WP[W_MASS, p]
    return u / msum


@kernel
def _cluster_energy(S, c):
    """Internal energy of cluster c: kinetic energy about its mean velocity plus potential.

    Momentum changes only by the external forces, so this is conserved as well, and
    unlike the total energy it is computed with rounding relative to itself (a block
    moving at velocity 1 with tiny relative motion has a large total and a tiny
    internal energy). With external forces f_i it is less ``sum (f_i - m_i F/M) x_i``
    (F, M: the cluster's total force and mass), which keeps it conserved: uniform
    gravity drops out. A cluster held by a wall has mean velocity 0, and all of its
    external forces work on it.
    """
    o = S.coff[c]
    e = o + S.chi[c] - S.clo[c]
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    WP = S.WP
    u = _mean_velocity(S, o, e)
    en = 0.0
    for p in range(o, e + 1):
        en += 0.5 * WP[W_MASS, p] * (S.V[p] - u) * (S.V[p] - u)
    for p in range(o, e):
        a = WP[W_ALPHA, p] if mode == MODE_MIXED else alpha
        en += S.TR[p] * _potential(S.X[p] - S.X[p + 1], mode, a)
    if S.ints[I_UNIT] == 0:
        ftot = 0.0
        mtot = 0.0
        wall = False
        for p in range(o, e + 1):
            ftot += WP[W_MASS, p] * WP[W_ACC, p]
            mtot += WP[W_MASS, p]
            wall = wall or WP[W_IM, p] == 0.0
        g = 0.0 if wall else ftot / mtot
        for p in range(o, e + 1):
            en -= WP[W_MASS, p] * (WP[W_ACC, p] - g) * S.X[p]
    return en


@kernel(inline="always")
def _project_energy(S, c):
    """Restore cluster c's internal energy, conserved exactly since it formed; whether
    its velocities changed.

    Called as the cluster is taken apart or joined to another (``_clusters``), so that
    each cluster's energy is restored when its structure changes, and an event costs
    the clusters it touches. The velocities of the balls that move (|v| above 1e-3 of
    the cluster's largest) are scaled by one factor about their own (mass-weighted)
    mean: momentum is untouched, and balls nearly at rest (ahead of a wave, or in its
    wake, or a wall) are never nudged into openings or collisions of rounding size. A
    correction that is not small against the motion it rescales (over 1e-6 of its
    kinetic energy) is not that motion's integration error, and is not applied. The
    corrections add up in fs[F_EPROJ], a measure of the integration error. (Hairer,
    Lubich & Wanner, Geometric Numerical Integration, IV.4: projection methods.) A
    damped line's energy is not conserved, nor a driven line's, and neither is ever
    projected.
    """
    if S.ints[I_DAMPED] == 1 or S.ints[I_DRIVEN] == 1:
        return False
    M = S.WP[W_MASS]
    o = S.coff[c]
    e = o + S.chi[c] - S.clo[c]
    defect = S.cen[c] - _cluster_energy(S, c)
    vmax = 0.0
    for p in range(o, e + 1):
        vmax = max(vmax, abs(S.V[p]))
    cut = 1e-3 * vmax
    us = 0.0
    ms = 0.0
    k = 0
    for p in range(o, e + 1):
        if abs(S.V[p]) > cut:
            us += M[p] * S.V[p]
            ms += M[p]
            k += 1
    if k < 2:
        return False
    us /= ms
    ks = 0.0
    for p in range(o, e + 1):
        if abs(S.V[p]) > cut:
            ks += 0.5 * M[p] * (S.V[p] - us) * (S.V[p] - us)
    if not (ks > 0.0 and abs(defect) <= 1e-6 * ks):
        return False
    S.fs[F_EPROJ] += abs(defect)
    lam = np.sqrt(1.0 + defect / ks)
    for p in range(o, e + 1):
        if abs(S.V[p]) > cut:
            S.V[p] = us + lam * (S.V[p] - us)
    return True
