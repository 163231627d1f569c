"""A line under its weight (``chain.gravity``, ``chainrun.solver.model.weigh``): the
static state on a floor against the force law written out, and what the experiment
file refuses."""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.config import parse_experiment
from chainrun.errors import ConfigError
from chainrun.solver.model import Line, Wall, weigh


def test_a_column_rests_on_its_floor_each_contact_carrying_the_weight_above_it():
    """Balls 2..6 at rest on a right wall, ball 1 falling onto them: each contact below
    ball 2 is compressed by (W / kappa)^(1/alpha), W the weight of the balls above it,
    the floor by the weight of them all; the striker's contact carries nothing."""
    mass = np.array([2.0, 1.0, 3.0, 1.5, 2.5, 1.0])
    kappa = np.array([4.0, 5.0, 6.0, 7.0, 8.0])
    line = Line.make(6, velocity=np.array([0.5, 0, 0, 0, 0, 0]), mass=mass, stiffness=kappa,
                     alpha=1.5, right=Wall(9.0, 1.5))
    g = 0.2
    weighed = weigh(line, g)
    np.testing.assert_array_equal(weighed.force, g * mass)
    x = weighed.position
    above = g * np.cumsum(mass[1:])  # the weight on contacts 2-3, ..., 5-6 and the floor
    np.testing.assert_allclose(x[-1], (above[-1] / 9.0) ** (2 / 3), rtol=1e-14)
    np.testing.assert_allclose(x[1:-1] - x[2:], (above[:-1] / kappa[1:]) ** (2 / 3),
                               rtol=1e-13)
    assert x[0] == x[1]  # the striker meets ball 2 as it would without the load
    # and without a floor the balls only weigh: the line falls
    assert not np.any(weigh(Line.make(6, velocity=line.velocity, mass=mass), g).position)


def run_text(chain: str, solver: str = 't_end = 1e-3', gravity: float = 9.81) -> str:
    return (f'name = "c"\nunits = "si"\n[chain]\nn = 6\ndiameter = 0.008\n'
            f'material = "steel"\ngravity = {gravity}\n{chain}\n[walls.right]\n'
            f'[solver]\n{solver}\n')


def test_gravity_sets_the_forces_and_keeps_pulling():
    with pytest.raises(ConfigError) as info:
        parse_experiment(run_text("k = 1\nspeed = 0.3\nforce = 1.0"), "toml")
    assert any(p.startswith("chain.gravity: sets the external forces itself")
               for p in info.value.problems)
    with pytest.raises(ConfigError) as info:
        parse_experiment(run_text("k = 1\nspeed = 0.3", solver=""), "toml")
    assert any("chain.gravity keeps pulling" in p for p in info.value.problems)
    with pytest.raises(ConfigError) as info:
        parse_experiment(run_text("k = 1\nspeed = 0.3", gravity=-9.81), "toml")
    assert any(p.startswith("chain.gravity:") for p in info.value.problems)
