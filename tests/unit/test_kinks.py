"""The damped step's switch filter (``_events._kinks_possible``) against the contact by
contact test written out in numpy.

A damped contact's load g = kappa c |c|^(alpha-1) + eta |c|^beta w may cross 0 inside a
step (the collision ends before the compression has gone, or a held contact pushes
again). The scan samples only the lanes the filter flags, so a lane it leaves out must
be one whose load stays on its side: bearing it above 0, held at 0 below 0, at both ends
of the step by more than the margin h |g'_1 - g'_0| / 2 that a parabola through the ends'
rates could dip. Every lane the law says may switch must be flagged, whichever of the
filter's loops a window takes.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
import pytest

from chainrun.solver import _state
from chainrun.solver._events import _kinks_possible
from chainrun.solver._jit import python_twin as twin

from helpers import DAMPED_LOOPS, WINDOW_ROWS

# what the filter reads of the state
Window = namedtuple("Window", "ints X0 V0 A0 X V A TR WP jbuf")


def _pow(a, e):
    """a^e by the C library's pow, lane by lane (0^e infinite for e < 0, as C's)."""
    return np.array([math.inf if x == 0.0 and y < 0.0 else math.pow(x, y)
                     for x, y in zip(a, np.broadcast_to(e, np.shape(a)))])


def _load_and_rate(kappa, alpha, eta, beta, c, w, a):
    """The load and its rate, lane by lane: g = kappa c |c|^(alpha-1) + eta |c|^beta w,
    g' = kappa alpha |c|^(alpha-1) w + eta (beta |c|^(beta-1) w^2 + |c|^beta a)."""
    ac = np.abs(c)
    fa = _pow(ac, alpha - 1.0)
    fb = _pow(ac, beta)
    with np.errstate(divide="ignore", invalid="ignore"):
        fbm = np.where(beta == 0.0, 0.0, beta * _pow(ac, beta - 1.0))
    g = kappa * c * fa + eta * fb * w
    dg = kappa * alpha * fa * w + eta * (fbm * w * w + fb * a)
    return g, dg


def _window(rng, m, alpha, beta, h):
    """A window of m balls at a step's two ends: compressions small and large, loads of
    both signs and near 0, undamped and held lanes; ``beta`` one number or one per lane."""
    ends = []
    X = np.cumsum(-rng.uniform(-1e-3, 2e-3, m))
    V = rng.normal(scale=0.3, size=m)
    A = rng.normal(scale=30.0, size=m)
    for _ in range(2):
        ends.append((X.copy(), V.copy(), A.copy()))
        # the step's end: the motion carried over h, with a kick to the rates
        X = X + V * h + 0.5 * A * h * h
        V = V + A * h + rng.normal(scale=0.05, size=m)
        A = A + rng.normal(scale=10.0, size=m)
    WP = np.zeros((WINDOW_ROWS, m))
    WP[_state.W_ALPHA] = alpha
    WP[_state.W_ETA] = rng.uniform(0.5, 2.0, m) * (rng.uniform(size=m) < 0.85)
    WP[_state.W_BETA] = beta
    WP[_state.W_HELD] = (rng.uniform(size=m) < 0.3).astype(float)
    TR = rng.uniform(1.0, 3.0, m)
    return ends, TR, WP


def _may_switch(ends, TR, WP, h):
    """The contact-by-contact test: (lanes that may switch, lanes clear of the margin by
    a millionth of it or more either way, where rounding cannot decide)."""
    nc = len(TR) - 1
    rows = [WP[r, :nc] for r in (_state.W_ALPHA, _state.W_ETA, _state.W_BETA, _state.W_HELD)]
    alpha, eta, beta, held = rows
    (X0, V0, A0), (X1, V1, A1) = ends
    g0, d0 = _load_and_rate(TR[:nc], alpha, eta, beta, X0[:-1] - X0[1:], V0[:-1] - V0[1:],
                            A0[:-1] - A0[1:])
    g1, d1 = _load_and_rate(TR[:nc], alpha, eta, beta, X1[:-1] - X1[1:], V1[:-1] - V1[1:],
                            A1[:-1] - A1[1:])
    margin = 0.5 * h * np.abs(d1 - d0)
    side = np.where(held != 0.0, -1.0, 1.0)
    clear = np.minimum(side * g0, side * g1) - margin  # > 0: stays on its side
    with np.errstate(invalid="ignore"):
        decided = ~np.isfinite(clear) | (np.abs(clear) > 1e-6 * np.maximum(margin, 1e-300))
    switch = (eta != 0.0) & ~(clear > 0.0)
    return switch, decided | (eta == 0.0)


@pytest.mark.parametrize("mode, alpha, beta", DAMPED_LOOPS)
def test_every_lane_that_may_switch_is_flagged(mode, alpha, beta):
    kinks = twin(_kinks_possible)
    flagged = kept = 0
    for seed in range(6):
        rng = np.random.default_rng(seed)
        m = 41
        h = 10.0 ** rng.uniform(-5.0, -3.0)
        lanes = beta if beta is not None else rng.choice([0.25, 0.5, 0.3], m)
        ends, TR, WP = _window(rng, m, alpha, lanes, h)
        if seed == 0:
            # a compression exactly 0 at the step's end: the rate is not a number there
            # (a damped lane bearing its load)
            X1 = ends[1][0]
            X1[6] = X1[5]
            WP[_state.W_ETA, 5] = 1.0
            WP[_state.W_HELD, 5] = 0.0
        ints = np.zeros(max(_state.I_MODE, _state.I_M) + 1, dtype=np.int64)
        ints[_state.I_M] = m
        ints[_state.I_MODE] = mode
        jbuf = np.full(m, 7, dtype=np.int64)
        (X0, V0, A0), (X1, V1, A1) = ends
        kinks(Window(ints, X0, V0, A0, X1, V1, A1, TR, WP, jbuf), h)
        want, decided = _may_switch(ends, TR, WP, h)
        got = jbuf[:m - 1] != 0
        assert set(np.unique(jbuf[:m - 1])) <= {0, 1}
        assert jbuf[m - 1] == 7  # the window's last ball has no lane after it
        assert not (want & ~got).any(), f"seed {seed}: lanes {np.flatnonzero(want & ~got)} missed"
        np.testing.assert_array_equal(got[decided], want[decided])
        assert not got[WP[_state.W_ETA, :m - 1] == 0.0].any()  # undamped: nothing to switch
        if seed == 0 and mode != _state.MODE_LINEAR:
            assert got[5]  # (a dashpot's rate is finite there)
        flagged += int(got.sum())
        kept += int((~got & (WP[_state.W_ETA, :m - 1] != 0.0)).sum())
    # the windows hold both kinds of damped lane: the filter has something to filter
    assert flagged > 20 and kept > 20
