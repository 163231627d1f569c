"""Transmission from driven runs (``chainrun.transmission``) against linear theory
computed here: the decay per ball of a monatomic chain driven above its cut-off, the
forced response of the finite chain below it, and the band gap of a dimer chain.

A Hertz chain (kappa = 1, masses m) between two walls under a load F0 has, at rest,
contacts of linear stiffness K = 3/2 kappa^(2/3) F0^(1/3) (the walls' too). Driven by
its left wall, w = A sin(omega t), with A far below the static compression, it is the
linear chain of springs K to a relative error of order A / delta0:

- a uniform chain above its cut-off 2 sqrt(K/m): the displacements of a semi-infinite
  chain go as r^j, r = -(lambda - sqrt(lambda^2 - 1)), lambda = omega^2 m / (2K) - 1 (the
  root of r + 1/r = -2 lambda inside the unit circle), and so do the contact forces and
  a ball's mean force: neighbouring sensors' amplitudes have the ratio |r| and phases
  that differ by pi;
- below it, the finite chain's steady response solves (K - omega^2 M) x = f, f the wall's
  push K A on ball 1 (numpy, here);
- a dimer chain of masses m1 > m2 has no wave between sqrt(2K/m1) and sqrt(2K/m2), and
  none above sqrt(2K (1/m1 + 1/m2)).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import chainrun
from chainrun.config import parse_experiment
from chainrun.errors import ChainrunWarning
from chainrun.runner import simulate_experiment
from helpers import driven_sweep

F0 = 1.0
K = 1.5 * F0 ** (1.0 / 3.0)          # kappa = 1
A = 1e-6                             # the wall's amplitude; the static compression is 1


def driven_chain(n: int, frequency: float, sensors, periods: int = 160):
    """A Hertz chain of n balls of mass 1 between walls under F0, its left wall shaken
    at ``frequency``, started over 60 periods (a slow start leaves little in the pass
    band), run for ``periods`` periods."""
    period = 1.0 / frequency
    # the drive moves 1e-12 of the energy the line stores: its balance is within the
    # rounding of that energy, which no warning mistakes for the solver's error
    with warnings.catch_warnings():
        warnings.simplefilter("error", ChainrunWarning)
        return chainrun.simulate(
            chain={"n": n, "k": 0, "alpha": 1.5, "precompression": F0},
            walls={"left": {"motion": {"amplitude": A, "frequency": frequency,
                                       "ramp": 60 * period}}, "right": {}},
            output={"sensors": list(sensors), "sensor_dt": period / 20},
            solver={"t_end": periods * period})


@pytest.mark.parametrize("ratio", [1.2, 1.5])
def test_above_the_cutoff_the_drive_decays_by_the_linear_rate_per_ball(ratio):
    cutoff = 2.0 * math.sqrt(K)              # m = 1
    omega = ratio * cutoff
    lam = omega**2 / (2.0 * K) - 1.0
    r = -(lam - math.sqrt(lam**2 - 1.0))
    assert abs(r + 1.0 / r + 2.0 * lam) < 1e-12 and -1.0 < r < 0.0
    t = chainrun.transmission(driven_chain(14, omega / (2 * math.pi), range(2, 8)))
    amp = t.amplitude.sel(harmonic=1).values
    phase = t.phase.sel(harmonic=1).values
    # balls 2..7 (ball 1 also feels the wall's own contact, which is not of the form
    # r^j); the right wall's reflection is |r|^14 smaller still
    np.testing.assert_allclose(amp[1:] / amp[:-1], abs(r), rtol=3e-3)
    np.testing.assert_allclose(np.abs(np.angle(np.exp(1j * np.diff(phase)))), math.pi,
                               atol=3e-3)
    assert int(t.periods) in (49, 50) and t.transmission.sel(sensor=7, harmonic=1) < 1e-2
    if ratio == 1.2:  # (at 1.5 ball 7's force, |r|^5 of ball 2's, is not 10 x the rest)
        assert t.steady.all()


def test_below_the_cutoff_the_finite_chain_transmits_its_forced_response():
    # between the chain's modes 4 and 5 (omega_j = 2 sqrt(K) sin(j pi / (2 (n + 1)))),
    # away from both: the response is steady, set by the whole chain, and reaches its end
    n = 14
    omega = 2.0 * math.sqrt(K) * math.sin(4.5 * math.pi / (2 * (n + 1)))
    stiff = (np.diag(np.full(n, 2.0 * K)) - K * np.eye(n, k=1) - K * np.eye(n, k=-1))
    push = np.zeros(n)
    push[0] = K * A
    x = np.linalg.solve(stiff - omega**2 * np.eye(n), push)
    contact = np.concatenate([[K * (A - x[0])], K * (x[:-1] - x[1:]), [K * x[-1]]])
    mean = 0.5 * (contact[:-1] + contact[1:])      # each ball's mean force, in phase or not
    t = chainrun.transmission(driven_chain(n, omega / (2 * math.pi), range(1, n + 1)))
    amp = t.amplitude.sel(harmonic=1).values
    top = np.abs(mean).max()
    np.testing.assert_allclose(amp, np.abs(mean), rtol=0, atol=1e-2 * top)
    clear = np.abs(mean) > 0.1 * top            # (ball 10 sits on a node of the force)
    expected = np.where(mean > 0.0, 0.0, math.pi)
    np.testing.assert_allclose(np.angle(np.exp(1j * (t.phase.sel(harmonic=1).values
                                                     - expected)))[clear], 0.0, atol=1e-2)
    np.testing.assert_allclose(t.transmission.sel(harmonic=1).values, amp / (K * A))
    assert float(t.transmission.sel(sensor=n, harmonic=1)) > 0.1
    # steady where the force is clear of its node; at the node what is left of the
    # start's modes outweighs the little force at f
    assert t.steady.values[clear].all() and not t.steady.sel(sensor=10)




def test_a_dimer_chain_transmits_nothing_in_its_gap_and_its_edges_are_the_linear_ones(
        tmp_path):
    m1, m2 = 1.0, 0.5
    edges = [math.sqrt(2 * K / m1), math.sqrt(2 * K / m2), math.sqrt(2 * K * (1 / m1 + 1 / m2))]
    edges = [w / (2 * math.pi) for w in edges]           # 0.2757, 0.3898, 0.4775
    step = 0.02
    frequencies = [round(0.20 + step * i, 2) for i in range(15)]   # 0.20 .. 0.48
    experiment = parse_experiment(driven_sweep("dimer-transmission", 40, frequencies,
                                               mass=[1.0, 0.5], sensor_dt=0.1, ramp=60.0,
                                               t_end=300.0), "toml", "<test>")
    assert simulate_experiment(experiment, tmp_path).failures == []
    t = chainrun.transmission(tmp_path)
    np.testing.assert_array_equal(t.frequency.values, frequencies)
    np.testing.assert_allclose(t.band_top.values, [edges[0], edges[2]], rtol=1e-9)
    np.testing.assert_allclose(t.band_bottom.values, [0.0, edges[1]], rtol=0, atol=1e-9)
    far = t.transmission.sel(sensor=40, harmonic=1).values
    near = t.transmission.sel(sensor=1, harmonic=1).values
    f = t.frequency.values
    # the stop band as the runs see it: the far end gets a tenth of the near end or less
    stopped = far < 0.1 * near
    first = int(np.argmax(stopped))
    last = first + int(np.argmin(stopped[first:])) - 1
    assert stopped[first] and not stopped[:first].any()
    assert abs(f[first] - edges[0]) <= step and abs(f[last] - edges[1]) <= step
    # orders of magnitude: the gap's middle against the acoustic band
    inside = (f > edges[0] + step) & (f < edges[1] - step)
    acoustic = f < edges[0]
    assert np.median(far[inside]) < 1e-3 * np.median(far[acoustic])
    assert far[inside].max() < 1e-3 and far[acoustic].min() > 0.3
    # above the top band it stops again
    assert stopped[f > edges[2]].all() and not stopped[(f > edges[1] + step)
                                                        & (f < edges[2])].any()
