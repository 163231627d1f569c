"""The force law and the conserved quantities of a line (pure numpy, any shape of batch).

The one home of the force, energy and momentum formulas of a ``Line``
(``chainrun.solver.model``: masses, stiffnesses, exponents, gaps, walls, external
forces, damping); the solver's diagnostics, the run files' observables, the analysis
and the checks all call these. Where every contact has one law (the paper's line among
them), the law is factored out of the sum, and a mass of 1 multiplies nothing: the
paper's line gets the numbers of its own formulas (sum v^2 / 2, sum v, sum
c^(alpha+1) / (alpha+1)) to the bit. The kernels' home of the law is ``_forces``.
"""

from __future__ import annotations

import numpy as np

from chainrun.solver import model


def _alike(a) -> bool:
    """Whether ``a`` (a number or an array) holds one value only."""
    return model._alike(np.atleast_1d(a))


def _first(a) -> float:
    return float(np.atleast_1d(a)[0])


def compressions(x: np.ndarray) -> np.ndarray:
    """Difference of neighbouring displacements, ``x_j - x_{j+1}``; shape (..., N-1)."""
    x = np.asarray(x, dtype=float)
    return x[..., :-1] - x[..., 1:]


# --- the force law --------------------------------------------------------------------------


def contact_load(delta, rate, kappa, alpha, eta, beta):
    """``kappa delta |delta|^(alpha-1) + eta |delta|^beta rate``: the law's elastic and
    damping parts before it is held at 0, continued smoothly to ``delta < 0``
    (negative: the contact would pull). Any shapes that broadcast, or scalars."""
    return (kappa * np.sign(delta) * np.abs(delta) ** alpha
            + eta * np.abs(delta) ** beta * rate)


def contact_law(delta, kappa, alpha, rate=None, eta=0.0, beta=0.0) -> np.ndarray:
    """Force of contacts compressed by ``delta`` (the gap taken off): ``kappa
    delta_+^alpha``; with a compression ``rate`` and a damping ``eta`` (exponent
    ``beta``), ``max(0, kappa delta^alpha + eta delta^beta rate)`` for delta > 0, 0
    apart. It never pulls. Arguments broadcast (per contact, or numbers)."""
    delta = np.asarray(delta, dtype=float)
    f = np.clip(delta, 0.0, None) ** alpha
    f = f if np.all(np.asarray(kappa) == 1.0) else f * kappa
    if rate is None or not np.any(np.asarray(eta) != 0.0):
        return f
    d = np.clip(delta, 0.0, None)
    load = f + eta * d ** beta * rate
    return np.where(delta > 0.0, np.clip(load, 0.0, None), 0.0)


def line_contact_forces(x: np.ndarray, line, v: np.ndarray | None = None) -> np.ndarray:
    """Force of each contact between balls of ``line`` (its stiffnesses, exponents, gaps
    and, with the velocities ``v``, its damping) at displacements ``x`` of shape
    (..., N); shape (..., N-1). The walls' contacts are not among them."""
    delta = compressions(x)
    if np.any(line.gap != 0.0):
        delta = delta - line.gap
    rate = None if v is None else compressions(v)
    return contact_law(delta, line.stiffness, line.alpha, rate, line.damping,
                       line.damping_exponent)


def wall_forces(x: np.ndarray, line, t=None, v: np.ndarray | None = None) -> np.ndarray:
    """Force of each wall's contact, left and right, at displacements ``x`` of shape
    (..., N): its law (``contact_law``) of ``w_L - x_1 - g`` and ``x_N - w_R - g``, a
    moving wall displaced as it is at the times ``t`` (shape (...), which such a line
    needs), with the velocities ``v`` its damping (against the wall's own velocity);
    0 where there is no wall. Shape (..., 2)."""
    x = np.asarray(x, dtype=float)
    out = np.zeros(x.shape[:-1] + (2,))
    if any(w is not None and w.motion is not None for w in line.walls) and t is None:
        raise ValueError("a line whose walls move needs the time of its positions")
    for side, w in enumerate(line.walls):
        if w is None:
            continue
        u = du = 0.0
        if w.motion is not None:
            u, du = w.motion(t), w.motion(t, 1)
        if side == 0:
            delta = u - x[..., 0] - w.gap
            rate = None if v is None else du - np.asarray(v)[..., 0]
        else:
            delta = x[..., -1] - u - w.gap
            rate = None if v is None else np.asarray(v)[..., -1] - du
        out[..., side] = contact_law(delta, w.stiffness, w.alpha, rate, w.damping,
                                     w.damping_exponent)
    return out


def contact_forces(x: np.ndarray, alpha, stiffness=1.0, gap=0.0, v=None, damping=0.0,
                   damping_exponent=0.0) -> np.ndarray:
    """``contact_law`` of the contacts between neighbours of ``x`` (shape (..., N)),
    their laws given one by one (numbers, or one per contact); shape (..., N-1)."""
    delta = compressions(x)
    if np.any(np.asarray(gap) != 0.0):
        delta = delta - gap
    return contact_law(delta, stiffness, alpha, None if v is None else compressions(v),
                       damping, damping_exponent)


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


# --- energies and momentum of a line (``chainrun.solver.model.Line``), in its own units -----


def _times_mass(a: np.ndarray, mass) -> np.ndarray:
    """``a * mass`` by ball, ``a`` itself where every mass is 1."""
    return a if np.all(np.asarray(mass) == 1.0) else a * mass


def line_kinetic_energy(v: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """``sum m v^2 / 2``; v of shape (..., N), ``mass`` the line's (shape (N,))."""
    v = np.asarray(v, dtype=float)
    return 0.5 * np.sum(_times_mass(v * v, mass), axis=-1)


def line_momentum(v: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """``sum m v``; v of shape (..., N), ``mass`` the line's (shape (N,))."""
    v = np.asarray(v, dtype=float)
    return np.sum(_times_mass(v, mass), axis=-1)


def impulse(line, t: float, walls: float = 0.0) -> float:
    """The momentum the line gains by time ``t`` from its constant external forces,
    its drives (forces prescribed in time) and its walls (``walls``: their impulses,
    integrated along the run, as ``Solution.wall_impulse`` sums them)."""
    drives = sum(float(d.integral(t)) for _, d in line.drives)
    return float(np.sum(line.force)) * t + walls + drives


def _law_energy(delta: np.ndarray, kappa, alpha) -> np.ndarray:
    e = np.zeros(np.broadcast_shapes(np.shape(delta), np.shape(kappa)))
    # (an overlap too large for a float's energy is inf, and the run says so: no warning)
    with np.errstate(invalid="ignore", over="ignore"):
        np.power(np.clip(delta, 0.0, None), np.asarray(alpha, dtype=float) + 1.0, out=e,
                 where=np.asarray(delta) > 0.0)
    return np.asarray(kappa, dtype=float) * e / (np.asarray(alpha, dtype=float) + 1.0)


#: Contacts per block of ``_one_law_energy``: its temporaries stay small and reused.
_BLOCK = 2**16


def _one_law_energy(x: np.ndarray, gap, kappa: float, alpha: float) -> np.ndarray:
    """``kappa sum delta_+^(alpha+1) / (alpha+1)`` over the contacts between balls,
    every one with the same law; shape (...).

    By blocks of contacts, and the power only where delta > 0: a snapshot of a long
    line is mostly balls at rest, and a fractional power, like a fresh temporary as long
    as the line, costs far more than the test.
    """
    gapped = bool(np.any(gap != 0.0))
    total = np.zeros(x.shape[:-1])
    with np.errstate(invalid="ignore", over="ignore"):
        for i in range(0, x.shape[-1] - 1, _BLOCK):
            c = compressions(x[..., i:i + _BLOCK + 1])
            if gapped:
                c = c - gap[i:i + _BLOCK]
            e = np.zeros_like(c)
            np.power(c, alpha + 1.0, out=e, where=c > 0.0)
            total += e.sum(axis=-1)
    return kappa * total / (alpha + 1.0)


def line_potential_energy(x: np.ndarray, line, t=None) -> np.ndarray:
    """Energy stored in the contacts (walls included), ``kappa delta_+^(alpha+1) /
    (alpha+1)`` with ``delta_j = x_j - x_{j+1} - g_j``, less the work ``sum f x`` of the
    constant external forces: so that kinetic plus potential energy is conserved.
    x of shape (..., N). A moving wall's contact is compressed by its displacement at
    the times ``t`` (shape (...)), which such a line needs (``Line.wall_displacement``);
    what the drives do is their work, not a potential."""
    x = np.asarray(x, dtype=float)
    if _alike(line.stiffness) and _alike(line.alpha):
        total = (_one_law_energy(x, line.gap, _first(line.stiffness), _first(line.alpha))
                 if line.n > 1 else np.zeros(x.shape[:-1]))
    else:
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
    if np.any(line.force != 0.0):
        total = total - x @ line.force
    return total[()]


def energy_rounding(x: np.ndarray, line, t: float = 0.0, energy: float | None = None) -> float:
    """How far ``line_potential_energy(x, line, t)`` (``energy``, if known) moves when the
    displacements ``x`` (shape (N,)) move by their rounding, one unit in the last place
    each: the sum over the contacts (walls included) of the force times the rounding of
    the positions it spans, with the energy's own rounding. On a precompressed line,
    whose positions carry the static compressions, it is the floor under any energy
    balance. Only the pressed contacts are evaluated (a long line's are few)."""
    x = np.asarray(x, dtype=float)
    total = 0.0
    if line.n > 1:
        delta = x[:-1] - x[1:]
        if np.any(line.gap != 0.0):
            delta = delta - line.gap
        on = np.flatnonzero(delta > 0.0)
        if on.size:
            kappa = np.broadcast_to(np.asarray(line.stiffness, dtype=float), delta.shape)[on]
            alpha = np.broadcast_to(np.asarray(line.alpha, dtype=float), delta.shape)[on]
            force = kappa * delta[on] ** alpha
            total += float(force @ (np.abs(x[on]) + np.abs(x[on + 1])))
    wl, wr = line.wall_displacement(t)
    for wall, delta, ends in ((line.left, float(wl) - x[0], abs(float(wl)) + abs(x[0])),
                              (line.right, x[-1] - float(wr), abs(x[-1]) + abs(float(wr)))):
        if wall is not None:
            total += float(contact_law(delta - wall.gap, wall.stiffness, wall.alpha)) * ends
    if energy is None:
        energy = float(line_potential_energy(x, line, t))
    return float(np.finfo(float).eps * (total + abs(energy)))


def baseline_energy(line) -> float:
    """Potential energy of the state a line rests in before it is struck: that of its
    initial positions where it starts at a static equilibrium (precompressed: the
    positions are not all 0), else 0."""
    if not np.any(line.position):
        return 0.0
    return float(line_potential_energy(line.position, line, 0.0))


def static_load_work(line, t) -> np.ndarray:
    """The work the static load does on a line that starts at rest in its static state
    (precompressed) as its walls move, by the times ``t``: each moving wall's static
    force, its contact's at t = 0, times its displacement into the line since then.

    It is the part of the drives' work that the contacts give back as the walls return
    (F0 w(t), swinging with the wall's phase), and the same first-order part of the
    contacts' energy above the static state: with it taken off both, the contacts'
    energy left is that of the deformation about the static state, never negative (the
    force laws are convex), and the drives' work left is what the line took up (0 where
    no wall moves or the line starts unloaded)."""
    t = np.asarray(t, dtype=float)
    work = np.zeros(t.shape)
    if not np.any(line.position):
        return work
    x = line.position
    w0 = line.wall_displacement(0.0)
    wt = line.wall_displacement(t)
    # (the left wall pushes with +x as its displacement grows, the right one with -x)
    for wall, delta, sign, start, now in (
            (line.left, float(w0[0]) - x[0], 1.0, float(w0[0]), wt[0]),
            (line.right, x[-1] - float(w0[1]), -1.0, float(w0[1]), wt[1])):
        if wall is not None and wall.motion is not None:
            force = float(contact_law(delta - wall.gap, wall.stiffness, wall.alpha))
            work = work + sign * force * (np.asarray(now) - start)
    return work[()]


def impact_energy(line) -> float:
    """The energy an impact puts into ``line``: its initial kinetic energy, plus the
    energy of any initial overlap (its potential energy at t = 0 above
    ``baseline_energy``). K/2 for the paper's line. Every energy share chainrun reports
    is a share of this."""
    start = float(line_kinetic_energy(line.velocity, line.mass)
                  + line_potential_energy(line.position, line, 0.0))
    return start - baseline_energy(line)
