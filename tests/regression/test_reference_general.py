"""Tests of the reference solver's general line (``reference.reference_line``) on its own.

``reference_line`` is the second opinion on chainrun's general kernels (masses,
stiffnesses, exponents, gaps, positions, forces, walls), so it is checked here only
against evidence that owes nothing to either: closed forms (``closed_forms.py``),
scaling laws of the equations, conservation laws, the paper's line given as
``chainrun.solver.model.Line`` and as the reference's own record (``paper_line``),
and its convergence in the step tolerance.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from scipy.integrate import quad

from chainrun.solver.model import Line, Wall
from closed_forms import (
    HERTZ_DURATION,
    HERTZ_DURATION_DMAX,
    contact_duration,
    linear_pair,
    linear_wall_bounce,
    max_compression,
    steel_bead,
    two_ball_velocities,
)
from reference import (
    CLOSE,
    FAMILIES,
    OPEN,
    _closing_time,
    line_energy,
    random_line,
    paper_line,
    reference_line,
)

#: One table of tolerances for this file, relative to the line's speed (velocities),
#: to its duration scale (times) or to its initial energy. The reference agrees with
#: itself at the tightest step tolerance to 3e-12 in velocity (``python
#: tests/reference.py``), so closed forms are asked for 1e-11.
TOL = {
    "velocity": 1e-11,
    "time": 1e-11,
    "snapshot": 1e-10,
    "energy": 1e-10,
    "momentum": 1e-13,
    "convergence": 1e-10,
    "compression_at_event": 1e-12,
    "scaling": 1e-11,
    "si": 1e-10,
}

ALPHAS = [1.0, 1.25, 1.5, 2.0, 2.5, 3.0]


@functools.lru_cache(maxsize=None)
def ref_random(family: str, seed: int, rtol: float | None = None):
    line, t_max = random_line(family, seed)
    kw = {} if rtol is None else {"rtol": rtol}
    return line, t_max, reference_line(line, t_max=t_max, **kw)


# ---- the closed forms themselves --------------------------------------------------------
@pytest.mark.parametrize("alpha", ALPHAS)
def test_duration_formula_is_the_integral(alpha):
    # The Beta-function form equals the defining integral, by quadrature.
    mu, k, u = 0.7, 1.9, 1.3
    p = alpha + 1.0
    d = max_compression(mu, k, alpha, u)
    integral, _ = quad(lambda x: 1.0 / math.sqrt(u * u - 2 * k * x ** p / (p * mu)), 0, d,
                       limit=200)
    assert contact_duration(mu, k, alpha, u) == pytest.approx(2 * integral, rel=1e-9)


def test_duration_constants():
    assert contact_duration(2.0, 3.0, 1.0, 0.4) == pytest.approx(math.pi * math.sqrt(2 / 3),
                                                                 rel=1e-15)
    assert HERTZ_DURATION_DMAX == pytest.approx(2.9432751843, rel=1e-10)
    assert HERTZ_DURATION == pytest.approx(3.2180654597, rel=1e-10)
    mu, k, u = 0.3, 5.0, 0.8
    assert contact_duration(mu, k, 1.5, u) == pytest.approx(
        HERTZ_DURATION * (mu / k) ** 0.4 * u ** -0.2, rel=1e-14)


# ---- the paper's line: chainrun's Line.paper and the reference's own record run alike ----
@pytest.mark.parametrize(("n", "k", "alpha"), [
    (2, 1, 1.0), (5, 1, 1.5), (5, 3, 1.5), (8, 3, 2.5), (6, 2, 1.0), (3, 3, 1.5),
    (1, 1, 1.5),
])
def test_paper_line_runs_as_the_references_own_record(n, k, alpha):
    a, b = reference_line(Line.paper(n, k, alpha)), reference_line(paper_line(n, k, alpha))
    assert a.terminal and b.terminal
    assert a.units == (1.0, 1.0, 1.0)
    np.testing.assert_allclose(a.final_velocity, b.final_velocity, rtol=0, atol=1e-14)
    np.testing.assert_allclose(a.event_time, b.event_time, rtol=0, atol=1e-14)
    np.testing.assert_array_equal(a.event_contact, b.event_contact)
    np.testing.assert_array_equal(a.event_kind, b.event_kind)


# ---- two balls --------------------------------------------------------------------------
@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize(("m1", "m2"), [(3.0, 1.0), (1.0, 3.0), (1.0, 10.0), (10.0, 1.0),
                                        (0.2, 0.2)])
def test_two_balls_masses(m1, m2, alpha):
    u, k = 0.7, 2.3
    r = reference_line(Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha, speed=u))
    assert r.terminal
    np.testing.assert_allclose(r.final_velocity, two_ball_velocities(m1, m2, u), rtol=0,
                               atol=TOL["velocity"] * u)
    # One contact, closed from t = 0 (touching, approaching), opening once.
    assert list(r.event_kind) == [OPEN] and list(r.event_contact) == [0]
    mu = m1 * m2 / (m1 + m2)
    tc = contact_duration(mu, k, alpha, u)
    assert abs(r.event_time[0] - tc) <= TOL["time"] * tc
    assert r.end_time == r.event_time[-1]


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
def test_gap_delays_the_collision(alpha):
    # The striker starts a gap g away: everything happens g/u later, and the striker
    # has then travelled g further.
    u, g = 0.6, 0.37
    kw = dict(mass=[2.0, 1.0, 1.5], stiffness=[1.5, 0.8], alpha=alpha, speed=u)
    a = reference_line(Line.make(3, **kw))
    b = reference_line(Line.make(3, gap=[g, 0.0], **kw))
    assert b.event_kind[0] == CLOSE and b.event_contact[0] == 0
    assert abs(b.event_time[0] - g / u) <= TOL["time"]
    np.testing.assert_array_equal(b.event_contact[1:], a.event_contact)
    np.testing.assert_allclose(b.event_time[1:], a.event_time + g / u, rtol=0,
                               atol=TOL["time"])
    np.testing.assert_allclose(b.final_velocity, a.final_velocity, rtol=0,
                               atol=TOL["velocity"])
    np.testing.assert_allclose(b.final_position, a.final_position + [g, 0, 0], rtol=0,
                               atol=TOL["snapshot"])


def test_linear_pair_snapshots():
    m1, m2, k, u = 2.0, 0.5, 3.0, 0.8
    tc = contact_duration(m1 * m2 / (m1 + m2), k, 1.0, u)
    times = np.array([0.0, 0.1, 0.3 * tc, 0.5 * tc, 0.99 * tc, tc, 1.2 * tc, 5.0])
    r = reference_line(Line.make(2, mass=[m1, m2], stiffness=k, alpha=1.0, speed=u),
                       times=times)
    x, v = linear_pair(times, m1, m2, k, u)
    np.testing.assert_allclose(r.positions, x, rtol=0, atol=TOL["snapshot"])
    np.testing.assert_allclose(r.velocities, v, rtol=0, atol=TOL["snapshot"])


# ---- walls -----------------------------------------------------------------------------
@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
@pytest.mark.parametrize("side", ["left", "right"])
def test_ball_on_a_wall(side, alpha):
    m, k, u, g = 1.7, 0.6, 0.9, 0.25
    wall = Wall(k, alpha, g)
    sign = 1.0 if side == "right" else -1.0
    line = Line.make(1, mass=m, velocity=[sign * u], **{side: wall})
    r = reference_line(line)
    assert r.terminal
    assert r.final_velocity[0] == pytest.approx(-sign * u, abs=TOL["velocity"] * u)
    label = 0 if side == "right" else -1          # n - 1 for the right wall, -1 left
    assert list(r.event_contact) == [label, label]
    assert list(r.event_kind) == [CLOSE, OPEN]
    tc = contact_duration(m, k, alpha, u)           # a wall: mu = m
    np.testing.assert_allclose(r.event_time, [g / u, g / u + tc], rtol=0,
                               atol=TOL["time"])


def test_wall_at_the_end_of_a_line():
    # Three equal balls against a right wall, linear everywhere: the wall's contact is
    # labelled n - 1 = 2; the line comes back with the striker's speed.
    line = Line.make(3, alpha=1.0, speed=1.0, right=Wall(1.0, 1.0, 0.0))
    r = reference_line(line)
    assert r.terminal
    assert 2 in set(r.event_contact.tolist())
    assert r.event_contact.min() >= 0
    v = r.final_velocity
    assert np.all(np.diff(v) >= -1e-12) and v[-1] <= 1e-12
    assert line_energy(line, r.final_position, v) == pytest.approx(0.5, rel=1e-12)


def test_bouncing_ball_under_a_force():
    # One ball pressed on a linear right wall by a constant force: parabolic flights
    # between bounces of closed-form duration, each leaving at minus the arrival speed.
    m, k, f, v0, g = 1.3, 4.0, 0.9, -0.4, 0.2
    line = Line.make(1, mass=m, velocity=[v0], force=[f], right=Wall(k, 1.0, g))
    a = f / m
    t1 = (-v0 + math.sqrt(v0 * v0 + 2 * a * g)) / a        # first touch
    u1 = math.sqrt(v0 * v0 + 2 * a * g)                      # arrival speed
    tb = linear_wall_bounce(m, k, f, u1)
    fl = 2 * u1 / a                                          # flight back to the wall
    expect = [t1, t1 + tb, t1 + tb + fl, t1 + 2 * tb + fl, t1 + 2 * tb + 2 * fl]
    t_max = expect[-1] + 0.5 * tb
    times = [expect[1] + 0.5 * fl, t_max]
    r = reference_line(line, t_max=t_max, times=times)
    assert not r.terminal and r.end_time == t_max
    assert list(r.event_kind) == [CLOSE, OPEN] * 2 + [CLOSE]
    np.testing.assert_allclose(r.event_time, expect, rtol=0, atol=TOL["time"])
    # top of the flight: at rest, as far from the wall as the force lets it rise
    assert r.velocities[0, 0] == pytest.approx(0.0, abs=TOL["snapshot"])
    assert r.positions[0, 0] == pytest.approx(g - u1 * u1 / (2 * a), abs=TOL["snapshot"])
    e0 = line_energy(line, line.position, line.velocity)
    assert line_energy(line, r.final_position, r.final_velocity) == pytest.approx(
        e0, abs=TOL["energy"] * 0.5 * m * u1 * u1)


@pytest.mark.parametrize("alpha", [1.0, 1.5])
def test_touching_balls_pulled_apart_part(alpha):
    # Two balls touching at rest, the forces pulling them apart: the contact carries
    # no force, and each flies off on its own parabola x = f t^2 / (2 m). (Was: the
    # contact started active, and its continuation sign(c)|c|^alpha held them together.)
    m, f = np.array([1.0, 2.0]), np.array([-0.3, 0.2])
    line = Line.make(2, mass=m, alpha=alpha, velocity=[0.0, 0.0], force=f)
    times = np.array([0.5, 1.0, 2.0])
    r = reference_line(line, t_max=2.0, times=times)
    assert r.event_time.size == 0
    np.testing.assert_allclose(r.positions, f * times[:, None] ** 2 / (2 * m), rtol=0,
                               atol=TOL["snapshot"])
    np.testing.assert_allclose(r.velocities, f * times[:, None] / m, rtol=0,
                               atol=TOL["snapshot"])
    # pushed together instead, they press on each other (the centre of mass moves
    # under the total force) and the contact stays closed: no event, compressed
    r = reference_line(Line.make(2, mass=m, alpha=alpha, velocity=[0.0, 0.0], force=-f),
                       t_max=2.0, times=times)
    assert r.event_time.size == 0
    np.testing.assert_allclose(r.velocities @ m, -f.sum() * times, rtol=0, atol=1e-12)
    assert np.all(r.positions[:, 0] - r.positions[:, 1] > 0)


# ---- free flight under forces: the stable quadratic --------------------------------------
@pytest.mark.parametrize(("r", "b", "t_star"), [
    (1.0, 1e-12, 1.0),         # barely curved: the textbook formula loses ~4 digits
    (1.0, -1e-12, 1.0),        # barely decelerated
    (1e-3, 2.0, 0.7),          # accelerated from near rest
    (-0.5, 1.0, 3.0),          # moving away first, pulled back
])
def test_closing_time_quadratic(r, b, t_star):
    d0 = -(r * t_star + 0.5 * b * t_star * t_star)
    assert _closing_time(d0, r, b, 1e-12) == pytest.approx(t_star, rel=1e-14)


def test_closing_time_no_root():
    assert _closing_time(-1.0, 0.5, -1.0, 1e-12) == np.inf       # decelerated, never there
    assert _closing_time(-1.0, -0.1, 0.0, 1e-12) == np.inf       # moving away, no force
    assert _closing_time(0.0, -0.1, 0.0, 1e-12) == np.inf        # just parted
    assert _closing_time(0.0, -0.1, 1.0, 1e-12) == pytest.approx(0.2, rel=1e-15)


# ---- scaling laws ------------------------------------------------------------------------
SCALING_LINE = dict(mass=[1.0, 3.0, 0.5, 2.0], stiffness=[1.0, 0.4, 2.0],
                    alpha=[1.5, 1.0, 2.0], gap=[0.0, 0.1, 0.0], velocity=[1.0, 0.0, 0.0, -0.3],
                    right=Wall(0.8, 1.5, 0.05))


def scaled(c_mass=1.0, c_speed=1.0, **over):
    kw = dict(SCALING_LINE, **over)
    right = kw.pop("right")
    kw["mass"] = np.asarray(kw["mass"]) * c_mass
    kw["stiffness"] = np.asarray(kw["stiffness"]) * c_mass
    kw["velocity"] = np.asarray(kw["velocity"]) * c_speed
    return Line.make(4, right=Wall(right.stiffness * c_mass, right.alpha, right.gap), **kw)


@pytest.mark.parametrize("c", [1e-3, 10.0, 7.5e4])
def test_scaling_masses_and_stiffnesses(c):
    # m x'' = F(x): multiplying every mass and stiffness by c changes nothing. Solved
    # in fixed units (1, 1, 1), so that the arithmetic really differs.
    a = reference_line(scaled(), units=(1, 1, 1))
    b = reference_line(scaled(c_mass=c), units=(1, 1, 1))
    np.testing.assert_allclose(b.final_velocity, a.final_velocity, rtol=0,
                               atol=TOL["scaling"])
    # an event's time is as good relative to it: after a free flight, a position's
    # rounding over the closing speed
    np.testing.assert_allclose(b.event_time, a.event_time, rtol=TOL["scaling"],
                               atol=TOL["scaling"])


@pytest.mark.parametrize("s", [0.01, 0.5, 30.0])
def test_scaling_hertz_speed(s):
    # One exponent a everywhere, no gap: x(t) -> s^p x(s^(p-1) t) with p = 2/(a+1)
    # maps solutions to solutions, so velocities scale with the striker's speed s and
    # times with s^((1-a)/(1+a)) (s^(-1/5) for Hertz).
    kw = dict(mass=[1.0, 3.0, 0.5, 2.0], stiffness=[1.0, 0.4, 2.0], alpha=1.5)
    a = reference_line(Line.make(4, velocity=[1.0, 0, 0, -0.3], **kw), units=(1, 1, 1))
    b = reference_line(Line.make(4, velocity=[s, 0, 0, -0.3 * s], **kw), units=(1, 1, 1))
    np.testing.assert_allclose(b.final_velocity, s * a.final_velocity, rtol=0,
                               atol=TOL["scaling"] * s)
    np.testing.assert_allclose(b.event_time, a.event_time * s ** -0.2, rtol=TOL["scaling"])


def test_units_do_not_matter():
    # The line's own units (default) and fixed units (1, 1, 1) give the same run.
    line = scaled()
    a, b = reference_line(line), reference_line(line, units=(1, 1, 1))
    assert a.units != (1.0, 1.0, 1.0)
    np.testing.assert_allclose(a.final_velocity, b.final_velocity, rtol=0,
                               atol=TOL["scaling"])


def test_steel_chain_in_si_units():
    # 25.4 mm steel beads struck at 0.5 m/s: the paper's velocities times 0.5.
    n, u = 6, 0.5
    mass, kappa = steel_bead()
    r = reference_line(Line.make(n, mass=mass, stiffness=kappa, alpha=1.5, speed=u))
    p = reference_line(paper_line(n, 1, 1.5))
    np.testing.assert_allclose(r.final_velocity, u * p.final_velocity, rtol=0,
                               atol=TOL["si"] * u)
    # time unit (m / (kappa u^(1/2)))^(2/5) = 3.3e-5 s for these beads
    t_unit = (mass / (kappa * u ** 0.5)) ** 0.4
    np.testing.assert_allclose(r.event_time, p.event_time * t_unit, rtol=TOL["si"])


# ---- random lines: conservation, terminal state, events, convergence ---------------------
RANDOM = [pytest.param(f, s, id=f"{f}-{s}") for f in FAMILIES for s in range(3)]


@pytest.mark.parametrize(("family", "seed"), RANDOM)
def test_random_line_conservation(family, seed):
    line, t_max, r = ref_random(family, seed)
    x, v = r.final_position, r.final_velocity
    e0 = line_energy(line, line.position, line.velocity)
    e_scale = max(abs(e0), 0.5 * float(np.sum(line.mass * line.velocity ** 2)))
    # energy minus the work of the forces, sum f (x(T) - x(0)), is conserved
    assert abs(line_energy(line, x, v) - e0) <= TOL["energy"] * e_scale
    if line.left is None and line.right is None:
        p0 = float(np.sum(line.mass * line.velocity) + np.sum(line.force) * r.end_time)
        assert abs(float(np.sum(line.mass * v)) - p0) <= TOL["momentum"] * (1 + abs(p0))
    if t_max is None:
        assert r.terminal
        # nothing approaches: walls are bodies at rest
        assert np.all(np.diff(v) >= -1e-12)
        if line.right is not None:
            assert v[-1] <= 1e-12
        if line.left is not None:
            assert v[0] >= -1e-12
    else:
        assert not r.terminal and r.end_time == pytest.approx(t_max, rel=1e-15)
    # each located event is a zero of the compression, kinds alternate per contact
    assert np.all(np.abs(r.event_compression) < TOL["compression_at_event"])
    assert np.all(np.diff(r.event_time) >= 0)
    for j in set(r.event_contact.tolist()):
        kinds = r.event_kind[r.event_contact == j]
        assert np.all(kinds[1:] != kinds[:-1])


@pytest.mark.parametrize(("family", "seed"), RANDOM)
def test_random_line_convergence(family, seed):
    # Default tolerance against the tightest scipy allows for DOP853 (2.2e-14).
    line, t_max, a = ref_random(family, seed)
    _, _, b = ref_random(family, seed, 2.3e-14)
    np.testing.assert_array_equal(a.event_contact, b.event_contact)
    np.testing.assert_array_equal(a.event_kind, b.event_kind)
    np.testing.assert_allclose(a.final_velocity, b.final_velocity, rtol=0,
                               atol=TOL["convergence"])
    # an event after a long flight moves by (velocity error) x (flight time)
    np.testing.assert_allclose(a.event_time, b.event_time, rtol=TOL["convergence"],
                               atol=TOL["convergence"])


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_random_line_convergence_many(family):
    for seed in range(3, 15):
        line, t_max = random_line(family, seed)
        a = reference_line(line, t_max=t_max)
        b = reference_line(line, t_max=t_max, rtol=2.3e-14)
        np.testing.assert_allclose(a.final_velocity, b.final_velocity, rtol=0,
                                   atol=TOL["convergence"], err_msg=f"seed {seed}")


def test_snapshots_are_the_state():
    # A snapshot at the end time is the final state; the snapshots of a terminal run
    # continue in free flight; times past t_max of a stopped run are NaN.
    line, _ = random_line("masses", 0)
    r0 = reference_line(line)
    times = [0.0, 0.5 * r0.end_time, r0.end_time, r0.end_time + 2.0]
    r = reference_line(line, times=times)
    np.testing.assert_array_equal(r.positions[0], line.position)
    np.testing.assert_array_equal(r.velocities[0], line.velocity)
    np.testing.assert_allclose(r.positions[2], r.final_position, rtol=0, atol=1e-13)
    np.testing.assert_allclose(r.velocities[3], r.final_velocity, rtol=0, atol=0)
    np.testing.assert_allclose(r.positions[3], r.final_position + 2.0 * r.final_velocity,
                               rtol=0, atol=1e-13)
    line, t_max = random_line("gravity", 0)
    r = reference_line(line, t_max=t_max, times=[t_max, t_max + 1])
    np.testing.assert_allclose(r.positions[0], r.final_position, rtol=0, atol=1e-13)
    assert np.all(np.isnan(r.positions[1]))


def test_needs_t_max():
    line, _ = random_line("gravity", 0)
    with pytest.raises(ValueError, match="t_max"):
        reference_line(line)
    line, _ = random_line("two_walls", 0)
    with pytest.raises(ValueError, match="t_max"):
        reference_line(line)
