"""The closed form of an isolated binary collision (``chainrun.solver._pairs``).

References: scipy's incomplete beta function and its inverse (the time to reach a
compression is one, see the module's docstring), the durations and maximum
compressions of ``closed_forms.py``, and an ODE integration of the pair's relative
coordinate by scipy.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.special import betainc, betaincinv

from chainrun.solver import _pairs
from closed_forms import contact_duration, max_compression


@numba.njit
def _betainc(a, b, x):
    return _pairs._betainc(a, b, x)


@numba.njit
def _greatest(kappa, alpha, im, w):
    return _pairs._greatest(kappa, alpha, im, w)


@numba.njit
def _relative(alpha, w, rmax, tau, s):
    return _pairs._relative(alpha, w, rmax, tau, s)


@pytest.mark.parametrize("a,b", [(0.4, 0.5), (0.5, 0.4), (0.5, 0.5), (1 / 3, 0.5),
                                 (0.5, 1 / 3), (0.25, 0.5), (0.5, 0.2)])
def test_incomplete_beta(a, b):
    # (near x = 1 the reference is 1 - I_{1-x}(b, a): scipy's I_x loses digits there)
    for x in np.concatenate([np.geomspace(1e-300, 1e-3, 30), np.linspace(0.0, 1.0, 201)]):
        assert _betainc(a, b, x) == pytest.approx(betainc(a, b, x), rel=1e-13, abs=1e-300)
    for x in 1.0 - np.geomspace(1e-15, 1e-3, 30):
        assert _betainc(a, b, x) == pytest.approx(1.0 - betainc(b, a, 1.0 - x), abs=2e-16)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0, 3.0, 1.2])
@pytest.mark.parametrize("mu,k,u", [(0.5, 1.0, 1.0), (0.5, 1.0, 1e-4), (2.0, 0.3, 7.0)])
def test_duration_and_greatest_compression(alpha, mu, k, u):
    rmax, tau = _greatest(k, alpha, 1.0 / mu, u)
    assert rmax == pytest.approx(max_compression(mu, k, alpha, u), rel=1e-14)
    assert tau == pytest.approx(contact_duration(mu, k, alpha, u), rel=1e-14)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0, 1.2])
def test_motion_is_the_inverse_incomplete_beta(alpha):
    # the time to reach u = r / r_max is (r_max / (p w)) B(u^p; 1/p, 1/2): scipy inverts it
    w, mu, k = 0.7, 0.5, 1.3
    p = alpha + 1.0
    rmax, tau = _greatest(k, alpha, 1.0 / mu, w)
    for s in np.concatenate([np.geomspace(1e-12, 0.5, 40) * tau,
                             (0.5 - np.geomspace(1e-12, 0.5, 40)) * tau,
                             np.linspace(0.5, 1.0, 41) * tau]):
        half = 0.5 * tau
        sg = min(s, tau - s)
        if sg < 0.5 * half:
            x = betaincinv(1.0 / p, 0.5, sg / half)
            z = 1.0 - x
        else:  # near the greatest compression, 1 - x from I_{1-x}(1/2, 1/p) = 1 - y
            z = betaincinv(0.5, 1.0 / p, (half - sg) / half)
            x = 1.0 - z
        r_ref = rmax * x ** (1.0 / p)
        rd_ref = math.copysign(w * math.sqrt(z), half - s)
        r, rd = _relative(alpha, w, rmax, tau, s)
        assert r == pytest.approx(r_ref, rel=1e-12, abs=1e-15 * rmax)
        assert rd == pytest.approx(rd_ref, rel=1e-11, abs=1e-12 * w)


@pytest.mark.parametrize("alpha", [1.5, 2.5])
def test_motion_against_an_ode_integration(alpha):
    w, mu, k = 1.1, 0.8, 2.0
    rmax, tau = _greatest(k, alpha, 1.0 / mu, w)

    def rhs(_t, y):
        return [y[1], -k / mu * max(y[0], 0.0) ** alpha]

    s = np.linspace(0.0, tau, 23)
    sol = solve_ivp(rhs, (0.0, tau), [0.0, w], method="DOP853", t_eval=s, rtol=1e-13,
                    atol=1e-15)
    for i, si in enumerate(s):
        r, rd = _relative(alpha, w, rmax, tau, si)
        assert r == pytest.approx(sol.y[0, i], abs=1e-10 * rmax)
        assert rd == pytest.approx(sol.y[1, i], abs=1e-10 * w)
    # the contact ends where the compression is back at 0, its rate reversed
    assert sol.y[0, -1] == pytest.approx(0.0, abs=1e-9 * rmax)
    assert sol.y[1, -1] == pytest.approx(-w, rel=1e-9)
