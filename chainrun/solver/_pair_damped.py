"""An isolated damped collision: its outcome and its interior, from the pair's own motion.

An isolated pair (``_pairs``) whose contact is damped moves in its relative coordinate
r = x_l - x_r as one mass mu = 1 / (1/m_l + 1/m_r) under the law's force, which is
held at 0 once it would pull:

    mu r'' = -max(0, kappa r^alpha + eta r^beta r'),   r(0) = 0,  r'(0) = w.

In the scaled variables of ``restitution`` (r = D s, t = (D / w) tau with
D = (mu w^2 / kappa)^(1/(alpha+1)), and G = eta D^(beta+1) / (mu w)),

    s'' = -(s |s|^(alpha-1) + G |s|^beta s')

until the load vanishes (the *unload*, at tau_u, with s_u > 0 and s'_u = -e: e is the
coefficient of restitution). From then the force is held at 0: the balls part at the
relative speed e w, and the compression reaches 0, where the contact opens, s_u / e
later (in tau). Where beta >= alpha the load can vanish only with s, and the contact
ends at s = 0.

``_walk`` integrates the scaled motion by DOP853 steps (``_generated._pair_step``, at
the tolerance ``PAIR_RTOL``) from the short series start that ``restitution`` uses
(the law is not smooth at s = 0 for non-integer exponents, where a Runge-Kutta step
loses its order), up to a given tau or to the unload, which it locates by the
Illinois variant of regula falsi on the length of the last step. A sealed contact
keeps the unload's instant, compression and e (``_damped_outcome``); its interior is
walked again wherever it is asked for (snapshots, sensors, a third ball's arrival).
The walk is checked against ``restitution.scaled_collision``, scipy's DOP853 with
its own event location (``tests/unit/test_pair_damped.py``).
"""

from __future__ import annotations

import math

from chainrun.solver._generated import _pair_step
from chainrun.solver._jit import kernel
from chainrun.solver._state import EPS

#: The series start's neglected terms are this squared, relative (as in ``restitution``).
_SERIES_EPS = 1e-8
#: Steps a walk may take; a scaled collision takes a few dozen.
_MAX_STEPS = 100000


@kernel(inline="always")
def _indicator(s, u, g, alpha, beta):
    """What turns <= 0 at the collision's end: the load over s^beta, which is smooth
    and positive while the contact pushes; s itself where beta >= alpha."""
    if beta >= alpha or not s > 0.0:
        return s
    return s ** (alpha - beta) + g * u


@kernel
def _walk(g, alpha, beta, tau_stop):
    """(tau, s, s', ended) of the scaled collision at tau_stop, or at its end if that
    comes first (ended True). NaN where the integration cannot go on."""
    a1 = -g / ((beta + 1.0) * (beta + 2.0))
    a2 = -1.0 / ((alpha + 1.0) * (alpha + 2.0))
    tau = _SERIES_EPS ** (1.0 / (alpha + 1.0))
    if g > 0.0:
        tau = min(tau, (_SERIES_EPS / g) ** (1.0 / (beta + 1.0)))
    tau = min(tau, tau_stop)
    s = tau + a1 * tau ** (beta + 2.0) + a2 * tau ** (alpha + 2.0)
    u = 1.0 + a1 * (beta + 2.0) * tau ** (beta + 1.0) + a2 * (alpha + 2.0) * tau ** (alpha + 1.0)
    h = tau
    for _ in range(_MAX_STEPS):
        if tau >= tau_stop:
            return tau, s, u, False
        last = tau + h >= tau_stop
        hh = tau_stop - tau if last else h
        s1, u1, err = _pair_step(s, u, hh, g, alpha, beta)
        if not err <= 1.0:
            h = hh * max(0.2, 0.9 * err ** -0.125) if math.isfinite(err) else 0.2 * hh
            if h < 4.0 * EPS * tau:
                break
            continue
        f1 = _indicator(s1, u1, g, alpha, beta)
        if f1 <= 0.0:
            return _land(s, u, tau, hh, f1, s1, u1, g, alpha, beta)
        tau = tau_stop if last else tau + hh
        s = s1
        u = u1
        h = hh * (10.0 if err == 0.0 else min(10.0, 0.9 * err ** -0.125))
    return math.nan, math.nan, math.nan, True


@kernel(inline="always")
def _land(s, u, tau, hb, fb, sb, ub, g, alpha, beta):
    """The end inside the step of length hb from (tau, s, s'): regula falsi (Illinois)
    on the step's length, each trial a step from the same start (shorter, so within
    the tolerance); the state where the indicator is first <= 0."""
    ha = 0.0
    fa = _indicator(s, u, g, alpha, beta)
    side = 0
    for _ in range(200):
        if hb - ha <= 4.0 * EPS * (tau + hb):
            break
        x = (ha * fb - hb * fa) / (fb - fa)
        if not ha < x < hb:
            x = 0.5 * (ha + hb)
        sx, ux, _e = _pair_step(s, u, x, g, alpha, beta)
        fx = _indicator(sx, ux, g, alpha, beta)
        if fx <= 0.0:
            hb, fb, sb, ub = x, fx, sx, ux
            if side == -1:
                fa *= 0.5
            side = -1
            if fx == 0.0:
                break
        else:
            ha, fa = x, fx
            if side == 1:
                fb *= 0.5
            side = 1
    return tau + hb, sb, ub, True


@kernel(inline="always")
def _damped_outcome(kappa, alpha, eta, beta, im, w):
    """(D, G, t_u, r_u, e, tau) of a damped contact entered at speed w > 0 between
    balls of inverse masses summing to im: the length scale, the scaled damping, the
    unload's instant and compression, the coefficient of restitution and the contact's
    whole duration (to its opening). NaN where the collision does not end."""
    mu = 1.0 / im
    d = (mu * w * w / kappa) ** (1.0 / (alpha + 1.0))
    g = eta * d ** (beta + 1.0) / (mu * w)
    tau, s, u, ended = _walk(g, alpha, beta, math.inf)
    e = -u
    if not (ended and math.isfinite(tau) and e > 0.0):
        return d, g, math.nan, math.nan, math.nan, math.nan
    tu = d / w * tau
    ru = d * s if s > 0.0 else 0.0
    return d, g, tu, ru, e, tu + ru / (e * w)


@kernel(inline="always")
def _damped_relative(alpha, beta, g, w, d, tu, ru, e, s):
    """(r, r') of a damped contact at s >= 0 after its compression was 0 going in."""
    if s >= tu:
        ew = e * w
        return ru - ew * (s - tu), -ew
    scale = d / w
    tau, sc, uc, ended = _walk(g, alpha, beta, s / scale)
    if ended:  # (within rounding of the unload): on the parting line from there
        return d * sc + w * uc * (s - scale * tau), w * uc
    return d * sc, w * uc
