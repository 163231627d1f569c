"""Forces and conserved quantities of the line (pure numpy, any shape of batch).

The one home of the energy and momentum formulas; the solver's diagnostics, the run
files' observables and the analysis all call these.
"""

from __future__ import annotations

import numpy as np


def compressions(x: np.ndarray) -> np.ndarray:
    """Compression of each contact, ``c_j = x_j - x_{j+1}``; shape (..., N-1)."""
    x = np.asarray(x, dtype=float)
    return x[..., :-1] - x[..., 1:]


def contact_forces(x: np.ndarray, alpha, stiffness=1.0, gap=0.0, v=None, damping=0.0,
                   damping_exponent=0.0) -> np.ndarray:
    """Force of each contact, ``kappa (c - g)_+^alpha`` (it never pulls); shape (..., N-1).

    ``alpha``, ``stiffness`` and ``gap`` are numbers or one per contact; ``c`` are the
    differences of ``x`` (``compressions``), so a gap of 0 gives the paper's law. With
    velocities ``v`` (shape of ``x``) and a ``damping`` eta (exponent beta), the damped
    law ``max(0, kappa d^alpha + eta d^beta d')`` for d = c - g > 0, 0 apart.
    """
    c = compressions(x)
    if np.any(np.asarray(gap) != 0.0):
        c = c - gap
    f = np.clip(c, 0.0, None) ** alpha
    f = f if np.all(np.asarray(stiffness) == 1.0) else f * stiffness
    if v is None or not np.any(np.asarray(damping) != 0.0):
        return f
    d = np.clip(c, 0.0, None)
    load = f + damping * d ** damping_exponent * compressions(v)
    return np.where(c > 0.0, np.clip(load, 0.0, None), 0.0)


def momentum(v: np.ndarray) -> np.ndarray:
    """Total momentum ``sum v``; shape (...)."""
    return np.asarray(v, dtype=float).sum(axis=-1)


def kinetic_energy(v: np.ndarray) -> np.ndarray:
    """``sum v^2 / 2``; shape (...)."""
    v = np.asarray(v, dtype=float)
    return 0.5 * np.einsum("...i,...i->...", v, v)


#: Contacts per block of ``potential_energy``: its temporaries stay small and reused.
_BLOCK = 2**16


def potential_energy(x: np.ndarray, alpha: float) -> np.ndarray:
    """``sum c_+^(alpha+1) / (alpha+1)`` over contacts; shape (...).

    By blocks of contacts, and the power only where c > 0: a snapshot of a long line
    is mostly balls at rest, and a fractional power, like a fresh temporary as long
    as the line, costs far more than the test.
    """
    x = np.asarray(x, dtype=float)
    total = np.zeros(x.shape[:-1])
    for i in range(0, x.shape[-1] - 1, _BLOCK):
        c = compressions(x[..., i:i + _BLOCK + 1])
        e = np.zeros_like(c)
        np.power(c, alpha + 1.0, out=e, where=c > 0.0)
        total += e.sum(axis=-1)
    return total[()] / (alpha + 1.0)


# --- contact laws of real spheres (SI) -------------------------------------------------------


def sphere_mass(density, diameter) -> np.ndarray:
    """Mass of a solid sphere, ``rho pi d^3 / 6``; any shape (broadcast)."""
    d = np.asarray(diameter, dtype=float)
    return np.asarray(density, dtype=float) * np.pi * d * d * d / 6.0


def hertz_stiffness(young1, poisson1, radius1, young2, poisson2, radius2=np.inf) -> np.ndarray:
    """Hertz constant ``kappa`` of two elastic spheres in contact, ``F = kappa delta^(3/2)``.

    ``kappa = (4/3) E* sqrt(R*)`` with ``1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2`` and
    ``R* = R1 R2 / (R1 + R2)``; a flat wall is a sphere of infinite radius
    (``radius2 = inf``, the default), for which ``R* = R1``. For two identical spheres
    of diameter d this is ``E d^(1/2) / (3 (1 - nu^2))``. Arguments broadcast.

    References
    ----------
    .. [1] K. L. Johnson, *Contact Mechanics*, Cambridge University Press (1985),
       section 4.2, eqs. (4.22)-(4.23).
    """
    e1, nu1, r1 = (np.asarray(a, dtype=float) for a in (young1, poisson1, radius1))
    e2, nu2, r2 = (np.asarray(a, dtype=float) for a in (young2, poisson2, radius2))
    e_star = 1.0 / ((1.0 - nu1 * nu1) / e1 + (1.0 - nu2 * nu2) / e2)
    r_star = np.where(np.isinf(r2), r1, r1 * r2 / (r1 + np.where(np.isinf(r2), 0.0, r2)))
    return 4.0 / 3.0 * e_star * np.sqrt(r_star)


# --- the general line (``chainrun.solver.model.Line``), in its own units --------------------


def line_kinetic_energy(v: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """``sum m v^2 / 2``; v of shape (..., N)."""
    v = np.asarray(v, dtype=float)
    return 0.5 * np.einsum("...i,i,...i->...", v, np.asarray(mass, dtype=float), v)


def line_momentum(v: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """``sum m v``; v of shape (..., N)."""
    return np.asarray(v, dtype=float) @ np.asarray(mass, dtype=float)


def _law_energy(delta: np.ndarray, kappa, alpha) -> np.ndarray:
    e = np.zeros(np.broadcast_shapes(np.shape(delta), np.shape(kappa)))
    # (an overlap too large for a float's energy is inf, and the run says so: no warning)
    with np.errstate(invalid="ignore", over="ignore"):
        np.power(np.clip(delta, 0.0, None), np.asarray(alpha, dtype=float) + 1.0, out=e,
                 where=np.asarray(delta) > 0.0)
    return np.asarray(kappa, dtype=float) * e / (np.asarray(alpha, dtype=float) + 1.0)


def line_potential_energy(x: np.ndarray, line, t=None) -> np.ndarray:
    """Energy stored in the contacts (walls included), ``kappa delta_+^(alpha+1) /
    (alpha+1)`` with ``delta_j = x_j - x_{j+1} - g_j``, less the work ``sum f x`` of the
    constant external forces: so that kinetic plus potential energy is conserved.
    x of shape (..., N). A moving wall's contact is compressed by its displacement at
    the times ``t`` (shape (...)), which such a line needs (``Line.wall_displacement``);
    what the drives do is their work, not a potential."""
    x = np.asarray(x, dtype=float)
    total = _law_energy(x[..., :-1] - x[..., 1:] - line.gap, line.stiffness,
                        line.alpha).sum(axis=-1)
    moving = [w is not None and w.motion is not None for w in line.walls]
    if any(moving):
        if t is None:
            raise ValueError("a line whose walls move needs the time of its positions")
        wl, wr = line.wall_displacement(t)
    else:
        wl = wr = 0.0
    if line.left is not None:
        w = line.left
        total = total + _law_energy(wl - x[..., 0] - w.gap, w.stiffness, w.alpha)
    if line.right is not None:
        w = line.right
        total = total + _law_energy(x[..., -1] - wr - w.gap, w.stiffness, w.alpha)
    return total - x @ line.force


def baseline_energy(line) -> float:
    """Potential energy of the state a line rests in before it is struck: that of its
    initial positions where it starts at a static equilibrium (precompressed: the
    positions are not all 0), else 0."""
    if not np.any(line.position):
        return 0.0
    return float(line_potential_energy(line.position, line, 0.0))


def impact_energy(line) -> float:
    """The energy an impact puts into ``line``: its initial kinetic energy, plus the
    energy of any initial overlap (its potential energy at t = 0 above
    ``baseline_energy``). K/2 for the paper's line. Every energy share chainrun reports
    is a share of this."""
    start = float(line_kinetic_energy(line.velocity, line.mass)
                  + line_potential_energy(line.position, line, 0.0))
    return start - baseline_energy(line)
