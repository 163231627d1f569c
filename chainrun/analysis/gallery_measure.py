"""Measurements and closed forms for the gallery (``make gallery``, ``docs/gallery/``).

This module owns the definitions the gallery's recipes (``chainrun.analysis.gallery``)
use, as pure functions of arrays: Nesterenko's long-wave laws in SI units (with and
without precompression) and the constants that turn the paper's units into them, the
effective restitution of a line against a wall and how long the wall holds it, the
energy on each side of a ball, the drift of free balls, the elastic collision of two
balls and Hertz's contact time. Pulses (a peak force, its time, a wave's speed) are
measured by ``chainrun.analysis.pulse``.

Conventions:

- a *contact force* is that of one contact (between two beads, or a bead and a wall);
  the *peak force* ``F_m`` of a wave is the largest contact force as it passes;
- the *effective restitution* of a line against a wall is the ratio of its centre-of-mass
  velocity after and before, ``-sum(m v_final) / sum(m v_initial)``;
- a *wall contact* lasts from the first touch (t = 0) to the instant the wall's force
  returns to zero: the opening of an elastic contact, the unloading of a damped one
  (``chainrun.solver.EventKind.UNLOAD``: the collision ends there, while the bead is
  still slightly pressed; the compression is gone a little later, at its opening).

References
----------
.. [1] V. F. Nesterenko, "Propagation of nonlinear compression pulses in granular
   media", J. Appl. Mech. Tech. Phys. 24, 733-743 (1983); the long-wave solution as
   given in section 5b of Hinch and Saint-Jean (1999).
.. [2] C. Daraio, V. F. Nesterenko, E. B. Herbold and S. Jin, Phys. Rev. E 73, 026610
   (2006): the laws in SI form, with the prefactors 0.6802 and 0.9314.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import integrate

from chainrun.solver import EventKind
from chainrun.solver.physics import line_kinetic_energy, line_momentum

__all__ = [
    "PAPER_TO_SI",
    "daraio_group",
    "drift",
    "energy_split",
    "hertz_contact_time_factor",
    "long_wave_prefactor",
    "long_wave_sound_prefactor",
    "nesterenko_precompressed_ratio",
    "restitution",
    "two_ball",
    "wall_contact",
]

#: ``(6/pi)^(1/2) 3^(-1/3) 4^(-1/6)``: a speed ``C F^(1/6)`` in balls per unit time of the
#: paper's units (F the peak force in the paper's units, identical Hertz spheres with
#: ``k = E d^(1/2) / (3(1 - nu^2))`` and ``m = rho pi d^3 / 6``) is, in m/s,
#: ``C * PAPER_TO_SI * (4 E^2 F / (d^2 rho^3 (1 - nu^2)^2))^(1/6)``.
PAPER_TO_SI = math.sqrt(6.0 / math.pi) * 3.0 ** (-1.0 / 3.0) * 4.0 ** (-1.0 / 6.0)


def long_wave_prefactor(force_law: str = "leading") -> float:
    """Nesterenko's prefactor of ``V = C (4 E^2 F_m / (d^2 rho^3 (1-nu^2)^2))^(1/6)``.

    In the paper's units the long-wave wave has speed ``c = (2/sqrt5) A^(1/4)``; its peak
    force is ``A^(3/2)`` by the leading term of the force (``force_law="leading"``, the
    identification Daraio et al. use, giving 0.6802) or ``0.9 A^(3/2)`` by the paper's
    (5.1) (``"5.1"``), which raises the prefactor by ``0.9^(-1/6)``.
    """
    c = 2.0 / math.sqrt(5.0)
    if force_law == "5.1":
        c *= 0.9 ** (-1.0 / 6.0)
    elif force_law != "leading":
        raise ValueError(f"force_law must be 'leading' or '5.1', got {force_law!r}")
    return c * PAPER_TO_SI


def long_wave_sound_prefactor() -> float:
    """The prefactor of the sound speed ``c0 = C (4 E^2 F0 / (d^2 rho^3 (1-nu^2)^2))^(1/6)``
    of a chain under a static force F0: the linearised contact has stiffness
    ``(3/2) k^(2/3) F0^(1/3)``, so in the paper's units ``c0 = sqrt(3/2) F0^(1/6)``."""
    return math.sqrt(1.5) * PAPER_TO_SI


def daraio_group(force, young, poisson, density, diameter):
    """``(4 E^2 F / (d^2 rho^3 (1 - nu^2)^2))^(1/6)`` in m/s (SI inputs)."""
    force = np.asarray(force, dtype=float)
    return (4.0 * young**2 * force
            / (diameter**2 * density**3 * (1.0 - poisson**2) ** 2)) ** (1.0 / 6.0)


def nesterenko_precompressed_ratio(f_r):
    """``V_s / c0`` of the long-wave solitary wave in a chain under static force F0, at
    ``f_r = F_m / F0`` (F_m the wave's largest contact force, F0 included)::

        V_s / c0 = (4/15 (3 + 2 f_r^(5/3) - 5 f_r^(2/3)))^(1/2) / (f_r^(2/3) - 1)

    It tends to 1 as f_r -> 1 and to ``sqrt(8/15) f_r^(1/6)`` as f_r -> inf, where it
    joins the law of the chain without precompression.
    """
    f = np.asarray(f_r, dtype=float)
    return np.sqrt(4.0 / 15.0 * (3.0 + 2.0 * f ** (5.0 / 3.0) - 5.0 * f ** (2.0 / 3.0))) \
        / (f ** (2.0 / 3.0) - 1.0)


def restitution(mass, v_initial, v_final) -> float:
    """Effective restitution of a line against a wall: ``-sum(m v_final)/sum(m v_initial)``."""
    return float(-line_momentum(v_final, mass) / line_momentum(v_initial, mass))


def wall_contact(event_time, event_contact, event_kind, contact: int
                 ) -> tuple[float, float, int]:
    """How long a wall holds a line that touches it at t = 0, from the run's events.

    The contact is loaded at t = 0; a loading ends at the first ``UNLOAD``, ``OPEN`` or
    ``RELEASE`` after it and a new one starts at a ``CLOSE``, ``ENGAGE`` or ``RELOAD``.

    Parameters
    ----------
    event_time : ndarray, shape (E,)
    event_contact, event_kind : ndarray of int, shape (E,)
        The run's events (``RunData.event_*``).
    contact : int
        The wall's contact, numbered as the run file numbers contacts (the right wall
        of N balls is N, the left wall 0).

    Returns
    -------
    (float, float, int)
        ``(end, opened, loadings)``: the last time the wall's force returned to zero,
        the last time its compression did (equal to ``end`` for an elastic wall; NaN
        when neither happened) and how many separate loadings there were.
    """
    time = np.asarray(event_time, float)
    mask = np.asarray(event_contact) == contact
    order = np.argsort(time[mask], kind="stable")
    end = opened = float("nan")
    loaded, loadings = True, 0
    for t, kind in zip(time[mask][order], np.asarray(event_kind)[mask][order]):
        if kind > 0:
            loaded = True
            continue
        if loaded:
            end, loaded, loadings = float(t), False, loadings + 1
        if kind in (EventKind.OPEN, EventKind.RELEASE):
            opened = float(t)
    return end, opened, loadings


def energy_split(mass, v, at: int) -> tuple[float, float, float]:
    """Kinetic energy of the balls before ball ``at`` (1-based), of it, and after it."""
    m, v = np.asarray(mass, float), np.asarray(v, float)
    i = at - 1
    return tuple(float(line_kinetic_energy(v[part], m[part]))
                 for part in (slice(None, i), slice(i, i + 1), slice(i + 1, None)))


def drift(final_position, final_velocity, end_time: float, t: float) -> np.ndarray:
    """Displacements at time ``t >= end_time`` of balls in free flight after ``end_time``."""
    return np.asarray(final_position, float) + np.asarray(final_velocity, float) * (t - end_time)


def two_ball(m1: float, m2: float, v1: float = 1.0) -> tuple[float, float]:
    """Velocities after an elastic collision of ``m1`` at ``v1`` with ``m2`` at rest."""
    return (m1 - m2) / (m1 + m2) * v1, 2.0 * m1 / (m1 + m2) * v1


def hertz_contact_time_factor() -> float:
    """``tau`` of Hertz's contact time ``t_c = tau (m^2 / (kappa^2 v))^(1/5)`` of a ball of
    mass m hitting a wall at v with ``F = kappa delta^(3/2)``.

    The largest compression is ``delta_m = (5 m v^2 / (4 kappa))^(2/5)`` and the contact
    lasts ``(2 delta_m / v) int_0^1 dx / sqrt(1 - x^(5/2))``.
    """
    integral, _ = integrate.quad(lambda x: 1.0 / math.sqrt(1.0 - x**2.5), 0.0, 1.0,
                                 epsabs=1e-13, epsrel=1e-13, limit=200)
    return 2.0 * integral * 1.25 ** 0.4
