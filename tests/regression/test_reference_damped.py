"""The test-only reference solver on damped lines (``reference.reference_line``).

Evidence owed to nothing in chainrun's solver: the damped linear oscillator's explicit
solution (its force's zero found by a root finder in ``closed_forms.oscillator``),
the energy balance kinetic + potential + dissipated = initial, the residual of the
law at each located event, and the elastic reference as the damping vanishes.
"""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.solver.model import Line, Wall
from chainrun.solver.restitution import contact_duration, restitution
from closed_forms import oscillator
from reference import CLOSE, OPEN, line_energy, reference_line


def balance(line, sol) -> float:
    """|kinetic + potential + dissipated - initial| relative to the initial energy."""
    e0 = line_energy(line, line.position, line.velocity)
    e1 = line_energy(line, sol.final_position, sol.final_velocity)
    return abs(e1 + sol.dissipated - e0) / abs(e0)


@pytest.mark.parametrize("eta", [0.05, 0.8, 2.0 * np.sqrt(2.0 * 0.75) * (1 - 1e-6),
                                 2.0 * np.sqrt(2.0 * 0.75) * (1 + 1e-6), 5.0])
def test_two_linear_balls_meet_the_closed_form(eta):
    # under-, (nearly) critically and over-damped: e and duration of the oscillator's
    # explicit solution
    m1, m2, k, u = 1.0, 3.0, 2.0, 0.7
    mu = m1 * m2 / (m1 + m2)
    line = Line.make(2, mass=[m1, m2], stiffness=k, alpha=1.0, speed=u, damping=eta)
    sol = reference_line(line)
    e, tc = oscillator(eta, k, mu, u)
    v1, v2 = sol.final_velocity
    assert (v2 - v1) / u == pytest.approx(e, abs=1e-10)
    assert m1 * v1 + m2 * v2 == pytest.approx(m1 * u, abs=1e-14)
    assert list(sol.event_kind) == [OPEN]
    assert sol.event_time[0] == pytest.approx(tc, rel=1e-10)
    assert sol.event_compression[0] > 0.0          # released while still pressed
    assert balance(line, sol) < 1e-12


@pytest.mark.parametrize("alpha, beta", [(1.5, 0.25), (1.5, 0.5), (1.5, 0.0), (2.0, 0.5)])
def test_two_nonlinear_balls_meet_the_scaled_integration(alpha, beta):
    # two independent integrations: the scaled two-body one and the reference line
    m1, m2, k, u, eta = 2.0, 0.5, 3.0, 1.3, 0.4
    mu = m1 * m2 / (m1 + m2)
    line = Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha, speed=u, damping=eta,
                     damping_exponent=beta)
    sol = reference_line(line)
    v1, v2 = sol.final_velocity
    assert (v2 - v1) / u == pytest.approx(restitution(eta, beta, k, alpha, mu, u), abs=1e-10)
    assert sol.event_time[0] == pytest.approx(contact_duration(eta, beta, k, alpha, mu, u),
                                              rel=1e-9)
    assert balance(line, sol) < 1e-12


@pytest.mark.parametrize("side", ["left", "right"])
def test_damped_wall_bounce(side):
    m, k, u, eta, gap = 1.7, 0.6, 0.9, 0.3, 0.25
    sign = 1.0 if side == "right" else -1.0
    line = Line.make(1, mass=m, velocity=[sign * u],
                     **{side: Wall(k, 1.0, gap, damping=eta)})
    sol = reference_line(line)
    e, tc = oscillator(eta, k, m, u)                 # a wall: mu = the ball's mass
    assert -sign * sol.final_velocity[0] / u == pytest.approx(e, abs=1e-10)
    assert list(sol.event_kind) == [CLOSE, OPEN]
    assert sol.event_time[1] - sol.event_time[0] == pytest.approx(tc, rel=1e-10)
    assert balance(line, sol) < 1e-12
    # and a Hertz wall with the Tsuji law
    line = Line.make(1, mass=m, velocity=[sign * u],
                     **{side: Wall(k, 1.5, gap, damping=eta, damping_exponent=0.25)})
    sol = reference_line(line)
    assert -sign * sol.final_velocity[0] / u == pytest.approx(
        restitution(eta, 0.25, k, 1.5, m, u), abs=1e-10)


def test_vanishing_damping_recovers_the_elastic_reference():
    kw = dict(mass=[1.0, 0.6, 1.4, 1.0], stiffness=[1.0, 2.0, 0.7], alpha=1.5, k=1)
    elastic = reference_line(Line.make(4, **kw))
    same = reference_line(Line.make(4, damping=0.0, damping_exponent=0.25, **kw))
    np.testing.assert_array_equal(same.final_velocity, elastic.final_velocity)
    assert same.dissipated == 0.0
    for eta in (1e-4, 1e-6):
        weak = reference_line(Line.make(4, damping=eta, damping_exponent=0.25, **kw))
        diff = np.max(np.abs(weak.final_velocity - elastic.final_velocity))
        assert diff < 10 * eta                       # first order in eta
        assert 0.0 < weak.dissipated < 10 * eta


def test_damped_chains_balance_energy():
    lines = [
        Line.make(5, mass=[1.0, 0.5, 2.0, 1.0, 0.8], stiffness=[1.0, 3.0, 0.5, 1.0],
                  alpha=1.5, k=2, damping=[0.2, 0.0, 0.5, 0.1], damping_exponent=0.25),
        Line.make(4, alpha=[1.0, 1.5, 2.0], damping=[0.3, 0.3, 0.3],
                  damping_exponent=[0.0, 0.5, 0.5], gap=[0.0, 0.1, -0.02], k=1),
        Line.make(3, alpha=1.5, velocity=[1.0, 0.0, -0.8], damping=1.5,
                  damping_exponent=0.25),
        Line.make(3, mass=[1.0, 2.0, 1.0], alpha=1.0, velocity=[0.5, 0.0, 0.0],
                  damping=0.4, right=Wall(2.0, 1.0, 0.1, damping=0.6)),
    ]
    for line in lines:
        sol = reference_line(line)
        assert sol.terminal
        assert balance(line, sol) < 1e-11
        assert sol.dissipated > 0.0
        if line.right is None:
            p0 = float(np.sum(line.mass * line.velocity))
            assert float(np.sum(line.mass * sol.final_velocity)) == pytest.approx(p0, abs=1e-13)


def test_force_resumes_while_still_compressed():
    # a light ball released by a damped contact bounces off a stiff wall back into the
    # heavy one before their compression is gone: the contact closes again at
    # delta > 0, where its law turns positive, and the energy still balances
    line = Line.make(2, mass=[1.0, 0.2], alpha=1.5, speed=1.0, damping=3.0,
                     damping_exponent=0.25, right=Wall(50.0, 1.5, 0.9))
    sol = reference_line(line, t_max=20.0)
    again = (sol.event_contact == 0) & (sol.event_kind == CLOSE) & (sol.event_compression > 0)
    assert np.count_nonzero(again) == 1
    assert balance(line, sol) < 1e-12
    # the law is zero at every located event of the damped contact (the residual)
    times = sol.event_time[sol.event_contact == 0]
    at = reference_line(line, t_max=20.0, times=times)
    for x, v in zip(at.positions, at.velocities):
        d, r = x[0] - x[1], v[0] - v[1]
        assert abs(d ** 1.5 + 3.0 * d ** 0.25 * r) < 1e-9
