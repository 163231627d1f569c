"""The passes of a series step that run across the window, against numpy."""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.solver import _generated, _state
from chainrun.solver._jit import python_twin as twin


@pytest.mark.parametrize("m", [1, 2, 11, 16, 17, 33, 48, 70])
@pytest.mark.parametrize("unit", [True, False])
@pytest.mark.parametrize("driven", [False, True])
def test_linear_orders_are_the_recurrence(m, unit, driven):
    """A linear line's orders, a tile of lanes at a time: each lane's compression c_k in
    the work tiles, its force kappa c_k, and each ball's term of order k + 2, the net
    force's over its mass and (k + 1)(k + 2), computed here order by order with numpy
    (the same operations: the same numbers), for windows that end inside a tile, on
    its edge and past it, and lanes without force between clusters; on a driven line
    the drive's term of each order added to its ball's."""
    pt, tile = _state.PT, _state.SERIES_TILE
    rng = np.random.default_rng(m)
    nc = m - 1
    cap = 96
    TX = np.zeros((pt + 1, cap))
    TX[:3, :m] = rng.normal(size=(3, m))
    MK = rng.uniform(0.5, 2.0, cap)
    MK[rng.random(cap) < 0.2] = 0.0  # lanes from a cluster's last ball to the next's first
    IM = np.ones(cap) if unit else rng.uniform(0.5, 2.0, cap)
    W = np.zeros(_state.TILE_STRIDE * (cap // tile + 1))
    G = np.zeros(cap)
    nd = 1 if driven else 0
    # the drives as the kernels keep them (_state): PT + 1 terms a drive, and a drive's
    # piece and its ball's compact index
    DT = rng.normal(size=nd * (pt + 1))
    DC = np.array([0, m // 2] * nd, dtype=np.int64)
    twin(_generated._linear_orders)(TX, W, G, MK, IM, nc, unit, DT, DC)

    T = np.zeros((pt + 1, m))
    T[:3] = TX[:3, :m]
    lanes = np.arange(nc)
    tiles = (lanes // tile) * _state.TILE_STRIDE + lanes % tile
    for k in range(1, pt + 1):
        c = T[k, :-1] - T[k, 1:]
        np.testing.assert_array_equal(W[tiles + k * tile], c)
        f = c * MK[:nc]
        if k < pt - 1:
            net = np.concatenate([[0.0], f]) - np.concatenate([f, [0.0]])
            s = 1.0 / ((k + 1) * (k + 2))
            T[k + 2] = net * s if unit else net * s * IM[:m]
            if driven:
                T[k + 2, m // 2] += DT[k + 2]
    np.testing.assert_array_equal(TX[:, :m], T)
    np.testing.assert_array_equal(G[:nc], c * MK[:nc])
