"""The damped force pass (``_forces._damped_forces``) against the force law written out
in numpy, lane by lane: kappa c |c|^(alpha-1) + eta |c|^beta w for a lane bearing its
load, 0 for one held at 0, the elastic force alone for an undamped lane, and the power
eta |c|^beta w^2 times the weight summed for the lanes bearing their load.

The pass has a loop for each law a window's lanes can share and one for the others;
each must give exactly what the law gives (the same operations in the same order),
whichever loop a window takes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chainrun.solver import _state
from chainrun.solver._forces import _damped_forces
from chainrun.solver._jit import python_twin as twin

from helpers import DAMPED_LOOPS, WINDOW_ROWS


def _window(rng, m, alpha, beta):
    """A window of m balls: compressions of both signs and exact zeros, undamped and
    held lanes; ``beta`` a number, or an array of one per lane."""
    X = np.cumsum(-rng.uniform(-1e-3, 2e-3, m))
    X[1::7] = X[0::7][: len(X[1::7])]  # some compressions exactly 0
    V = rng.normal(size=m)
    MK = rng.uniform(1.0, 3.0, m)
    WP = np.zeros((WINDOW_ROWS, m))
    WP[_state.W_ALPHA] = alpha
    WP[_state.W_ETA] = rng.uniform(0.1, 1.0, m) * (rng.uniform(size=m) < 0.8)
    WP[_state.W_BETA] = beta
    WP[_state.W_HELD] = (rng.uniform(size=m) < 0.15).astype(float)
    return X, V, MK, WP


def _law(X, V, MK, WP, DS, wgt, alpha):
    """The forces and the summed power, lane by lane, in numpy."""
    nc = len(X) - 1
    c = X[:nc] - X[1:]
    w = V[:nc] - V[1:]
    a = np.abs(c)
    power = np.sqrt(a) if alpha == 1.5 else np.array([math.pow(x, alpha - 1.0) for x in a])
    fe = np.where(c == 0.0, 0.0, c * power) * MK[:nc]
    beta = WP[_state.W_BETA, :nc]
    # (another exponent by the C library's pow, as the kernels take it: numpy's own
    # power may round its last bit otherwise)
    libm = np.array([math.pow(x, b) for x, b in zip(a, beta)])
    damping = np.select([beta == 0.0, beta == 0.25, beta == 0.5],
                        [np.ones(nc), np.sqrt(np.sqrt(a)), np.sqrt(a)], libm) * w
    eta = WP[_state.W_ETA, :nc]
    fd = eta * damping
    bearing = (eta != 0.0) & (WP[_state.W_HELD, :nc] == 0.0)
    F = np.where(eta == 0.0, fe, np.where(bearing, fe + fd, 0.0))
    ds = DS.copy()
    if wgt != 0.0:
        ds[:nc] = np.where(bearing, DS[:nc] + wgt * fd * w, DS[:nc])
    return F, ds


@pytest.mark.parametrize("mode, alpha, beta", DAMPED_LOOPS)
@pytest.mark.parametrize("wgt", [0.0, 0.03])
def test_the_damped_forces_are_the_law_exactly(mode, alpha, beta, wgt):
    forces = twin(_damped_forces)
    for seed in range(5):
        rng = np.random.default_rng(seed)
        m = 37
        lanes = beta if beta is not None else rng.choice([0.0, 0.25, 0.5, 0.3], m)
        X, V, MK, WP = _window(rng, m, alpha, lanes)
        F = np.full(m, 7.0)
        DS = rng.uniform(0.0, 1.0, m)
        want_F, want_DS = _law(X, V, MK, WP, DS, wgt, alpha)
        forces(X, V, F, MK, WP, DS, wgt, m, mode, alpha)
        np.testing.assert_array_equal(F[:m - 1], want_F[:m - 1])
        assert F[m - 1] == 7.0  # the window's last ball has no lane after it
        np.testing.assert_array_equal(DS, want_DS)
