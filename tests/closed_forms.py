"""Closed forms of the general line model, for the tests (test-only).

The evidence here owes nothing to any solver: elastic collisions of two bodies, the
duration of a contact with the force law ``k delta^alpha`` (through the Beta
function), a linear pair's whole trajectory, a ball bouncing on a linear wall under
a constant force, the restitution and duration of a linear spring-dashpot collision (the
damped oscillator's explicit solution, its force's zero found by a root finder), and the
Hertz stiffness of two steel beads.

Duration of a contact. The compression delta of two bodies (reduced mass mu, relative
speed u at first touch) obeys ``mu delta'' = -k delta^alpha`` while positive, so
energy gives ``delta'^2 = u^2 - 2 k delta^(alpha+1) / ((alpha+1) mu)`` and the
largest compression is ``d = ((alpha+1) mu u^2 / (2k))^(1/(alpha+1))``. The contact
lasts, by the symmetry of loading and unloading,

    t_c = 2 int_0^d dx / sqrt(u^2 - 2 k x^(alpha+1) / ((alpha+1) mu))
        = (2 d / u) int_0^1 ds / sqrt(1 - s^p),        p = alpha + 1,
        = (2 d / u) (1/p) B(1/p, 1/2)                  (w = s^p).

For alpha = 1 this is pi sqrt(mu/k); for alpha = 3/2, t_c = 2.94328 d / u =
3.21807 (mu/k)^(2/5) u^(-1/5).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq
from scipy.special import beta

#: Hertz (alpha = 3/2): t_c = HERTZ_DURATION * (mu/k)^(2/5) u^(-1/5), and
#: t_c = HERTZ_DURATION_DMAX * d / u (d the largest compression).
HERTZ_DURATION_DMAX = 0.8 * beta(0.4, 0.5)                  # 2.9432751843...
HERTZ_DURATION = HERTZ_DURATION_DMAX * 1.25 ** 0.4          # 3.2180654597...


def two_ball_velocities(m1: float, m2: float, u: float) -> tuple[float, float]:
    """Velocities after an elastic collision of ball 1 (mass m1, speed u) with ball 2
    (mass m2) at rest: momentum and energy conserved, whatever the contact law."""
    return u * (m1 - m2) / (m1 + m2), 2.0 * m1 * u / (m1 + m2)


def max_compression(mu: float, k: float, alpha: float, u: float) -> float:
    p = alpha + 1.0
    return (p * mu * u * u / (2.0 * k)) ** (1.0 / p)


def contact_duration(mu: float, k: float, alpha: float, u: float) -> float:
    """Duration of a contact ``k delta^alpha`` between bodies of reduced mass ``mu``
    meeting at relative speed ``u`` (a wall: mu = the ball's mass)."""
    p = alpha + 1.0
    return 2.0 * max_compression(mu, k, alpha, u) / u * beta(1.0 / p, 0.5) / p


def linear_pair(t, m1: float, m2: float, k: float, u: float):
    """Positions and velocities, shape (T, 2), of two balls touching at t = 0 with a
    linear contact k, ball 1 at speed u, ball 2 at rest, both at x = 0.

    The compression c = x1 - x2 obeys mu c'' = -k c: c = u sin(w t)/w, w = sqrt(k/mu),
    until t = pi/w; the centre of mass moves at m1 u / (m1 + m2).
    """
    t = np.asarray(t, dtype=float)
    m = m1 + m2
    w = math.sqrt(k * m / (m1 * m2))
    ts = math.pi / w
    tc = np.minimum(t, ts)
    vc = m1 * u / m
    c = u * np.sin(w * tc) / w
    cd = u * np.cos(w * tc)
    v1f, v2f = two_ball_velocities(m1, m2, u)
    x1 = vc * tc + m2 / m * c + v1f * (t - tc)
    x2 = vc * tc - m1 / m * c + v2f * (t - tc)
    v1 = np.where(t < ts, vc + m2 / m * cd, v1f)
    v2 = np.where(t < ts, vc - m1 / m * cd, v2f)
    return np.stack([x1, x2], axis=-1), np.stack([v1, v2], axis=-1)


def linear_wall_bounce(m: float, k: float, f: float, u: float) -> float:
    """Duration of the contact of a ball (mass m) meeting a linear wall k at speed u
    while a constant force f presses it on the wall.

    delta = f/k + A sin(w t + phi), w = sqrt(k/m), with delta(0) = 0, delta'(0) = u:
    A = sqrt((f/k)^2 + (u/w)^2); delta returns to 0 after (pi + 2 asin(f/(k A))) / w,
    and the ball leaves at -u (the motion is reversible).
    """
    w = math.sqrt(k / m)
    a = math.hypot(f / k, u / w)
    return (math.pi + 2.0 * math.asin(f / (k * a))) / w


def oscillator(eta: float, k: float, mu: float, v: float) -> tuple[float, float]:
    """(e, t_end) of mu x'' + eta x' + k x = 0, x(0) = 0, x'(0) = v, from its explicit
    solution: the first zero of the force k x + eta x' found by brentq."""
    gamma, w0 = eta / (2 * mu), math.sqrt(k / mu)
    if gamma < w0:
        w = math.sqrt(w0 * w0 - gamma * gamma)
        x = lambda t: v / w * math.exp(-gamma * t) * math.sin(w * t)
        dx = lambda t: v * math.exp(-gamma * t) * (math.cos(w * t) - gamma / w * math.sin(w * t))
        hi = min(math.pi / w, 50.0 / w0)   # x > 0 and the force < 0 after its zero, until pi/w
    else:
        w = math.sqrt(gamma * gamma - w0 * w0)
        x = lambda t: v / w * math.exp(-gamma * t) * math.sinh(w * t)
        dx = lambda t: v * math.exp(-gamma * t) * (math.cosh(w * t) - gamma / w * math.sinh(w * t))
        hi = 50.0 / w0
    force = lambda t: k * x(t) + eta * dx(t)
    t = brentq(force, 1e-12 / w0, hi, xtol=1e-300, rtol=4 * np.finfo(float).eps)
    return -dx(t) / v, t


# A uniform chain of steel beads in SI units.
STEEL = dict(E=200e9, nu=0.3, rho=7850.0, d=25.4e-3)


def steel_bead() -> tuple[float, float]:
    """(mass, kappa) of a 25.4 mm steel bead: F = kappa delta^(3/2) between two beads,
    kappa = E d^(1/2) / (3 (1 - nu^2)) (Hertz, effective radius d/4)."""
    s = STEEL
    mass = s["rho"] * math.pi * s["d"] ** 3 / 6.0
    kappa = s["E"] * math.sqrt(s["d"]) / (3.0 * (1.0 - s["nu"] ** 2))
    return mass, kappa


# --- small oscillations of a chain of springs (the linear spectrum) ---------------------
# Masses m joined by springs K in a line (Kittel, Introduction to Solid State Physics,
# ch. 4; Brillouin, Wave Propagation in Periodic Structures, ch. 1).


def modes_between_walls(K: float, m: float, n: int) -> np.ndarray:
    """omega_j, j = 1..n, of n masses between two fixed walls, n + 1 springs:
    ``2 sqrt(K/m) sin(j pi / (2 (n + 1)))``."""
    j = np.arange(1, n + 1)
    return 2.0 * math.sqrt(K / m) * np.sin(j * math.pi / (2.0 * (n + 1)))


def shapes_between_walls(n: int) -> np.ndarray:
    """Mode j's displacements, shape (n, n): ``sin(i j pi / (n + 1))`` of ball i."""
    i = np.arange(1, n + 1)
    return np.sin(np.outer(i, i) * math.pi / (n + 1))


def modes_free_and_wall(K: float, m: float, n: int) -> np.ndarray:
    """omega_j of n masses with one free end and a fixed wall at the other, n springs:
    ``2 sqrt(K/m) sin((2j - 1) pi / (2 (2n + 1)))``."""
    j = np.arange(1, n + 1)
    return 2.0 * math.sqrt(K / m) * np.sin((2 * j - 1) * math.pi / (2.0 * (2 * n + 1)))


def monatomic_dispersion(K: float, m: float, q) -> np.ndarray:
    """omega(q) of the infinite line of equal masses: ``2 sqrt(K/m) |sin(q/2)|``."""
    return 2.0 * math.sqrt(K / m) * np.abs(np.sin(np.asarray(q, dtype=float) / 2.0))


def dimer_band_edges(K: float, m1: float, m2: float) -> tuple[float, float, float]:
    """The top of the acoustic band, the bottom and top of the optical band of the
    infinite line of masses m1 > m2 in turn: ``sqrt(2K/m1)``, ``sqrt(2K/m2)``,
    ``sqrt(2K (1/m1 + 1/m2))``."""
    return (math.sqrt(2.0 * K / m1), math.sqrt(2.0 * K / m2),
            math.sqrt(2.0 * K * (1.0 / m1 + 1.0 / m2)))


def light_impurity_mode(K: float, m: float, m_light: float) -> float:
    """The localised mode of one light mass ``m_light = (1 - e) m`` in the infinite line
    of masses m: ``2 sqrt(K/m) / sqrt(1 - e^2)``, above the band (Montroll & Potts,
    Phys. Rev. 100, 525 (1955)); its amplitude falls by ``(1 - e)/(1 + e)`` per ball."""
    e = 1.0 - m_light / m
    return 2.0 * math.sqrt(K / m) / math.sqrt(1.0 - e * e)
