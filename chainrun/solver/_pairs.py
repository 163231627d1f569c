"""Isolated binary collisions in closed form.

Two free balls (or a ball and a wall) that meet with no third body able to reach
either of them while they touch collide exactly as the pair alone would. In their
relative coordinate r = x_l - x_r (the compression) the contact is the motion of one
mass mu = 1 / (1/m_l + 1/m_r) in the potential kappa r^p / p, p = alpha + 1, entered at
speed w: the energy gives the greatest compression, r_max^p = p mu w^2 / (2 kappa), and
the time to reach r is

    s(r) = (r_max / w) int_0^(r / r_max) du / sqrt(1 - u^p)
         = (r_max / (p w)) B(u^p; 1/p, 1/2),

an incomplete beta function, so the contact lasts tau = 2 r_max I / w with
I = sqrt(pi) Gamma(1 + 1/p) / Gamma(1/2 + 1/p), and ends with r = 0 and the relative
velocity reversed. Through the contact the centre of mass moves at its constant
velocity V, the left ball at x_l = X + f_l r and the right at x_r = X - f_r r
(f_l = m_r / (m_l + m_r), f_r = m_l / (m_l + m_r); a wall's f is 0).

A damped contact has no such closed form: its relative motion is integrated once, at
the meeting, to its unload (where the force would pull) and its coefficient of
restitution e, and again up to any instant inside asked for (``_pair_damped``). It
then ends as an elastic one does, the relative velocity reversed and times e, after
the unload is logged; it has dissipated all but e^2 of the relative motion's energy.

Such a contact is *sealed* (``SEALED``): the step loop applies it whole, logs its
close and open, and never integrates it. Since r >= 0 throughout, the left ball never
falls behind the centre of mass's line and the right ball never gets ahead of it: a
neighbour that stays clear of that line while the contact lasts cannot touch the pair
(``_clear_of``). A neighbour whose motion changes while a contact is sealed is checked
again, and where it could reach the pair the contact is taken back into the
integration at that instant (``_clusters._unseal``), from its exact state
(``_sealed_at``), as are the contacts next to a cluster.
"""

from __future__ import annotations

import math

from chainrun.solver._forces import _stored
from chainrun.solver._jit import kernel
from chainrun.solver._pair_damped import _damped_outcome, _damped_relative
from chainrun.solver._state import (
    B_IM, C_ALPHA, C_BETA, C_ETA, C_KAPPA, EPS, SEALED, SL_CMAX, SL_E, SL_G, SL_PH, SL_RU,
    SL_T0, SL_TAU, SL_TU, SL_V, SL_W, SL_X, _free_at,
)

_HALF_PI = 0.5 * math.pi


@kernel(inline="always")
def _lentz(e, c, d):
    """One term e of a continued fraction 1 / (1 + e1 / (1 + e2 / ...)) by the modified
    Lentz method: its (c, d) and the factor it multiplies the value by."""
    tiny = 1e-300
    d = 1.0 + e * d
    if abs(d) < tiny:
        d = tiny
    c = 1.0 + e / c
    if abs(c) < tiny:
        c = tiny
    d = 1.0 / d
    return c, d, c * d


@kernel
def _betainc(a, b, x):
    """The regularized incomplete beta function I_x(a, b), 0 <= x <= 1, a, b > 0: its
    continued fraction (DLMF 8.17.22) by the modified Lentz method, on whichever of
    x and 1 - x it converges fast for (DLMF 8.17.4), so that the smaller of I and
    1 - I is the one computed directly."""
    if x <= 0.0:
        return 0.0
    if x >= 1.0:
        return 1.0
    if x > (a + 1.0) / (a + b + 2.0):
        return 1.0 - _betainc(b, a, 1.0 - x)
    front = math.exp(a * math.log(x) + b * math.log1p(-x)
                     - (math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b))) / a
    # the fraction's first level, 1 / (1 - (a + b) x / (a + 1))
    c = 1.0
    d = 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) >= 1e-300 else 1e-300)
    h = d
    for m in range(1, 300):
        m2 = 2 * m
        c, d, step = _lentz(m * (b - m) * x / ((a + m2 - 1.0) * (a + m2)), c, d)
        h *= step
        c, d, step = _lentz(-(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0)), c, d)
        h *= step
        if abs(step - 1.0) < EPS:
            break
    return front * h


@kernel
def _phase(a, y, yc):
    """The angle phi in [0, pi/2] with I_{sin^2 phi}(a, 1/2) = y (yc = 1 - y, given
    apart for its accuracy near 1): the compression is r_max sin(phi)^(2a) and its
    rate w cos(phi) at the fraction y of the way to the greatest compression.

    Newton's method kept inside a bracket, on ln I near phi = 0 (I ~ phi^(2a) there)
    and on 1 - I = I_{cos^2 phi}(1/2, a) near pi/2 (linear there), so that each side
    keeps its relative accuracy."""
    if y <= 0.0:
        return 0.0
    if yc <= 0.0:
        return _HALF_PI
    beta = math.exp(math.lgamma(a) + math.lgamma(0.5) - math.lgamma(a + 0.5))
    low = y <= 0.5
    if low:
        phi = math.asin(min(1.0, (y * a * beta) ** (0.5 / a)))
    else:
        phi = max(0.0, _HALF_PI - 0.5 * yc * beta)
    lo = 0.0
    hi = _HALF_PI
    for _ in range(100):
        sn = math.sin(phi)
        cs = math.cos(phi)
        slope = 2.0 * sn ** (2.0 * a - 1.0) / beta if sn > 0.0 else math.inf
        if low:
            i = _betainc(a, 0.5, sn * sn)
            g = math.log(i) - math.log(y) if i > 0.0 else -math.inf
            dg = slope / i if i > 0.0 else math.inf
        else:
            g = yc - _betainc(0.5, a, cs * cs)
            dg = slope
        if g == 0.0:
            return phi
        if g < 0.0:
            lo = phi
        else:
            hi = phi
        nxt = phi - g / dg if math.isfinite(dg) and dg > 0.0 else 0.5 * (lo + hi)
        if not (lo < nxt < hi):
            nxt = 0.5 * (lo + hi)
        if abs(nxt - phi) <= 2.0 * EPS * phi or hi - lo <= 2.0 * EPS * hi:
            return nxt
        phi = nxt
    return phi


@kernel
def _duration_factor(alpha):
    """I = int_0^1 du / sqrt(1 - u^(alpha + 1)): the contact lasts 2 r_max I / w."""
    a = 1.0 / (alpha + 1.0)
    return math.exp(0.5 * math.log(math.pi) + math.lgamma(1.0 + a) - math.lgamma(0.5 + a))


@kernel
def _greatest(kappa, alpha, im, w):
    """(r_max, tau): the greatest compression and the duration of an elastic contact
    of stiffness kappa and exponent alpha between balls of inverse masses summing to
    im, entered at speed w > 0."""
    p = alpha + 1.0
    rmax = (p * w * w / (2.0 * kappa * im)) ** (1.0 / p)
    return rmax, 2.0 * rmax * _duration_factor(alpha) / w


@kernel
def _relative(alpha, w, rmax, tau, s):
    """(r, r') at s after the compression was 0 going in (0 <= s <= tau)."""
    half = 0.5 * tau
    back = s > half
    sg = tau - s if back else s
    if alpha == 1.0:
        ph = math.pi * sg / tau
        r = rmax * math.sin(ph)
        rd = w * math.cos(ph)
    else:
        ph = _phase(1.0 / (alpha + 1.0), sg / half, (half - sg) / half)
        r = rmax * math.sin(ph) ** (2.0 / (alpha + 1.0))
        rd = w * math.cos(ph)
    return r, -rd if back else rd


@kernel(inline="always")
def _fractions(S, j):
    """(f_l, f_r): the shares of the relative coordinate in the two balls' motion."""
    il = S.bp[B_IM, j]
    ir = S.bp[B_IM, j + 1]
    return il / (il + ir), ir / (il + ir)


@kernel(inline="always")
def _damped_seal(S, j):
    """Whether sealed contact j is damped (its sl rows SL_TU.. exist on a damped line
    only; an undamped contact there has G = 0)."""
    return S.sl.shape[0] > SL_G and S.sl[SL_G, j] > 0.0


@kernel
def _damped_at(S, j, s):
    """(r, r') of damped sealed contact j at s >= 0 after its compression was 0."""
    return _damped_relative(S.cp[C_ALPHA, j], S.cp[C_BETA, j], S.sl[SL_G, j], S.sl[SL_W, j],
                            S.sl[SL_CMAX, j], S.sl[SL_TU, j], S.sl[SL_RU, j],
                            S.sl[SL_E, j], s)


@kernel(inline="always")
def _unload_ahead(S, j):
    """Whether damped sealed contact j has yet to unload (with the compression left
    at its unload > 0: where the load vanishes only with it, there is none)."""
    return _damped_seal(S, j) and S.sl[SL_PH, j] == 0.0 and S.sl[SL_RU, j] > 0.0


@kernel(inline="always")
def _first_end(S, j):
    """When the heap next calls on sealed contact j: its unload, or its end (see
    _binary._sealed_end)."""
    if _unload_ahead(S, j):
        return S.sl[SL_T0, j] + S.sl[SL_TU, j]
    return S.sl[SL_T0, j] + S.sl[SL_TAU, j]


@kernel
def _sealed_lost(S, j, t):
    """The energy damped sealed contact j has dissipated by t (0 for an elastic one):
    what its relative motion came in with, less its relative kinetic and elastic
    energy then; all but e^2 of it once the contact has ended."""
    if not _damped_seal(S, j):
        return 0.0
    s = t - S.sl[SL_T0, j]
    if s <= 0.0:
        return 0.0
    im = S.bp[B_IM, j] + S.bp[B_IM, j + 1]
    w = S.sl[SL_W, j]
    e_in = 0.5 * w * w / im
    if s >= S.sl[SL_TAU, j]:
        e = S.sl[SL_E, j]
        return e_in * (1.0 - e * e)
    r, rd = _damped_at(S, j, s)
    return e_in - 0.5 * rd * rd / im - _stored(S, j, r)


@kernel(inline="always")
def _sealed_contact(S, b):
    """The sealed contact ball b is in, or -1."""
    if b >= 1 and S.cst[b - 1] == SEALED:
        return b - 1
    if b < S.cst.shape[0] and S.cst[b] == SEALED:
        return b
    return -1


@kernel
def _sealed_at(S, j, b, t):
    """(x, v) at t of ball b (j or j + 1) of sealed contact j: before the contact and
    after it, the straight lines the pair came in and leaves on."""
    s = t - S.sl[SL_T0, j]
    tau = S.sl[SL_TAU, j]
    w = S.sl[SL_W, j]
    if s <= 0.0:
        r, rd = w * s, w
    elif _damped_seal(S, j):
        r, rd = _damped_at(S, j, s)
    elif s >= tau:
        r, rd = -w * (s - tau), -w
    else:
        r, rd = _relative(S.cp[C_ALPHA, j], w, S.sl[SL_CMAX, j], tau, s)
    fl, fr = _fractions(S, j)
    xc = S.sl[SL_X, j] + S.sl[SL_V, j] * s
    if b == j:
        return xc + fl * r, S.sl[SL_V, j] + fl * rd
    return xc - fr * r, S.sl[SL_V, j] - fr * rd


@kernel
def _clear_of(S, j, a, t1, t2):
    """Whether free ball a, a neighbour of the pair of contact j in free flight (no
    external force), stays clear of the pair's centre of mass's line from t1 to t2,
    with a margin for the rounding of the positions; the line is that of a contact
    whose compression was 0 at sl[SL_T0, j], with centre sl[SL_X, j] then."""
    x0 = S.sl[SL_X, j]
    v = S.sl[SL_V, j]
    t0 = S.sl[SL_T0, j]
    worst = -math.inf
    scale = 0.0
    for t in (t1, t2):
        xa = _free_at(S, a, t)[0]
        xc = x0 + v * (t - t0)
        gap = xa - xc if a < j else xc - xa  # a compression: < 0 apart
        worst = max(worst, gap)
        scale = max(scale, abs(xa) + abs(xc) + abs(v * (t - t0))
                    + abs(S.bv[a] * (t - S.bt[a])))
    return worst < -64.0 * EPS * max(1.0, scale)


@kernel
def _closed_form(S, j, t):
    """Fill sl[:, j] for a contact between free balls j, j + 1 closing at t, or return
    False when it has no closed form (no stiffness, or a non-finite outcome). A
    compression r0 at t (within rounding of 0 where the heap predicted the meeting)
    is taken as the contact having begun r0 / w earlier."""
    kappa = S.cp[C_KAPPA, j]
    alpha = S.cp[C_ALPHA, j]
    im = S.bp[B_IM, j] + S.bp[B_IM, j + 1]
    if not (kappa > 0.0 and im > 0.0):
        return False
    xl, vl = _free_at(S, j, t)
    xr, vr = _free_at(S, j + 1, t)
    w = vl - vr
    if not w > 0.0:
        return False
    # (the rows of a damped line: its contacts' damping, and the unload of sl)
    damped = S.sl.shape[0] > SL_G and S.cp[C_ETA, j] > 0.0
    g = tu = ru = e = 0.0
    if damped:
        rmax, g, tu, ru, e, tau = _damped_outcome(kappa, alpha, S.cp[C_ETA, j],
                                                  S.cp[C_BETA, j], im, w)
    else:
        rmax, tau = _greatest(kappa, alpha, im, w)
    t0 = t - (xl - xr) / w
    if not (math.isfinite(tau) and tau > 0.0 and math.isfinite(t0 + tau)):
        return False
    fl, fr = _fractions(S, j)
    S.sl[SL_T0, j] = t0
    S.sl[SL_TAU, j] = tau
    S.sl[SL_X, j] = fr * (xl + vl * (t0 - t)) + fl * (xr + vr * (t0 - t))
    S.sl[SL_V, j] = fr * vl + fl * vr
    S.sl[SL_W, j] = w
    S.sl[SL_CMAX, j] = rmax
    if S.sl.shape[0] > SL_G:
        if damped:
            S.sl[SL_TU, j] = tu
            S.sl[SL_E, j] = e
            S.sl[SL_RU, j] = ru
            S.sl[SL_G, j] = g
        else:
            S.sl[SL_TU, j] = tau
            S.sl[SL_E, j] = 1.0
            S.sl[SL_RU, j] = 0.0
            S.sl[SL_G, j] = 0.0
        S.sl[SL_PH, j] = 0.0
    return True
