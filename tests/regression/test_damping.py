"""Damped contacts in the solver: restitution, contact duration and the energy budget.

The references are closed forms (the linear dashpot's two-body motion, evaluated
here), or the two-body relative motion integrated here with scipy, which shares no
code with the solver.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from chainrun.solver import EventKind, Line, simulate
from chainrun.solver.model import Wall
from chainrun.solver.physics import line_kinetic_energy, line_potential_energy


def dashpot_collision(mu, kappa, eta, v):
    """(restitution, duration) of the linear spring-dashpot, force held at 0: closed form.

    delta(t) = (v / w) exp(-g t) sin(w t), g = eta / (2 mu), w^2 = kappa / mu - g^2
    (under-damped); the collision ends at the first root of kappa delta + eta delta'.
    """
    g = eta / (2.0 * mu)
    w = math.sqrt(kappa / mu - g * g)

    def delta(t):
        return v / w * math.exp(-g * t) * math.sin(w * t)

    def rate(t):
        return v * math.exp(-g * t) * (math.cos(w * t) - g / w * math.sin(w * t))

    def load(t):
        return kappa * delta(t) + eta * rate(t)

    # the load is eta v > 0 at t = 0 and kappa delta < 0 at the half period: bracket
    # its first root there
    t_end = brentq(load, 1e-300, math.pi / w, xtol=1e-15, rtol=4 * np.finfo(float).eps)
    return -rate(t_end) / v, t_end


def two_body(mu, kappa, alpha, eta, beta, v):
    """(restitution, duration) of mu c'' = -(kappa c^alpha + eta c^beta c'), held at 0
    from where that would pull, integrated with scipy to its unload."""

    def rhs(t, y):
        c, w = y
        c = max(c, 0.0)
        return [y[1], -(kappa * c ** alpha + eta * c ** beta * w) / mu]

    def load(t, y):
        c = max(y[0], 0.0)
        return kappa * c ** alpha + eta * c ** beta * y[1] if t > 0 else 1.0

    load.terminal = True
    load.direction = -1
    scale = (mu * v * v / kappa) ** (1.0 / (alpha + 1.0)) / v  # the contact's time
    sol = solve_ivp(rhs, (0.0, 50.0 * scale), [0.0, v], method="DOP853", rtol=1e-13,
                    atol=1e-16 * max(v, scale * v), events=load)
    t_end = float(sol.t_events[0][0])
    return -float(sol.y_events[0][0][1]) / v, t_end


def _pair(m1, m2, kappa, alpha, eta, beta, v):
    return Line.make(2, mass=[m1, m2], stiffness=kappa, alpha=alpha, damping=eta,
                     damping_exponent=beta, velocity=[v, 0.0])


def _restitution(sol, v):
    u = sol.final_velocity
    return (u[1] - u[0]) / v


@pytest.mark.parametrize("v", [1e-3, 1.0, 7.5e2])
@pytest.mark.parametrize("m1,m2,kappa,eta", [(1.0, 1.0, 1.0, 0.1), (0.3, 2.0, 5.0, 1.2),
                                             (2.0, 0.5, 1e3, 30.0)])
def test_linear_dashpot_restitution_and_duration_are_the_closed_forms(m1, m2, kappa, eta, v):
    mu = m1 * m2 / (m1 + m2)
    e, duration = dashpot_collision(mu, kappa, eta, v)
    sol = simulate(_pair(m1, m2, kappa, 1.0, eta, 0.0, v))
    assert sol.terminal
    assert _restitution(sol, v) == pytest.approx(e, abs=1e-9)
    unload = sol.event_time[sol.event_kind == EventKind.UNLOAD]
    assert unload.size == 1
    assert unload[0] == pytest.approx(duration, rel=1e-9)
    # momentum is kept, and what the collision took is what the damping dissipated
    u = sol.final_velocity
    assert m1 * u[0] + m2 * u[1] == pytest.approx(m1 * v, rel=1e-12)
    lost = 0.5 * m1 * v * v - 0.5 * (m1 * u[0] ** 2 + m2 * u[1] ** 2)
    assert sol.dissipated_energy == pytest.approx(lost, rel=1e-9)
    assert sol.contact_dissipation == pytest.approx([sol.dissipated_energy], rel=1e-14)


@pytest.mark.parametrize("alpha,beta", [(1.5, 0.5), (1.5, 0.25), (1.5, 0.0), (2.0, 1.0)])
@pytest.mark.parametrize("v", [0.05, 1.0, 20.0])
def test_nonlinear_laws_restitution_and_duration_match_a_two_body_integration(alpha, beta, v):
    m1, m2, kappa, eta = 1.0, 1.7, 2.0, 0.4
    mu = m1 * m2 / (m1 + m2)
    e, duration = two_body(mu, kappa, alpha, eta, beta, v)
    sol = simulate(_pair(m1, m2, kappa, alpha, eta, beta, v))
    assert _restitution(sol, v) == pytest.approx(e, abs=1e-8)
    unload = sol.event_time[sol.event_kind == EventKind.UNLOAD]
    assert unload[0] == pytest.approx(duration, rel=1e-8)


def test_the_tsuji_exponent_gives_a_restitution_independent_of_the_speed():
    alpha = 1.5
    es = [_restitution(simulate(_pair(1.0, 1.0, 1.0, alpha, 0.3, (alpha - 1) / 2, v)), v)
          for v in (1e-3, 1e-1, 1.0, 10.0, 1e3)]
    assert np.ptp(es) < 1e-9
    assert 0.0 < es[0] < 1.0
    # and with Kuwabara-Kono's exponent it does depend on the speed
    kk = [_restitution(simulate(_pair(1.0, 1.0, 1.0, alpha, 0.3, 0.5, v)), v)
          for v in (1e-1, 10.0)]
    assert kk[0] > kk[1] + 0.01


def test_a_damped_wall_bounce_is_the_two_body_collision_with_the_ball_mass():
    m, kappa, eta, v = 0.7, 3.0, 0.5, 2.0
    line = Line.make(1, mass=m, velocity=[v],
                     right=Wall(kappa, alpha=1.0, damping=eta, damping_exponent=0.0))
    sol = simulate(line)
    e, duration = dashpot_collision(m, kappa, eta, v)
    assert sol.terminal
    assert -sol.final_velocity[0] / v == pytest.approx(e, abs=1e-9)
    assert sol.wall_dissipation[1] == pytest.approx(0.5 * m * v * v * (1 - e * e), rel=1e-9)
    assert sol.wall_dissipation[0] == 0.0
    # the wall's impulse, integrated along the run: the ball's change of momentum
    assert sol.wall_impulse[1] == pytest.approx(-(1 + e) * m * v, rel=1e-9)
    assert sol.diagnostics.momentum_error < 1e-12


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.0])
def test_the_walls_impulses_are_integrated_on_elastic_lines_too(alpha):
    """A ball bouncing between two walls (the series and DOP853 steps alike): each
    bounce gives 2 m v, and the momentum check accounts for the walls."""
    m, v = 1.5, 0.8
    line = Line.make(1, mass=m, velocity=[v], left=Wall(2e4, alpha=alpha, gap=0.5),
                     right=Wall(1e4, alpha=alpha, gap=0.5))
    # it meets the right wall at t = 0.625 and the left one at 1.875, each contact
    # lasting under 0.1 (stiff walls): by t = 2.5 it has bounced once off each
    sol = simulate(line, t_end=2.5)
    assert sol.wall_impulse == pytest.approx([2 * m * v, -2 * m * v], rel=1e-10)
    assert sol.final_velocity[0] == pytest.approx(v, rel=1e-10)
    assert sol.diagnostics.momentum_error < 1e-12


def _random_damped_line(rng, n):
    law = rng.integers(4)
    alpha = [1.0, 1.5, 1.5, rng.uniform(1.0, 2.5, n - 1)][law]
    beta = [0.0, 0.5, 0.25, rng.uniform(0.0, 1.0, n - 1)][law]
    right = None
    if rng.random() < 0.5:
        right = Wall(rng.uniform(0.5, 2.0), alpha=1.5, damping=rng.uniform(0.0, 0.5),
                     damping_exponent=0.5)
    velocity = np.zeros(n)
    velocity[:rng.integers(1, 3)] = rng.uniform(0.5, 2.0)
    return Line.make(n, mass=rng.uniform(0.3, 3.0, n), stiffness=rng.uniform(0.5, 2.0, n - 1),
                     alpha=alpha, damping=rng.uniform(0.0, 0.8, n - 1),
                     damping_exponent=beta, velocity=velocity, right=right)


@pytest.mark.parametrize("seed", range(12))
def test_energy_balance_on_random_damped_lines(seed):
    """kinetic + contact energy + dissipated = initial, at every snapshot and at the end,
    computed here from the positions and velocities the solver returns."""
    rng = np.random.default_rng(seed)
    line = _random_damped_line(rng, int(rng.integers(3, 9)))
    times = np.linspace(0.0, 20.0, 41)
    sol = simulate(line, times, t_end=40.0)
    e0 = float(line_kinetic_energy(line.velocity, line.mass))
    for x, v, d in zip(sol.positions, sol.velocities, sol.dissipated):
        e = float(line_kinetic_energy(v, line.mass) + line_potential_energy(x, line))
        assert abs(e + d - e0) <= 1e-10 * e0
    assert np.all(np.diff(sol.dissipated) >= -1e-14 * e0)
    assert sol.diagnostics.energy_error <= 1e-10
    total = sol.contact_dissipation.sum() + sol.wall_dissipation.sum()
    assert total == pytest.approx(sol.dissipated_energy, rel=1e-12)
    if line.right is None:  # no wall: momentum is kept
        p = line.mass @ sol.final_velocity
        assert p == pytest.approx(line.mass @ line.velocity, rel=1e-12)


def test_every_damped_collision_unloads_before_it_opens():
    rng = np.random.default_rng(5)
    n = 8
    line = Line.make(n, mass=rng.uniform(0.5, 2.0, n), alpha=1.5, damping=0.2,
                     damping_exponent=0.25)
    sol = simulate(line)
    assert sol.terminal
    for j in range(n - 1):
        kinds = sol.event_kind[sol.event_contact == j]
        for i in np.flatnonzero(kinds == EventKind.OPEN):
            assert i > 0 and kinds[i - 1] == EventKind.UNLOAD
    # the terminal state: no two neighbours approach
    assert np.all(np.diff(sol.final_velocity) >= -1e-12)


def test_a_held_contact_opens_where_its_compression_vanishes():
    """A damped contact held at 0 opens where its compression reaches 0; inside a
    cluster that goes on moving the opening changes no force, and is found inside the
    step rather than ending it. Each such opening of a line struck at its end (a
    slow cluster shedding its tail) is logged where the compression is 0 (to the
    positions' accuracy, 1e-9 of the line's length scale), the balls parting there,
    and the run keeps its balances."""
    line = Line.make(40, k=1, alpha=1.5, damping=0.3, damping_exponent=0.5)
    sol = simulate(line)
    assert sol.terminal
    held = []
    for i in np.flatnonzero(sol.event_kind == EventKind.OPEN):
        j = sol.event_contact[i]
        before = np.flatnonzero(sol.event_contact[:i] == j)
        if before.size and sol.event_kind[before[-1]] == EventKind.UNLOAD:
            held.append((int(j), float(sol.event_time[i])))
    assert len(held) > 20
    times = np.array(sorted({t for _, t in held}))
    at = simulate(line, times)
    for j, t in held:
        k = int(np.searchsorted(times, t))
        c = at.positions[k, j] - at.positions[k, j + 1] - line.gap[j]
        w = at.velocities[k, j] - at.velocities[k, j + 1]
        assert abs(c) <= 1e-9, (j, t, c)
        assert w < 0.0, (j, t, w)
    assert sol.diagnostics.energy_error < 1e-10
    assert sol.diagnostics.momentum_error < 1e-12


def test_the_elastic_limit():
    n = 6
    base = dict(mass=[1.0, 2.0, 0.5, 1.0, 1.5, 1.0], alpha=1.5, k=2)
    elastic = simulate(Line.make(n, **base))
    for eta in (1e-4, 1e-6):
        damped = simulate(Line.make(n, damping=eta, damping_exponent=0.5, **base))
        gap = np.abs(damped.final_velocity - elastic.final_velocity).max()
        assert gap < 50 * eta
        assert 0.0 < damped.dissipated_energy < 50 * eta
    assert elastic.dissipated_energy == 0.0
    assert not np.any(elastic.event_kind == EventKind.UNLOAD)


def test_sensor_forces_are_the_damped_law_at_the_snapshots():
    rng = np.random.default_rng(3)
    n = 6
    line = Line.make(n, mass=rng.uniform(0.5, 2.0, n), alpha=1.5, damping=0.4,
                     damping_exponent=0.5, k=1)
    dt = 0.25
    times = np.arange(0.0, 12.0, dt)
    sol = simulate(line, times, sensors=[2, 4], sensor_dt=dt)
    from chainrun.solver.physics import contact_forces

    forces = contact_forces(sol.positions, line.alpha, line.stiffness, v=sol.velocities,
                            damping=line.damping, damping_exponent=line.damping_exponent)
    m = sol.sensor_time.size  # (samples stop at the terminal state, snapshots go on)
    assert m > 10
    forces = forces[:m]
    for s, ball in enumerate((2, 4)):
        np.testing.assert_allclose(sol.sensor_force[:m, s, 0], forces[:, ball - 2],
                                   rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(sol.sensor_force[:m, s, 1], forces[:, ball - 1],
                                   rtol=1e-9, atol=1e-12)
    assert np.all(sol.sensor_force >= 0.0)
    # the damping's force is there: the elastic law alone differs while a contact moves
    elastic = contact_forces(sol.positions, line.alpha, line.stiffness)[:m]
    assert np.abs(elastic - forces).max() > 1e-3


@pytest.mark.parametrize("beta,alpha", [(0.0, 1.0), (0.5, 1.5)])
def test_a_heavily_damped_line_ends_moving_as_one_body(alpha, beta):
    """The terminal rule with damping: no contact pushes and no pair approaches. Under
    heavy damping every collision is nearly perfectly inelastic, and the line ends
    moving nearly as one body, with the momentum it was given."""
    n, k = 10, 2
    sol = simulate(Line.make(n, alpha=alpha, damping=1e3, damping_exponent=beta, k=k))
    assert sol.terminal
    v = sol.final_velocity
    assert np.all(np.diff(v) >= 0.0)
    assert v.sum() == pytest.approx(k, rel=1e-12)
    assert np.ptp(v) < 1e-2 * v.mean()
    # nearly all of the impact energy went into the damping
    assert sol.dissipated_energy == pytest.approx(0.5 * k - 0.5 * k * k / n, rel=1e-3)


@pytest.mark.parametrize("seed", range(10))
def test_damped_lines_against_the_reference_solver(seed):
    """The test-only reference solver (tests/reference.py, which shares no code with the
    solver) on random damped lines, walls included: final state, snapshots and the
    energy dissipated."""
    from reference import reference_line

    rng = np.random.default_rng(100 + seed)
    line = _random_damped_line(rng, int(rng.integers(2, 7)))
    times = np.linspace(0.0, 8.0, 9)
    ref = reference_line(line, times=times, t_max=200.0)
    sol = simulate(line, times)
    assert ref.terminal and sol.terminal
    scale = float(np.max(np.abs(line.velocity)))
    np.testing.assert_allclose(sol.final_velocity, ref.final_velocity, atol=1e-9 * scale)
    np.testing.assert_allclose(sol.velocities, ref.velocities, atol=1e-9 * scale)
    e0 = float(line_kinetic_energy(line.velocity, line.mass))
    assert sol.dissipated_energy == pytest.approx(ref.dissipated, abs=1e-10 * e0)
    # every unloading located, at the same instants: the reference logs it as an
    # opening of a contact still compressed (by as little as rounding, where the load
    # reaches 0 just as the compression does)
    unloads = {(int(j), t) for j, t, k in zip(sol.event_contact, sol.event_time,
                                              sol.event_kind) if k == EventKind.UNLOAD}
    ends = [(int(j), t, c) for j, t, k, c in zip(ref.event_contact, ref.event_time,
                                                 ref.event_kind, ref.event_compression)
            if k == -1]
    assert unloads

    def near(j, t, events):
        return any(j == i and abs(t - u) <= 1e-9 * (1 + t) for i, u, *_ in events)

    for j, t in unloads:
        assert near(j, t, ends), (j, t)
    for j, t, c in ends:
        if c > 1e-9:
            assert near(j, t, unloads), (j, t, c)


def test_a_load_that_touches_zero_ends_as_the_reference_says():
    """Twelve damped beads moving together onto a damped wall: the first contact's load
    falls to 0, and on some CPUs turns back up at the instant the step lands there
    (within rounding of 0, with no crossing left to find), on others not; which, the
    rounding decides. Either way the contact must not stay held while it pushes, which
    left the cluster without a force and its steps growing without end: the run ends
    terminal within a few hundred events, as the independent reference solver does."""
    from chainrun.config import load_experiment
    from reference import reference_line

    path = Path(__file__).resolve().parents[2] / "configs" / "gallery" / "wall-column-damped.toml"
    spec = next(s for s in load_experiment(path).runs() if s.n == 12)
    sol = simulate(spec.line, max_events=1000)
    assert sol.terminal
    ref = reference_line(spec.line)
    speed = np.abs(spec.line.velocity).max()
    np.testing.assert_allclose(sol.final_velocity, ref.final_velocity, rtol=0,
                               atol=1e-9 * speed)
    kinds = sol.event_kind[sol.event_contact == 0]
    for i in np.flatnonzero(kinds == EventKind.UNLOAD):  # unloaded: reloads or opens
        assert i + 1 < kinds.size and kinds[i + 1] in (EventKind.RELOAD, EventKind.OPEN)
    assert sol.diagnostics.energy_error < 1e-10
    assert sol.diagnostics.momentum_error < 1e-10


def test_a_held_contact_reloads_when_a_third_ball_pushes():
    """A damped collision of balls 1 and 2 unloads (its force 0 while still compressed:
    the contact is held); a heavy ball 3, fast, strikes ball 2 from the right a third
    of the way through the held phase and pushes it back: contact 0 must bear its load
    again (RELOAD), well after its unload and before it could open. Ball 3's gap is set
    from the reference solver's run of balls 1 and 2 alone, so the strike lands in the
    held phase whatever the rounding; the run agrees with that solver."""
    from reference import reference_line

    kw = dict(alpha=1.5, damping=0.3, damping_exponent=0.5, mass=[1.0, 1.0, 5.0])
    pair = Line.make(3, velocity=[1.0, 0.0, 0.0], gap=[0.0, 1e3], **kw)
    alone = reference_line(pair)
    on_0 = alone.event_contact == 0
    t_unload = alone.event_time[on_0][0]      # the reference ends the load with an OPEN
    held = simulate(pair)  # the held phase ends where the compression does
    t_open = held.event_time[(held.event_contact == 0) & (held.event_kind == EventKind.OPEN)][0]
    assert t_open > t_unload * (1 + 1e-3)
    t_strike = t_unload + (t_open - t_unload) / 3
    x2 = reference_line(pair, times=[0.0, t_strike]).positions[:, 1]
    w = 10.0
    line = Line.make(3, velocity=[1.0, 0.0, -w], gap=[0.0, x2[1] - x2[0] + w * t_strike],
                     **kw)
    sol = simulate(line)
    assert sol.terminal
    kinds = list(sol.event_kind[:3])
    assert list(sol.event_contact[:3]) == [0, 1, 0]
    assert kinds == [EventKind.UNLOAD, EventKind.CLOSE, EventKind.RELOAD]
    assert sol.event_time[1] == pytest.approx(t_strike, rel=1e-6)
    ref = reference_line(line)
    np.testing.assert_allclose(sol.final_velocity, ref.final_velocity, rtol=0, atol=1e-9 * w)
    assert sol.diagnostics.energy_error < 1e-10
    assert sol.diagnostics.momentum_error < 1e-10


def test_a_load_that_vanishes_with_the_compression_opens_the_contact():
    """Eighty balls strike a line of 1000 with Kuwabara-Kono damping, integrated: at
    t = 3.9e6 (4.6e6 in other steps; rounding steers this line) a slow collision of
    balls 258 and 259 (0-based) unloads within rounding of its compression's 0 (the
    damping goes as c^beta). The contact must open at that instant, not stay held
    without force while its balls part: no crossing was left for a step to find, the
    cluster's steps grew without end, and the run ended non-finite at t = 8.5e307."""
    line = Line.make(1000, k=80, alpha=1.5, damping=0.01, damping_exponent=0.5)
    sol = simulate(line, closed_form=False)
    assert sol.terminal, sol.message
    pair = sol.event_contact == 258
    kinds, times = sol.event_kind[pair], sol.event_time[pair]
    last = int(np.flatnonzero(kinds == EventKind.UNLOAD)[-1])
    assert kinds[last + 1] == EventKind.OPEN and times[last + 1] == times[last]
    assert times[last] > 3e6
    assert sol.diagnostics.energy_error < 1e-10
    assert sol.diagnostics.momentum_error < 1e-10
