"""Energy projection: each cluster's internal energy, restored at every change of structure.

A cluster's internal energy (kinetic energy about its mean velocity plus the
potential of its contacts) is conserved exactly between changes of structure;
``_project_energy`` puts back what the integration lost, and adds the corrections up
as a measure of the integration error (``Diagnostics.energy_correction``).
"""

from __future__ import annotations

import numpy as np

from chainrun.solver._forces import _potential
from chainrun.solver._jit import kernel
from chainrun.solver._state import F_ALPHA, F_EPROJ, I_MODE, I_NCL


@kernel(inline="always")
def _mean_velocity(S, o, e):
    u = 0.0
    for p in range(o, e + 1):
        u += S.V[p]
    return u / (e - o + 1)


@kernel
def _cluster_energy(S, c):
    """Internal energy of cluster c: kinetic energy about its mean velocity plus potential.

    Momentum is conserved exactly, so this is conserved as well, and unlike the total
    energy it is computed with rounding relative to itself (a block moving at velocity
    1 with tiny relative motion has a large total and a tiny internal energy).
    """
    o = S.coff[c]
    e = o + S.chi[c] - S.clo[c]
    mode = S.ints[I_MODE]
    alpha = S.fs[F_ALPHA]
    u = _mean_velocity(S, o, e)
    en = 0.0
    for p in range(o, e + 1):
        en += 0.5 * (S.V[p] - u) * (S.V[p] - u)
    for p in range(o, e):
        en += _potential(S.X[p] - S.X[p + 1], mode, alpha)
    return en


@kernel
def _project_energy(S):
    """Restore each cluster's internal energy, conserved exactly between changes of structure.

    The velocities of the balls that move (|v| above 1e-3 of the cluster's largest)
    are scaled by one factor about their own mean: momentum is untouched, and balls
    nearly at rest (ahead of a wave, or in its wake) are never nudged into openings
    or collisions of rounding size. A correction that is not small against the
    motion it rescales (over 1e-6 of its kinetic energy) is not that motion's
    integration error, and is not applied. The corrections add up in fs[F_EPROJ], a
    measure of the integration error. (Hairer, Lubich & Wanner, Geometric Numerical
    Integration, IV.4: projection methods.)
    """
    for c in range(S.ints[I_NCL]):
        o = S.coff[c]
        e = o + S.chi[c] - S.clo[c]
        defect = S.cen[c] - _cluster_energy(S, c)
        vmax = 0.0
        for p in range(o, e + 1):
            vmax = max(vmax, abs(S.V[p]))
        cut = 1e-3 * vmax
        us = 0.0
        k = 0
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                us += S.V[p]
                k += 1
        if k < 2:
            continue
        us /= k
        ks = 0.0
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                ks += 0.5 * (S.V[p] - us) * (S.V[p] - us)
        if not (ks > 0.0 and abs(defect) <= 1e-6 * ks):
            continue
        S.fs[F_EPROJ] += abs(defect)
        lam = np.sqrt(1.0 + defect / ks)
        for p in range(o, e + 1):
            if abs(S.V[p]) > cut:
                S.V[p] = us + lam * (S.V[p] - us)
