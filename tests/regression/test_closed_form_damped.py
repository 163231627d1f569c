"""Isolated damped collisions taken whole (``chainrun.solver._pair_damped``).

A damped collision that no third body can reach is applied from the pair's own
relative motion: its coefficient of restitution, its unload and its opening. The
references are ``restitution`` (scipy's integration of the scaled collision), the
energy the relative motion loses (all but e^2), and the independent
``reference.reference_line`` where a third ball arrives, with ``closed_form=False``
runs for what only the solver computes (sensors).
"""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.solver import EventKind, restitution, simulate
from chainrun.solver.model import Line, Wall
from reference import reference_line

#: the restitution module's e is trusted to 2e-12; a comparison with the reference
#: solver is asked for what test_general_model asks
TOL = {"outcome": 1e-11, "reference": 1e-8}

LAWS = [(1.0, 0.0), (1.5, 0.5), (1.5, 0.25), (2.0, 0.0)]


@pytest.mark.parametrize("alpha,beta", LAWS)
@pytest.mark.parametrize(("m1", "m2", "k", "u", "eta"), [(1.0, 1.0, 1.0, 1.0, 0.3),
                                                         (3.0, 1.0, 2.3, 0.7, 1.5),
                                                         (1.0, 10.0, 0.5, 2.0, 0.05)])
def test_a_damped_meeting_after_a_gap(m1, m2, k, u, eta, alpha, beta):
    g = 0.3
    line = Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha, speed=u, gap=g,
                     damping=eta, damping_exponent=beta)
    sol = simulate(line)
    assert sol.diagnostics.closed_form_collisions == 1
    assert sol.diagnostics.steps == 0
    mu = m1 * m2 / (m1 + m2)
    e = restitution.restitution(eta, beta, k, alpha, mu, u)
    v = m1 * u / (m1 + m2)
    want = [v - m2 / (m1 + m2) * e * u, v + m1 / (m1 + m2) * e * u]
    np.testing.assert_allclose(sol.final_velocity, want, rtol=0, atol=TOL["outcome"] * u)
    # closes, unloads at the force's zero, opens once the balls have parted
    assert list(sol.event_kind) == [EventKind.CLOSE, EventKind.UNLOAD, EventKind.OPEN]
    tu = restitution.contact_duration(eta, beta, k, alpha, mu, u)
    assert sol.event_time[1] == pytest.approx(g / u + tu, rel=1e-10)
    # all but e^2 of the relative motion's energy is dissipated, in the contact
    lost = 0.5 * mu * u * u * (1.0 - e * e)
    assert sol.dissipated_energy == pytest.approx(lost, rel=1e-10)
    assert sol.contact_dissipation[0] == pytest.approx(lost, rel=1e-10)
    assert sol.diagnostics.energy_error < 1e-12 and sol.diagnostics.momentum_error < 1e-13
    # the integrated collision agrees to the integration's accuracy
    slow = simulate(line, closed_form=False)
    assert slow.diagnostics.closed_form_collisions == 0 and slow.diagnostics.steps > 0
    np.testing.assert_allclose(slow.final_velocity, sol.final_velocity, rtol=0,
                               atol=1e-10 * u)
    np.testing.assert_allclose(slow.event_time, sol.event_time, rtol=1e-10)
    assert list(slow.event_kind) == list(sol.event_kind)


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_damped_wall_bounce(side):
    m, k, u, g, eta, beta = 1.7, 0.6, 0.9, 0.25, 0.4, 0.5
    sign = 1.0 if side == "right" else -1.0
    sol = simulate(Line.make(1, mass=m, velocity=[sign * u],
                             **{side: Wall(k, 1.5, g, eta, beta)}))
    assert sol.diagnostics.closed_form_collisions == 1
    e = restitution.restitution(eta, beta, k, 1.5, m, u)
    assert sol.final_velocity[0] == pytest.approx(-sign * e * u, abs=TOL["outcome"] * u)
    # the wall's impulse is the momentum it gave, (1 + e) m u, and it took the energy
    left, right = sol.wall_impulse
    assert (left if side == "left" else right) == pytest.approx(-sign * (1 + e) * m * u,
                                                                rel=1e-11)
    lost = 0.5 * m * u * u * (1.0 - e * e)
    wall = sol.wall_dissipation[0 if side == "left" else 1]
    assert wall == pytest.approx(lost, rel=1e-10)
    assert sol.diagnostics.momentum_error < 1e-13 and sol.diagnostics.energy_error < 1e-12


def test_snapshots_inside_a_damped_contact():
    # positions, velocities and the energy dissipated so far, inside the contact and
    # after its unload, against the integrated contact
    line = Line.make(2, mass=[1.0, 2.0], stiffness=1.3, alpha=1.5, speed=0.8, gap=0.4,
                     damping=0.7, damping_exponent=0.5)
    mu = 2.0 / 3.0
    tu = restitution.contact_duration(0.7, 0.5, 1.3, 1.5, mu, 0.8)
    t0 = 0.4 / 0.8
    times = t0 + np.array([-0.1, 0.0, 0.1, 0.4, 0.7, 0.999, 1.0, 1.01, 1.1, 3.0]) * tu
    sol = simulate(line, times)
    slow = simulate(line, times, closed_form=False)
    assert sol.diagnostics.closed_form_collisions == 1
    np.testing.assert_allclose(sol.positions, slow.positions, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sol.velocities, slow.velocities, rtol=0, atol=1e-10)
    np.testing.assert_allclose(sol.dissipated, slow.dissipated, rtol=0, atol=1e-10)
    assert np.all(np.diff(sol.dissipated) >= 0.0) and sol.dissipated[0] == 0.0
    assert sol.dissipated[-1] == pytest.approx(sol.dissipated_energy, rel=1e-14)


def third_ball_line(gap):
    """Balls 2 and 3 meet at t = 0.01 (sealed: ball 1 is at rest far behind), unload
    at t = 2.011 and part at t = 2.811; ball 0, fast, strikes ball 1 at t = 0.1, and
    ball 1 reaches the pair at t = 0.705 (gap 0.6), while its contact pushes, or at
    t = 2.072 (gap 7.4), while its force is held at 0."""
    return Line.make(4, alpha=1.5, velocity=[10.0, 0.0, 1.0, 0.0], gap=[1.0, gap, 0.01],
                     mass=[1.0, 1.3, 0.8, 1.1], damping=0.8, damping_exponent=0.5)


@pytest.mark.parametrize("gap,unloaded", [(0.6, False), (7.4, True)])
def test_a_third_ball_reaching_a_damped_sealed_contact(gap, unloaded):
    line = third_ball_line(gap)
    sol = simulate(line)
    ref = reference_line(line)
    assert sol.diagnostics.closed_form_collisions >= 1
    np.testing.assert_allclose(sol.final_velocity, ref.final_velocity, rtol=0,
                               atol=TOL["reference"])
    assert sol.diagnostics.energy_error < 1e-11 and sol.diagnostics.momentum_error < 1e-12
    # the pair 2-3 was in contact when ball 1 arrived, before or after its unload
    pair = sol.event_contact == 2
    assert list(sol.event_kind[pair][:2]) == [EventKind.CLOSE, EventKind.UNLOAD]
    arrival = sol.event_time[(sol.event_contact == 1) & (sol.event_kind == EventKind.CLOSE)][0]
    unload = sol.event_time[pair][1]
    assert bool(unload < arrival) == unloaded
    assert arrival < 2.811
    slow = simulate(line, closed_form=False)
    np.testing.assert_allclose(sol.final_velocity, slow.final_velocity, rtol=0, atol=1e-9)
    assert sol.dissipated_energy == pytest.approx(slow.dissipated_energy, rel=1e-9)
    np.testing.assert_allclose(sol.contact_dissipation, slow.contact_dissipation, rtol=1e-8,
                               atol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_a_damped_gas_against_the_reference(seed):
    rng = np.random.default_rng(100 + seed)
    n = 8
    line = Line.make(n, mass=10.0 ** rng.uniform(-0.5, 0.5, n), alpha=rng.choice([1.0, 1.5]),
                     stiffness=10.0 ** rng.uniform(-0.5, 0.5, n - 1),
                     gap=rng.uniform(0.05, 1.0, n - 1), velocity=rng.uniform(-1.0, 1.0, n),
                     damping=rng.uniform(0.0, 0.5, n - 1) * (rng.random(n - 1) < 0.8),
                     damping_exponent=rng.choice([0.0, 0.5]),
                     left=Wall(1.0, 1.5, 0.3, 0.2, 0.5))
    sol = simulate(line)
    ref = reference_line(line)
    assert sol.terminal and sol.diagnostics.closed_form_collisions > 0
    np.testing.assert_allclose(sol.final_velocity, ref.final_velocity, rtol=0,
                               atol=TOL["reference"])
    # the same collisions at the same times (the reference logs a damped contact's
    # opening where the solver logs its unload, so the closes are compared); the last
    # collisions are slow ones, hundreds of time units on, whose instants move by
    # the velocities' error times that: 3e-8 relative, as for the integrated solver
    got = np.sort(sol.event_time[sol.event_kind == EventKind.CLOSE])
    want = np.sort(ref.event_time[ref.event_kind == int(EventKind.CLOSE)])
    assert got.shape == want.shape
    assert np.all(np.abs(got - want) <= 1e-7 * (1.0 + want))
    assert sol.diagnostics.energy_error < 1e-11 and sol.diagnostics.momentum_error < 1e-12


def test_a_sensor_inside_damped_sealed_contacts():
    line = Line.make(3, mass=[1.0, 2.0, 1.5], alpha=1.5, velocity=[1.0, 0.0, 0.0],
                     gap=[0.3, 5.0], damping=0.5, damping_exponent=0.5)
    sol = simulate(line, sensors=[2], sensor_dt=0.01)
    slow = simulate(line, sensors=[2], sensor_dt=0.01, closed_form=False)
    assert sol.diagnostics.closed_form_collisions == 2
    assert np.abs(sol.sensor_force).max() > 0.3
    np.testing.assert_allclose(sol.sensor_force, slow.sensor_force, rtol=0, atol=1e-9)


@pytest.mark.parametrize("fraction", [0.4, 1.05])
def test_a_run_ending_inside_a_damped_contact(fraction):
    # before its unload, and after it: the energy dissipated so far is counted, and
    # the wall's impulse
    m, k, u, g = 1.3, 0.8, 0.7, 0.4
    line = Line.make(2, mass=[m, 2.0], velocity=[0.0, u], gap=[3.0],
                     right=Wall(k, 1.5, g, 0.6, 0.5), damping=0.3, damping_exponent=0.5)
    tu = restitution.contact_duration(0.6, 0.5, k, 1.5, 2.0, u)
    t_end = g / u + fraction * tu
    sol = simulate(line, t_end=t_end, times=[t_end])
    slow = simulate(line, t_end=t_end, times=[t_end], closed_form=False)
    assert sol.diagnostics.closed_form_collisions == 1
    assert sol.diagnostics.energy_error < 1e-12 and sol.diagnostics.momentum_error < 1e-13
    assert 0.0 < sol.dissipated_energy
    assert sol.dissipated_energy == pytest.approx(slow.dissipated_energy, rel=1e-9)
    assert sol.dissipated[-1] == pytest.approx(sol.dissipated_energy, rel=1e-12)
    assert sol.wall_impulse[1] == pytest.approx(slow.wall_impulse[1], rel=1e-9)
    np.testing.assert_allclose(sol.final_velocity, slow.final_velocity, rtol=0, atol=1e-10)
