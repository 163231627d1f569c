"""One damped collision of two bodies: its coefficient of restitution and duration.

This module owns the two-body physics behind the damped contact law of
``chainrun.solver.model``, in any consistent units. The compression delta of two
bodies of reduced mass ``mu = m_1 m_2 / (m_1 + m_2)`` (a ball on a wall: its mass),
meeting at relative speed v > 0, obeys

    mu delta'' = -max(0, kappa delta^alpha + eta delta^beta delta'),
    delta(0) = 0,   delta'(0) = v,

and the contact ends at the first t > 0 where the force reaches 0 (for beta = 0 it
jumps to eta v at t = 0; for a damped contact the end comes before delta = 0). The
coefficient of restitution is ``e = -delta'(t_end) / v``.

Scaled form. With the length ``D = (mu v^2 / kappa)^(1/(alpha+1))`` and the time
``D / v``, s = delta / D obeys

    s'' = -max(0, s^alpha + G s^beta s'),   s(0) = 0,  s'(0) = 1,
    G = eta D^(beta+1) / (mu v),

so e depends on (alpha, beta, G) alone, and on the speed only through G, which is
proportional to ``v^((2 beta + 1 - alpha)/(alpha + 1))``: e is independent of the
impact speed exactly when ``beta = (alpha - 1)/2``. Then ``G = eta / sqrt(mu kappa)``.

The named laws (``law_exponent``): ``"dashpot"`` (beta = 0; with alpha = 1 the
spring-dashpot, e independent of speed), ``"kuwabara-kono"`` (viscoelastic Hertz,
beta = 1/2; e falls with the speed), ``"tsuji"`` (beta = (alpha - 1)/2, 1/4 for Hertz;
e independent of speed).

Closed form: alpha = 1, beta = 0. With gamma = G/2 (the rate eta / (2 mu) in units of
the frequency sqrt(kappa/mu)), delta is a damped oscillation and the force
``kappa delta + eta delta'`` is ``-mu delta''``, which vanishes first at

    tau_c = 2 atan2(w, gamma) / w,          w = sqrt(1 - gamma^2)    (gamma < 1),
    tau_c = 2 / gamma = 2                                             (gamma = 1),
    tau_c = 2 atanh(W / gamma) / W,         W = sqrt(gamma^2 - 1)    (gamma > 1),

in units of sqrt(mu/kappa), and there ``delta' = -v exp(-gamma tau_c)`` exactly, so
``e = exp(-gamma tau_c)``. (Under-damped: delta'' = 0 where sin(w t + 2 phi) = 0 with
tan phi = gamma/w, i.e. w t = pi - 2 phi = 2 atan(w/gamma); there cos(w t) -
(gamma/w) sin(w t) = -1. Over-damped: the same with w = i W, tanh(W t/2) = W/gamma.)
e falls from 1 at G = 0 through e^-2 at critical damping (G = 2) to 0 as G -> inf
(e ~ 1/G^2), monotonically, so every e in (0, 1] has one damping; the contact ends
before delta = 0 (the force of the unclipped law turns negative), and the duration is
shorter than pi sqrt(mu/kappa). This is the result of Schwager and Poeschel (2007),
who showed that the coefficient usually quoted for this model, from the return to
delta = 0, is wrong for the force that never pulls.

Other laws: an integration of the scaled equation by scipy's DOP853 (order 8) with
``rtol = RTOL`` and ``atol = 1e-20``, ending on the force's zero located by scipy's
event search on the step's dense output. It starts at a small tau_0 from the series
``s = tau - G tau^(beta+2)/((beta+1)(beta+2)) - tau^(alpha+2)/((alpha+1)(alpha+2))``
(whose neglected terms are of relative size (G tau_0^(beta+1) + tau_0^(alpha+1))^2,
below 1e-16), because the law is not smooth at s = 0 for non-integer exponents, where
a Runge-Kutta step loses its order. The inverse (``damping_for_restitution``) solves
e(G) = e by ``brentq`` in log G; G is cached per (alpha, beta, e).

Accuracy, measured by ``python -m chainrun.solver.restitution`` (``_measure``): over
alpha in {1, 1.5, 2, 3}, beta in {0, 1/4, 1/2, (alpha-1)/2} and G from 1e-3 to 30, e
differs from its value at rtol = 2.2e-14 (scipy's floor) by at most 1.3e-12
(relative), and t_end by at most 2e-12 for G <= 5 (5e-10 at G = 30, alpha = 3, where
e = 1e-6 and the force creeps to its zero, so that its instant is ill-conditioned); at
alpha = 1, beta = 0 the integration meets the closed form to 1.1e-13 in e and 1.1e-11
in t_end; at small G the slope of 1 - e meets first-order perturbation theory,
``1 - e = 2 G s_m^(beta+1) B((beta+1)/p, 3/2) / p + ...`` (p = alpha + 1,
s_m = (p/2)^(1/p); for Kuwabara-Kono the constant 1.15344 of Schwager and Poeschel
1998), to 1e-8. So e from the integration is trusted to 2e-12, and
``damping_for_restitution`` gives a damping whose e is the one asked for to that
accuracy (``tests/unit/test_restitution.py`` checks 1e-10 and speed independence to 1e-9).

References
----------
T. Schwager and T. Poeschel, "Coefficient of normal restitution of viscous particles
and cooling rate of granular gases", Phys. Rev. E 57, 650-654 (1998).
T. Schwager and T. Poeschel, "Coefficient of restitution and linear-dashpot model
revisited", Granular Matter 9, 465-469 (2007).
G. Kuwabara and K. Kono, "Restitution coefficient in a collision between two spheres",
Jpn. J. Appl. Phys. 26, 1230 (1987).
Y. Tsuji, T. Tanaka and T. Ishida, "Lagrangian numerical simulation of plug flow of
cohesionless particles in a horizontal pipe", Powder Technology 71, 239-250 (1992).
"""

from __future__ import annotations

import functools
import math

__all__ = ["LAWS", "RTOL", "contact_duration", "damping_for_restitution", "is_speed_free",
           "law_exponent", "restitution", "scaled_collision", "scaled_damping"]

#: The named damping laws and their exponent beta (of the contact's alpha).
LAWS = ("dashpot", "kuwabara-kono", "tsuji")
#: Relative tolerance of the scaled integration (DOP853 steps).
RTOL = 1e-13
#: Largest scaled damping G the inverse searches (e is about 1/G^2 there: < 1e-16).
_G_MAX = 1e9


def law_exponent(law: str, alpha: float) -> float:
    """The damping exponent beta of a named law for the contact exponent ``alpha``.

    ``"dashpot"``: 0; ``"kuwabara-kono"``: 1/2; ``"tsuji"``: (alpha - 1)/2.

    Raises
    ------
    ValueError
        For any other name.
    """
    if law == "dashpot":
        return 0.0
    if law == "kuwabara-kono":
        return 0.5
    if law == "tsuji":
        return (float(alpha) - 1.0) / 2.0
    raise ValueError(f"unknown damping law {law!r} (known: {', '.join(map(repr, LAWS))})")


def is_speed_free(alpha: float, beta: float) -> bool:
    """Whether e does not depend on the impact speed: ``beta == (alpha - 1)/2``."""
    return float(beta) == (float(alpha) - 1.0) / 2.0


def _check_positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    return value


def _check_law(damping, damping_exponent, stiffness, alpha, reduced_mass, speed):
    damping, beta = float(damping), float(damping_exponent)
    for name, value in (("damping", damping), ("damping_exponent", beta)):
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
    alpha = float(alpha)
    if not (math.isfinite(alpha) and alpha >= 1.0):
        raise ValueError(f"alpha must be a finite number >= 1, got {alpha!r}")
    return (damping, beta, _check_positive("stiffness", stiffness), alpha,
            _check_positive("reduced_mass", reduced_mass), _check_positive("speed", speed))


def _length(stiffness: float, alpha: float, reduced_mass: float, speed: float) -> float:
    """D = (mu v^2 / kappa)^(1/(alpha+1)): the scale of the largest compression."""
    return (reduced_mass * speed * speed / stiffness) ** (1.0 / (alpha + 1.0))


def scaled_damping(damping: float, damping_exponent: float, stiffness: float, alpha: float,
                   reduced_mass: float, speed: float) -> float:
    """G = eta D^(beta+1) / (mu v): the one parameter of the scaled collision."""
    eta, beta, kappa, alpha, mu, v = _check_law(damping, damping_exponent, stiffness, alpha,
                                                reduced_mass, speed)
    return eta * _length(kappa, alpha, mu, v) ** (beta + 1.0) / (mu * v)


def _linear(g: float) -> tuple[float, float]:
    """(e, tau_c) of the linear spring-dashpot in closed form (module docstring)."""
    gamma = 0.5 * g
    if gamma < 1.0:
        w = math.sqrt((1.0 - gamma) * (1.0 + gamma))
        tau = 2.0 * math.atan2(w, gamma) / w
    elif gamma == 1.0:
        tau = 2.0
    else:
        big = math.sqrt((gamma - 1.0) * (gamma + 1.0))
        tau = 2.0 * math.atanh(big / gamma) / big
    return math.exp(-gamma * tau), tau


def _elastic_duration(alpha: float) -> float:
    """tau_c of the undamped scaled collision: 2 s_m B(1/p, 1/2) / p, p = alpha + 1."""
    from scipy.special import beta as beta_fn

    p = alpha + 1.0
    s_max = (p / 2.0) ** (1.0 / p)
    return 2.0 * s_max * beta_fn(1.0 / p, 0.5) / p


def _integrate(g: float, alpha: float, beta: float, rtol: float) -> tuple[float, float]:
    """(e, tau_end) of the scaled collision by DOP853, from the series start."""
    import numpy as np
    from scipy.integrate import solve_ivp

    # Start where the series' neglected terms are ~1e-16 relative (module docstring).
    eps = 1e-8
    tau0 = eps ** (1.0 / (alpha + 1.0))
    if g > 0.0:
        tau0 = min(tau0, (eps / g) ** (1.0 / (beta + 1.0)))
    a1 = -g / ((beta + 1.0) * (beta + 2.0))
    a2 = -1.0 / ((alpha + 1.0) * (alpha + 2.0))
    s0 = tau0 + a1 * tau0 ** (beta + 2.0) + a2 * tau0 ** (alpha + 2.0)
    v0 = 1.0 + a1 * (beta + 2.0) * tau0 ** (beta + 1.0) + a2 * (alpha + 2.0) * tau0 ** (alpha + 1.0)

    def force(s, ds):
        # the law's smooth continuation (no clipping): integration stops at its zero
        return math.copysign(abs(s) ** alpha, s) + g * abs(s) ** beta * ds

    def rhs(t, y):
        return np.array([y[1], -force(y[0], y[1])])

    def ends(t, y):
        return force(y[0], y[1])

    def touches(t, y):  # for beta >= alpha the force may vanish only with s
        return y[0]

    ends.terminal = touches.terminal = True
    ends.direction = touches.direction = -1.0
    sol = solve_ivp(rhs, (tau0, 1e6), [s0, v0], method="DOP853",
                    rtol=rtol, atol=1e-20, events=(ends, touches))
    hits = [(t[0], y[0]) for t, y in zip(sol.t_events, sol.y_events) if len(t)]
    if sol.status != 1 or not hits:
        raise RuntimeError(f"the scaled collision (G = {g!r}, alpha = {alpha!r}, "
                           f"beta = {beta!r}) did not end: {sol.message}")
    tau, y = min(hits, key=lambda h: h[0])
    return -float(y[1]), float(tau)


@functools.lru_cache(maxsize=4096)
def scaled_collision(g: float, alpha: float, beta: float, rtol: float = RTOL
                     ) -> tuple[float, float]:
    """(e, tau_end) of the scaled collision with damping G (module docstring).

    In closed form for alpha = 1, beta = 0; for G = 0, e = 1 and the elastic duration;
    otherwise by the integration.
    """
    g, alpha, beta = float(g), float(alpha), float(beta)
    if alpha == 1.0 and beta == 0.0:
        return _linear(g)
    if g == 0.0:
        return 1.0, _elastic_duration(alpha)
    return _integrate(g, alpha, beta, rtol)


def restitution(damping: float, damping_exponent: float, stiffness: float, alpha: float,
                reduced_mass: float, speed: float) -> float:
    """The coefficient of restitution e of a collision at relative speed ``speed``.

    Parameters
    ----------
    damping, damping_exponent : float
        eta >= 0 and beta >= 0 of the law ``kappa delta^alpha + eta delta^beta delta'``.
    stiffness, alpha : float
        kappa > 0 and alpha >= 1.
    reduced_mass : float
        ``m_1 m_2 / (m_1 + m_2)``; for a ball on a wall, its mass.
    speed : float
        The relative speed at first touch, > 0.
    """
    g = scaled_damping(damping, damping_exponent, stiffness, alpha, reduced_mass, speed)
    return scaled_collision(g, float(alpha), float(damping_exponent))[0]


def contact_duration(damping: float, damping_exponent: float, stiffness: float,
                     alpha: float, reduced_mass: float, speed: float) -> float:
    """How long the contact of ``restitution``'s collision lasts: from first touch to
    the force's return to 0. Arguments as for ``restitution``."""
    g = scaled_damping(damping, damping_exponent, stiffness, alpha, reduced_mass, speed)
    tau = scaled_collision(g, float(alpha), float(damping_exponent))[1]
    return tau * _length(float(stiffness), float(alpha), float(reduced_mass),
                         float(speed)) / float(speed)


#: below this 1 - e, the damping is that of first order in G (_elastic_slope)
_NEAR_ELASTIC = 1e-9


def _elastic_slope(alpha: float, beta: float) -> float:
    """c in 1 - e = c G + O(G^(min(2, (alpha + 1)/(alpha - beta)))): the energy the
    damping takes along the elastic collision over twice its energy,
    ``2 (p/2)^((beta+1)/p) B((beta+1)/p, 3/2) / p`` with p = alpha + 1 (for the
    Kuwabara-Kono law at alpha = 3/2, Schwager and Poeschel's 1.15344). Below
    1 - e = 1e-9 the neglected term is at most ~1e-12 in e, the integration's own
    accuracy, which cannot resolve 1 - e there."""
    from scipy.special import beta as beta_fn

    p = alpha + 1.0
    return 2.0 * (p / 2.0) ** ((beta + 1.0) / p) * beta_fn((beta + 1.0) / p, 1.5) / p


@functools.lru_cache(maxsize=4096)
def _scaled_inverse(e: float, alpha: float, beta: float) -> float:
    """The G whose scaled collision has restitution e (0 < e < 1)."""
    from scipy.optimize import brentq

    if 1.0 - e < _NEAR_ELASTIC:
        return (1.0 - e) / _elastic_slope(alpha, beta)
    if alpha == 1.0 and beta == 0.0:
        def miss(log_g):
            return _linear(math.exp(log_g))[0] - e
    else:
        def miss(log_g):
            return scaled_collision(math.exp(log_g), alpha, beta)[0] - e
    # bracket in log G: e(G) falls from 1 (G -> 0) to 0 (G -> inf), monotonically
    lo, hi = -2.0, 2.0
    while miss(lo) < 0.0:
        lo -= 4.0
    while miss(hi) > 0.0:
        hi += 4.0
        if hi > math.log(_G_MAX):
            raise ValueError(f"restitution {e!r} needs a damping beyond reach")
    return math.exp(brentq(miss, lo, hi, xtol=1e-15, rtol=8.9e-16, maxiter=200))


def damping_for_restitution(e, law: str, stiffness, alpha, reduced_mass, speed=None):
    """The damping eta that gives a collision the coefficient of restitution ``e``.

    Every argument but ``law`` may be an array (they broadcast); the scaled inverse is
    solved once for each distinct pair (e, alpha), so a long line of alike contacts
    costs one solve.

    Parameters
    ----------
    e : float or array_like
        0 < e <= 1 (1 gives 0: elastic).
    law : {"dashpot", "kuwabara-kono", "tsuji"}
        Sets the damping exponent (``law_exponent``).
    stiffness, alpha, reduced_mass : float or array_like
        As for ``restitution``.
    speed : float or array_like, optional
        The impact speed at which the collision has restitution ``e``. Needed unless
        e does not depend on it (``is_speed_free``: tsuji, the dashpot with alpha = 1,
        Kuwabara-Kono with alpha = 2), where the damping is ``G sqrt(mu kappa)``.

    Returns
    -------
    float or ndarray
        eta, for the exponent ``law_exponent(law, alpha)``; a float if every argument
        is a scalar.

    Raises
    ------
    ValueError
        An unknown law, e outside (0, 1], a missing speed where e depends on it, or
        another argument out of range.
    """
    import numpy as np

    law_exponent(law, 1.0)  # an unknown law fails first
    scalar = all(np.ndim(a) == 0 for a in (e, stiffness, alpha, reduced_mass, speed))
    e, kappa, alpha, mu = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (
        e, stiffness, alpha, reduced_mass)))
    bad = ~(np.isfinite(e) & (e > 0.0) & (e <= 1.0))
    if bad.any():
        raise ValueError(f"the restitution must be in (0, 1], got {float(e[bad].flat[0])!r}")
    for name, a, low in (("stiffness", kappa, 0.0), ("reduced_mass", mu, 0.0)):
        if not np.all(np.isfinite(a) & (a > low)):
            raise ValueError(f"{name} must be a finite number > 0, got "
                             f"{float(a[~(np.isfinite(a) & (a > low))].flat[0])!r}")
    if not np.all(np.isfinite(alpha) & (alpha >= 1.0)):
        raise ValueError(f"alpha must be a finite number >= 1, got "
                         f"{float(alpha[~(np.isfinite(alpha) & (alpha >= 1.0))].flat[0])!r}")
    beta = np.vectorize(lambda a: law_exponent(law, a), otypes=[float])(alpha)
    free = beta == (alpha - 1.0) / 2.0
    damped = e < 1.0
    if speed is None:
        if np.any(damped & ~free):
            a = float(alpha[damped & ~free].flat[0])
            raise ValueError(f"the restitution of the {law} law (alpha = {a:g}) depends "
                             "on the impact speed: give the speed it refers to")
        v = np.ones_like(e)  # any speed: G does not depend on it
    else:
        v = np.broadcast_to(np.asarray(speed, dtype=float), e.shape)
        if not np.all(np.isfinite(v) & (v > 0.0)):
            raise ValueError(f"speed must be a finite number > 0, got "
                             f"{float(v[~(np.isfinite(v) & (v > 0.0))].flat[0])!r}")
    g = np.zeros(e.shape)
    pairs = np.stack([e[damped], alpha[damped], beta[damped]], axis=-1)
    if pairs.size:
        unique, back = np.unique(pairs, axis=0, return_inverse=True)
        solved = np.array([_scaled_inverse(float(ei), float(ai), float(bi))
                           for ei, ai, bi in unique])
        g[damped] = solved[back.reshape(-1)]
    length = (mu * v * v / kappa) ** (1.0 / (alpha + 1.0))
    eta = np.where(free, g * np.sqrt(mu * kappa), g * mu * v / length ** (beta + 1.0))
    return float(eta) if scalar else eta


def _measure() -> None:
    """Print the accuracy of the integration (``python -m chainrun.solver.restitution``)."""
    from scipy.special import beta as beta_fn

    worst_e = worst_t = 0.0
    for alpha in (1.0, 1.5, 2.0, 3.0):
        for beta in sorted({0.0, 0.25, 0.5, (alpha - 1.0) / 2.0}):
            for g in (1e-3, 1e-2, 0.1, 0.5, 1.0, 2.0, 5.0, 30.0):
                e, t = _integrate(g, alpha, beta, RTOL)
                e2, t2 = _integrate(g, alpha, beta, 2.2e-14)
                worst_e = max(worst_e, abs(e - e2) / e2)
                worst_t = max(worst_t, abs(t - t2) / t2)
    print(f"vs rtol 2.2e-14: e {worst_e:.2e}, duration {worst_t:.2e} (relative)")
    worst_e = worst_t = 0.0
    for g in (1e-4, 1e-2, 0.3, 1.0, 1.9, 2.0, 2.1, 5.0, 50.0):
        e, t = _integrate(g, 1.0, 0.0, RTOL)
        ec, tc = _linear(g)
        worst_e = max(worst_e, abs(e - ec) / ec)
        worst_t = max(worst_t, abs(t - tc) / tc)
    print(f"alpha = 1, beta = 0 vs the closed form: e {worst_e:.2e}, "
          f"duration {worst_t:.2e} (relative)")
    for alpha, beta in ((1.5, 0.5), (1.5, 0.25), (1.5, 0.0), (2.0, 0.5)):
        p = alpha + 1.0
        slope = 2.0 * (p / 2.0) ** ((beta + 1.0) / p) * beta_fn((beta + 1.0) / p, 1.5) / p
        g = 1e-5
        # Richardson on G and 2G removes the O(G^2) term
        d1 = 1.0 - _integrate(g, alpha, beta, RTOL)[0]
        d2 = 1.0 - _integrate(2 * g, alpha, beta, RTOL)[0]
        print(f"alpha = {alpha}, beta = {beta}: d(1-e)/dG = {(4 * d1 - d2) / (2 * g):.10f}, "
              f"perturbation {slope:.10f}")


if __name__ == "__main__":
    _measure()
