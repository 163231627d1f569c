"""The similarity solution of section 4d: equation (4.9), by shooting and by Airy functions.

This module owns the theory of the linear impulse wave (paper section 4). With
``x_n(t) = t^(1/6) f(xi)``, ``xi = (n - t)/t^(1/3)``, the wave form obeys::

    f'''' - 8 xi f'' - 4 f' = 0                                            (4.9)

with f decaying ahead of the wave (xi -> +inf) and normalized so that the wave's energy
``int f'^2 dxi`` (kinetic plus potential, from the rear xi0 forward) is a given share of
the impact energy 1/2 (the paper's 96.2%).

Two independent solutions are provided and must agree:

- ``shoot``: the paper's method. Start at a large ``xi_inf`` on the decaying WKB solution
  ``xi^(-1) exp(-(4/3) sqrt(2) xi^(3/2))`` and integrate (4.9) backwards until f reaches
  its maximum (f' = 0) at xi0; then normalize.
- ``airy``: the closed form. ``g = Ai(c xi)^2`` with ``c = 2^(1/3)`` solves
  ``g''' - 8 xi g' - 4 g = 0`` (the derivative of (4.9)), since the square of any
  solution of ``w'' = z w`` obeys ``y''' - 4 z y' - 2 y = 0``. So
  ``f(xi) = k int_xi^inf Ai(c y)^2 dy = (k/c) (Ai'(z)^2 - z Ai(z)^2)``, z = c xi.
  The paper's footnote prints ``Ai^2(-2^(1/3) y)``; with that sign the integrand
  oscillates ahead of the wave and f does not decay, and it does not solve (4.9) as
  printed (``printed_airy_f`` is kept for the tests that show it). The rear of the wave,
  where f' = f'' = 0, is at the first zero a1 of Ai: ``xi0 = a1 / c``.

References
----------
.. [1] E. J. Hinch and S. Saint-Jean, "The fragmentation of a line of balls by an
   impact", Proc. R. Soc. Lond. A 455, 3201-3220 (1999), section 4d.
.. [2] M. Abramowitz and I. A. Stegun, Handbook of Mathematical Functions (1965),
   10.4.57 (products of Airy functions).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from scipy import integrate, optimize, special

__all__ = [
    "C",
    "PAPER_ENERGY_SHARE",
    "AirySolution",
    "ShootingSolution",
    "airy",
    "printed_airy_f",
    "residual",
    "shift_and_beta",
    "shoot",
    "wkb_exponent",
]

#: The scale of the Airy argument, 2^(1/3).
C = 2.0 ** (1.0 / 3.0)
#: The paper's normalization: the wave carries 96.2% of the impact energy 1/2.
PAPER_ENERGY_SHARE = 0.962
#: The paper's starting point of the backward shooting.
PAPER_XI_INF = 3.0


def wkb_exponent() -> float:
    """The coefficient in ``exp(-(4/3) sqrt(2) xi^(3/2))``, the WKB decay of (4.9)."""
    return 4.0 / 3.0 * np.sqrt(2.0)


@dataclass(frozen=True)
class AirySolution:
    """The closed-form similarity solution ``f(xi) = (k/c)(Ai'(z)^2 - z Ai(z)^2)``.

    Attributes
    ----------
    k : float
        Amplitude fixed by the energy normalization.
    energy : float
        ``int_xi0^inf f'^2 dxi``.
    xi0 : float
        Rear of the wave, the maximum of f: ``a1 / 2^(1/3)``.
    f0 : float
        ``f(xi0)``, the maximum displacement.
    xi_peak, peak : float
        Where ``-f'`` is largest (``a1' / 2^(1/3)``, a1' the first zero of Ai') and its
        value.
    """

    k: float
    energy: float
    xi0: float
    f0: float
    xi_peak: float
    peak: float

    def derivatives(self, xi) -> np.ndarray:
        """f, f', f'', f''', f'''' at ``xi``; shape (5,) + shape of xi."""
        xi = np.asarray(xi, dtype=float)
        z = C * xi
        ai, aip, _, _ = special.airy(z)
        k = self.k
        f = k / C * (aip * aip - z * ai * ai)
        d1 = -k * ai * ai
        d2 = -2.0 * k * C * ai * aip
        d3 = -2.0 * k * C**2 * (aip * aip + z * ai * ai)
        d4 = -2.0 * k * C**3 * (4.0 * z * ai * aip + ai * ai)
        return np.stack([f, d1, d2, d3, d4])

    def f(self, xi) -> np.ndarray:
        return self.derivatives(xi)[0]

    def df(self, xi) -> np.ndarray:
        return self.derivatives(xi)[1]


def airy(energy_share: float = PAPER_ENERGY_SHARE) -> AirySolution:
    """The closed-form solution normalized to ``energy_share`` of the impact energy 1/2.

    Parameters
    ----------
    energy_share : float
        Share of the impact energy in the wave (0.962 in the paper).

    Returns
    -------
    AirySolution
    """
    a1 = float(special.ai_zeros(1)[0][0])
    a1p = float(special.ai_zeros(1)[1][0])
    energy = 0.5 * energy_share
    # int_xi0^inf Ai(c xi)^4 dxi = (1/c) int_a1^inf Ai(z)^4 dz
    ai4 = integrate.quad(lambda z: special.airy(z)[0] ** 4, a1, np.inf,
                         epsabs=1e-15, epsrel=1e-13, limit=400)[0]
    k = float(np.sqrt(energy * C / ai4))
    aip_a1 = float(special.airy(a1)[1])
    f0 = k / C * aip_a1**2   # Ai(a1) = 0
    peak = k * float(special.airy(a1p)[0]) ** 2
    return AirySolution(k=k, energy=energy, xi0=a1 / C, f0=f0, xi_peak=a1p / C, peak=peak)


def printed_airy_f(xi, k: float = 1.0) -> np.ndarray:
    """The paper's printed footnote form ``k int_xi^inf Ai^2(-2^(1/3) y) dy``, by quadrature.

    Kept only to show that it is not the decaying solution of (4.9): the integral to
    +inf does not converge (its integrand oscillates with slowly decaying amplitude), so
    it is cut at ``y = 40`` here.
    """
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    out = [k * integrate.quad(lambda y: special.airy(-C * y)[0] ** 2, x, 40.0, limit=2000)[0]
           for x in xi]
    return np.array(out)


def residual(derivatives: np.ndarray, xi) -> np.ndarray:
    """``f'''' - 8 xi f'' - 4 f'`` from stacked derivatives (f, f', f'', f''', f'''')."""
    d = np.asarray(derivatives, dtype=float)
    return d[4] - 8.0 * np.asarray(xi, dtype=float) * d[2] - 4.0 * d[1]


@dataclass(frozen=True)
class ShootingSolution:
    """The solution of (4.9) found by shooting backwards, on a grid.

    Attributes
    ----------
    xi : ndarray, shape (M,)
        Increasing, from ``xi0`` to ``xi_inf``.
    f, df, d2f, d3f : ndarray, shape (M,)
        The normalized solution and its derivatives there.
    xi0, f0 : float
        Where f' = 0 (the maximum of f, the rear of the wave) and f there.
    xi_peak, peak : float
        The maximum of ``-f'`` and where it is.
    energy : float
        ``int_xi0^xi_inf f'^2 dxi`` after normalization.
    xi_inf : float
    scale : float
        Factor applied to the unnormalized WKB start.
    """

    xi: np.ndarray
    f: np.ndarray
    df: np.ndarray
    d2f: np.ndarray
    d3f: np.ndarray
    xi0: float
    f0: float
    xi_peak: float
    peak: float
    energy: float
    xi_inf: float
    scale: float


def _rhs(xi, y):
    f, d1, d2, d3, _ = y
    return [d1, d2, d3, 8.0 * xi * d2 + 4.0 * d1, d1 * d1]


def shoot(xi_inf: float = PAPER_XI_INF, energy_share: float = PAPER_ENERGY_SHARE,
          *, rtol: float = 1e-12, points: int = 2001) -> ShootingSolution:
    """Solve (4.9) by shooting backwards from ``xi_inf``, as the paper describes.

    The start is the decaying WKB solution ``f = xi^(-1) E``, ``E = exp(-b xi^(3/2))``,
    ``b = (4/3) sqrt(2)``, with its first three derivatives from the same leading form;
    the growing and algebraic solutions it leaves out are of relative size
    ``xi_inf^(-3/2)`` at the start and shrink relative to the decaying one by
    ``exp(-b xi_inf^(3/2))`` on the way back, so the result converges quickly with
    ``xi_inf`` (about 1e-5 at the paper's xi_inf = 3). The integration stops at the
    rear xi0, where f' and f'' vanish together (f' = 0 there is a double zero, so the
    stop is the second zero of f'' on the way back); the energy ``int f'^2`` is integrated along and the solution is scaled to
    ``energy_share`` of 1/2.

    Parameters
    ----------
    xi_inf : float
        Starting point (3 in the paper).
    energy_share : float
    rtol : float
        Relative tolerance of the integrator (DOP853).
    points : int
        Size of the returned grid.

    Returns
    -------
    ShootingSolution
    """
    b = wkb_exponent()
    x = float(xi_inf)
    # f = x^-1 E with E = exp(-b x^1.5): derivatives of the leading WKB form, exactly.
    s = np.exp(-b * x**1.5)
    p1 = -1.5 * b * x**0.5            # (log E)'
    p2 = -0.75 * b * x**-0.5
    p3 = 0.375 * b * x**-1.5
    u = [1.0 / x, -1.0 / x**2, 2.0 / x**3, -6.0 / x**4]     # x^-1 and its derivatives
    e = [1.0, p1, p1 * p1 + p2, p1**3 + 3 * p1 * p2 + p3]   # E^-1 E^(j)
    f = u[0] * e[0]
    d1 = u[1] * e[0] + u[0] * e[1]
    d2 = u[2] * e[0] + 2 * u[1] * e[1] + u[0] * e[2]
    d3 = u[3] * e[0] + 3 * u[2] * e[1] + 3 * u[1] * e[2] + u[0] * e[3]
    y0 = np.array([f, d1, d2, d3]) * s
    y0 = y0 / abs(y0[0])   # start at unit size; the normalization fixes the scale

    # f' = -k Ai^2 <= 0 touches zero at xi0 without changing sign, so the rear is found
    # as the second zero of f'' on the way back (the first is the peak of -f').
    def rear(xi, y):
        return y[2]

    rear.terminal = 2
    rear.direction = 0
    sol = integrate.solve_ivp(_rhs, (x, -10.0), list(y0) + [0.0], method="DOP853",
                              rtol=rtol, atol=rtol * 1e-3, events=rear, dense_output=True)
    if sol.status != 1 or len(sol.t_events[0]) < 2:
        raise RuntimeError(f"shooting from xi_inf = {x}: no rear of the wave ({sol.message})")
    xi0 = float(sol.t_events[0][1])
    y_end = sol.sol(xi0)
    energy_raw = -float(y_end[4])          # integrated backwards: int_xi0^x f'^2
    scale = float(np.sqrt(0.5 * energy_share / energy_raw))
    grid = np.linspace(xi0, x, points)
    y = sol.sol(grid) * scale
    # the peak of -f': f'' = 0 inside the wave; refine on the dense output
    i = int(np.argmax(-y[1]))
    lo, hi = grid[max(i - 1, 0)], grid[min(i + 1, points - 1)]
    xi_peak = optimize.brentq(lambda z: sol.sol(z)[2], lo, hi, xtol=1e-15)
    peak = -float(sol.sol(xi_peak)[1]) * scale
    return ShootingSolution(
        xi=grid, f=y[0], df=y[1], d2f=y[2], d3f=y[3], xi0=xi0, f0=float(y_end[0]) * scale,
        xi_peak=float(xi_peak), peak=peak, energy=energy_raw * scale**2, xi_inf=x,
        scale=scale,
    )


def shift_and_beta() -> tuple[Fraction, Fraction]:
    """The shift delta and coefficient beta of section 4e, from the paper's two equations.

    Losing contact at ``n - t = delta`` gives ``2 delta^2 + 2 delta + 2/3 - beta = 0``;
    the rebound velocity ``-f(xi0) t^(-5/6) / 6`` gives ``2 delta^2 - beta = -1/6``.
    Subtracting, ``2 delta + 2/3 = 1/6``.

    Returns
    -------
    delta, beta : Fraction
        ``-1/4`` (a shift of 1/4 to the left, as used in Fig 5) and ``7/24``.
    """
    delta = (Fraction(1, 6) - Fraction(2, 3)) / 2
    beta = 2 * delta * delta + Fraction(1, 6)
    assert 2 * delta**2 + 2 * delta + Fraction(2, 3) - beta == 0
    return delta, beta
