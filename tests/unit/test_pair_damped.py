"""An isolated damped collision's outcome and interior (``chainrun.solver._pair_damped``).

References: ``restitution.scaled_collision`` (scipy's DOP853 with its own event
location, and the linear spring-dashpot's closed form), and a scipy integration of
the unscaled relative motion with its force held at 0 once it would pull.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from chainrun.solver import _pair_damped, restitution


@numba.njit
def _walk(g, alpha, beta, tau_stop):
    return _pair_damped._walk(g, alpha, beta, tau_stop)


@numba.njit
def _outcome(kappa, alpha, eta, beta, im, w):
    return _pair_damped._damped_outcome(kappa, alpha, eta, beta, im, w)


@numba.njit
def _relative(alpha, beta, g, w, d, tu, ru, e, s):
    return _pair_damped._damped_relative(alpha, beta, g, w, d, tu, ru, e, s)


LAWS = [(1.0, 0.0), (1.5, 0.5), (1.5, 0.25), (1.5, 0.0), (2.0, 0.5), (3.0, 1.0)]


@pytest.mark.parametrize("alpha,beta", LAWS)
@pytest.mark.parametrize("g", [1e-3, 0.05, 0.7, 3.0])
def test_the_walk_ends_where_the_restitution_module_does(alpha, beta, g):
    e_ref, tau_ref = restitution.scaled_collision(g, alpha, beta)
    tau, s, u, ended = _walk(g, alpha, beta, math.inf)
    assert ended
    assert -u == pytest.approx(e_ref, rel=1e-11, abs=1e-14)
    assert tau == pytest.approx(tau_ref, rel=1e-10)
    # the load vanishes there: s^alpha = -g s^beta s'
    assert s > 0.0
    assert s ** alpha == pytest.approx(-g * s ** beta * u, rel=1e-9)


def test_a_walk_stopped_short_of_the_end_does_not_end():
    tau_end = _walk(0.3, 1.5, 0.5, math.inf)[0]
    tau, _s, _u, ended = _walk(0.3, 1.5, 0.5, 0.5 * tau_end)
    assert not ended and tau == 0.5 * tau_end


def _held_motion(kappa, alpha, eta, beta, mu, w, times):
    """r(t), r'(t) of the law by scipy from a series start (as restitution), to the
    zero of its load, located by scipy's event search; from there in free flight."""
    def load(_t, y):
        r, rd = y
        return kappa * math.copysign(abs(r) ** alpha, r) + eta * abs(r) ** beta * rd

    def rhs(t, y):
        return [y[1], -load(t, y) / mu]

    load.terminal = True
    load.direction = -1.0
    t0 = 1e-9 / w
    a1 = -eta * w ** beta / (mu * (beta + 1.0) * (beta + 2.0))
    a2 = -kappa * w ** (alpha - 1.0) / (mu * (alpha + 1.0) * (alpha + 2.0))
    y0 = [w * (t0 + a1 * t0 ** (beta + 2.0) + a2 * t0 ** (alpha + 2.0)),
          w * (1.0 + a1 * (beta + 2.0) * t0 ** (beta + 1.0)
               + a2 * (alpha + 2.0) * t0 ** (alpha + 1.0))]
    sol = solve_ivp(rhs, (t0, 10 * times[-1]), y0, method="DOP853", rtol=1e-13,
                    atol=1e-20, events=load, dense_output=True)
    tu = sol.t_events[0][0]
    ru, rdu = sol.y_events[0][0]
    inside = times < tu
    r = np.where(inside, 0.0, ru + rdu * (times - tu))
    rd = np.where(inside, 0.0, rdu)
    r[inside], rd[inside] = sol.sol(times[inside])
    return r, rd


@pytest.mark.parametrize("alpha,beta", [(1.0, 0.0), (1.5, 0.5), (2.0, 0.25)])
def test_the_interior_against_an_integration_of_the_clipped_law(alpha, beta):
    kappa, eta, m1, m2, w = 2.0, 0.6, 1.0, 3.0, 0.7
    im = 1.0 / m1 + 1.0 / m2
    d, g, tu, ru, e, tau = _outcome(kappa, alpha, eta, beta, im, w)
    assert e == pytest.approx(restitution.restitution(eta, beta, kappa, alpha, 1.0 / im, w),
                              rel=1e-11)
    assert tu == pytest.approx(restitution.contact_duration(eta, beta, kappa, alpha,
                                                            1.0 / im, w), rel=1e-10)
    # after the unload the balls part at e w, and the compression reaches 0 at tau
    assert ru > 0.0 and tau == pytest.approx(tu + ru / (e * w), rel=1e-14)
    times = np.array([0.01, 0.2, 0.5, 0.8, 0.99, 1.0, 1.2]) * tu
    times = np.sort(np.append(times, 0.5 * (tu + tau)))
    r_ref, rd_ref = _held_motion(kappa, alpha, eta, beta, 1.0 / im, w, times)
    for t, r1, rd1 in zip(times, r_ref, rd_ref):
        r, rd = _relative(alpha, beta, g, w, d, tu, ru, e, t)
        assert r == pytest.approx(r1, rel=1e-9, abs=1e-12 * d)
        assert rd == pytest.approx(rd1, rel=1e-9, abs=1e-12 * w)


def test_an_undamped_limit_lasts_as_the_elastic_contact():
    # G -> 0: e -> 1 and the duration that of the elastic contact
    tau, _s, u, ended = _walk(1e-9, 1.5, 0.5, math.inf)
    e_ref, tau_ref = restitution.scaled_collision(0.0, 1.5, 0.5)
    assert ended and -u == pytest.approx(e_ref, abs=1e-8)
    assert tau == pytest.approx(tau_ref, rel=1e-8)
