"""A step from a contact's closing or to its opening: DOP853's error estimate there in
closed form, which sizes those steps (``_steppers._branch_step``)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate._ivp import dop853_coefficients as dop
from scipy.integrate._ivp.rk import rk_step

from chainrun.solver import _generated
from chainrun.solver._jit import python_twin as twin


def _estimate(k: np.ndarray, h: float) -> float:
    """scipy's DOP853 error estimate of one component from its stages k (scale 1)."""
    e5 = k @ dop.E5
    e3 = k @ dop.E3
    return abs(h) * e5 * e5 / np.sqrt(e5 * e5 + 0.01 * e3 * e3)


@pytest.mark.parametrize("a", [0.25, 0.5, 1.5, 2.5, 1.0 / 3.0])
@pytest.mark.parametrize("h", [0.03, 0.4, 2.0])
@pytest.mark.parametrize("at_end", [False, True])
def test_the_branch_estimate_is_scipys_step(a, h, at_end):
    """A ball whose acceleration A t^a begins at the step's start (a contact closing at
    compression 0), or A (h - t)^a vanishes at its end (one opening): scipy's own
    DOP853 step of that motion from rest, its stages and error estimate per component,
    against A h^(a + 1) g_v and A h^(a + 2) g_x of the closed form the solver sizes
    such steps by."""
    amp = 3.0

    def fun(t, y):
        return np.array([y[1], amp * ((h - t) if at_end else t) ** a])

    n = dop.N_STAGES
    k = np.zeros((n + 1, 2))
    rk_step(fun, 0.0, np.zeros(2), fun(0.0, np.zeros(2)), h, dop.A[:n, :n], dop.B, dop.C[:n], k)
    gv, gx = twin(_generated._branch_error)(a, at_end)
    assert amp * h ** (a + 1.0) * gv == pytest.approx(_estimate(k[:, 1], h), rel=1e-12)
    assert amp * h ** (a + 2.0) * gx == pytest.approx(_estimate(k[:, 0], h), rel=1e-12)


@pytest.mark.parametrize("a", [0.0, 1.0, 2.0, 3.0])
@pytest.mark.parametrize("at_end", [False, True])
def test_a_polynomial_acceleration_leaves_no_estimate(a, at_end):
    """From a constant, linear, quadratic or cubic acceleration the step's estimate is 0
    (DOP853's embedded rules integrate them exactly): to rounding."""
    gv, gx = twin(_generated._branch_error)(a, at_end)
    assert abs(gv) < 1e-14
    assert abs(gx) < 1e-14
