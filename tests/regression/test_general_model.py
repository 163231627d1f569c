"""Tests of ``chainrun.solver.simulate`` on the general line model.

Masses, per-contact stiffnesses and exponents, gaps and overlaps, initial positions,
external forces and walls (``chainrun.solver.model.Line``), in the line's own units.
The expected values come from closed forms (``closed_forms.py``), from exact scaling
laws of the equations, or from the independent scipy reference of
``tests/reference.py`` (``reference_line``), never from stored chainrun output.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from chainrun.solver import EventKind, Line, Outcome, Wall, simulate
from closed_forms import (
    contact_duration,
    linear_pair,
    linear_wall_bounce,
    steel_bead,
    two_ball_velocities,
)
from reference import FAMILIES, line_energy, paper_line, random_line, reference_line

#: One table of tolerances for this file. Lines here have speeds, masses and
#: durations of order 1 (the SI chain is compared in its own units), so the
#: tolerances are absolute in those units unless said otherwise.
#:
#: Closed forms: chainrun at its default rtol 1e-12 meets the two-ball closed forms of
#: the paper's units to 3.4e-12; 1e-10 (relative to the speed, or to the contact's
#: duration) leaves a factor 30.
#:
#: The reference (``python tests/reference.py``): its final velocities at the default
#: rtol 1e-13 differ from those at the tightest rtol scipy allows (2.2e-14) by at
#: most 3e-12 over 120 random lines of these families, and from those at rtol 1e-12
#: by up to 1.8e-10 (a gravity line of 12 collisions: each collision amplifies the
#: step errors). So chainrun at rtol 1e-12 should be within ~1e-10 of the reference;
#: 1e-8 leaves a factor 100 for that amplification, while a modelling error (a wrong
#: mass, stiffness, exponent, gap, wall or force) shows at 1e-3 or more. An event after
#: a long free flight moves by (velocity error) x (flight time) / (approach speed):
#: up to 2e-9 between the reference's own tolerances after a flight of 66 time units,
#: hence times and positions relative to (1 + t).
TOL = {
    "closed_form": 1e-10,
    "reference_velocity": 1e-8,
    "reference_time": 1e-8,         # absolute and relative: |dt| <= 1e-8 (1 + t)
    "reference_position": 1e-8,     # |dx| <= 1e-8 (1 + t), t the time of the state
    "energy": 1e-9,                 # relative to the initial energy scale
    "scaling": 1e-10,               # same line, other units: only rounding differs
    "si": 1e-9,                     # SI chain vs paper units, relative
}


def run(line: Line, times=(), **kw):
    return simulate(line, times, **kw)


@functools.lru_cache(maxsize=None)
def ref_random(family: str, seed: int):
    line, t_max = random_line(family, seed)
    return reference_line(line, t_max=t_max)


def located(sol, after: float = 0.0):
    """The located events (OPEN, CLOSE) after ``after``: (time, contact, kind)."""
    keep = (np.isin(sol.event_kind, [EventKind.OPEN, EventKind.CLOSE])
            & (sol.event_time > after))
    return sol.event_time[keep], sol.event_contact[keep], sol.event_kind[keep]


def assert_close_in_time(got, want, t, tol: float, what: str):
    """|got - want| <= tol (1 + t), t the time (or times) of the values."""
    got, want = np.asarray(got, float), np.asarray(want, float)
    assert got.shape == want.shape, f"{what}: shapes {got.shape} and {want.shape}"
    err = np.abs(got - want) / (1.0 + np.asarray(t, float))
    assert np.all(err <= tol), (f"{what}: worst error {err.max():.3g} (1 + t) > {tol:g}"
                                f"\n got  {got}\n want {want}")


def canonical(t, c, kind, tol: float):
    """Events in a canonical order: by time, and by contact among events within
    ``tol (1 + t)`` of each other (simultaneous to rounding: in a symmetric line, the
    order of simultaneous events is a solver's convention)."""
    t, c, kind = (np.asarray(a) for a in (t, c, kind))
    order = np.argsort(t, kind="stable")
    t, c, kind = t[order], c[order], kind[order]
    start = 0
    for i in range(1, t.size + 1):
        if i == t.size or t[i] - t[i - 1] > tol * (1.0 + abs(t[i])):
            group = np.arange(start, i)
            sub = group[np.argsort(c[group], kind="stable")]
            t[group], c[group], kind[group] = t[sub], c[sub], kind[sub]
            start = i
    return t, c, kind


def assert_same_events(got, want, tol: float):
    """Same located events (time, contact, kind) to ``tol (1 + t)`` in time."""
    gt, gc, gk = canonical(*got, tol)
    wt, wc, wk = canonical(*want, tol)
    np.testing.assert_array_equal(gc, wc, err_msg="event contacts")
    np.testing.assert_array_equal(gk, wk, err_msg="event kinds")
    assert_close_in_time(gt, wt, wt, tol, "event times")


def assert_ok(sol, terminal: bool):
    assert sol.outcome.ok, sol.message
    assert bool(sol.terminal) is terminal, sol.message
    assert sol.outcome is (Outcome.TERMINAL if terminal else Outcome.STOP_TIME)


# ---- 1. Closed forms ---------------------------------------------------------------------
TWO_BALLS = [
    pytest.param(1.0, 1.0, 1.0, 1.0, id="paper"),
    pytest.param(3.0, 1.0, 2.3, 0.7, id="heavy-striker"),
    pytest.param(1.0, 3.0, 2.3, 0.7, id="light-striker"),
    pytest.param(10.0, 1.0, 1.0, 1.0, id="ratio-10"),
    pytest.param(1.0, 10.0, 0.5, 2.0, id="ratio-0.1"),
]


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
@pytest.mark.parametrize(("m1", "m2", "k", "u"), TWO_BALLS)
def test_two_balls(m1, m2, k, u, alpha):
    # Any contact law: momentum and energy fix the final velocities; the contact lasts
    # (2 d / u) B(1/p, 1/2) / p (p = alpha + 1, d its largest compression).
    line = Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha, speed=u)
    sol = run(line)
    assert_ok(sol, terminal=True)
    np.testing.assert_allclose(sol.final_velocity, two_ball_velocities(m1, m2, u),
                               rtol=0, atol=TOL["closed_form"] * u)
    t, c, kind = located(sol)
    assert list(c) == [0] and list(kind) == [EventKind.OPEN]
    tc = contact_duration(m1 * m2 / (m1 + m2), k, alpha, u)
    assert abs(t[0] - tc) <= TOL["closed_form"] * tc
    assert abs(sol.end_time - tc) <= TOL["closed_form"] * tc


def test_linear_pair_snapshots():
    m1, m2, k, u = 2.0, 0.5, 3.0, 0.8
    tc = contact_duration(m1 * m2 / (m1 + m2), k, 1.0, u)
    times = np.array([0.0, 0.1, 0.3 * tc, 0.5 * tc, 0.99 * tc, 1.2 * tc, 5.0])
    sol = run(Line.make(2, mass=[m1, m2], stiffness=k, alpha=1.0, speed=u), times)
    x, v = linear_pair(times, m1, m2, k, u)
    np.testing.assert_allclose(sol.positions, x, rtol=0, atol=TOL["closed_form"])
    np.testing.assert_allclose(sol.velocities, v, rtol=0, atol=TOL["closed_form"])


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
@pytest.mark.parametrize("side", ["left", "right"])
def test_ball_on_a_wall(side, alpha):
    # A wall is a body of infinite mass at rest: the ball comes back at -u after a
    # contact as long as a pair's with mu = m. Event labels: -1 left, n - 1 right.
    m, k, u, g = 1.7, 0.6, 0.9, 0.25
    sign = 1.0 if side == "right" else -1.0
    line = Line.make(1, mass=m, velocity=[sign * u], **{side: Wall(k, alpha, g)})
    sol = run(line)
    assert_ok(sol, terminal=True)
    assert abs(sol.final_velocity[0] + sign * u) <= TOL["closed_form"] * u
    t, c, kind = located(sol)
    label = 0 if side == "right" else -1
    assert list(c) == [label, label]
    assert list(kind) == [EventKind.CLOSE, EventKind.OPEN]
    tc = contact_duration(m, k, alpha, u)
    np.testing.assert_allclose(t, [g / u, g / u + tc], rtol=0, atol=TOL["closed_form"])


def test_wall_labels_in_a_line():
    # Three balls between two walls, linear: the walls' contacts are logged as -1 and
    # n - 1 = 2, the balls' as 0 and 1.
    line = Line.make(3, alpha=1.0, velocity=[0.0, 1.0, 0.0], gap=0.2,
                     left=Wall(1.0, 1.0, 0.1), right=Wall(1.0, 1.0, 0.1))
    sol = run(line, t_end=20.0)
    assert_ok(sol, terminal=False)
    _, c, _ = located(sol)
    assert set(c.tolist()) == {-1, 0, 1, 2}


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
def test_gap_delays_the_collision(alpha):
    # Two balls a gap g apart: contact at g/u, then the closed forms.
    m1, m2, k, u, g = 2.0, 1.0, 1.5, 0.6, 0.37
    sol = run(Line.make(2, mass=[m1, m2], stiffness=k, alpha=alpha, gap=g, speed=u))
    assert_ok(sol, terminal=True)
    t, c, kind = located(sol)
    assert list(kind) == [EventKind.CLOSE, EventKind.OPEN] and list(c) == [0, 0]
    tc = contact_duration(m1 * m2 / (m1 + m2), k, alpha, u)
    np.testing.assert_allclose(t, [g / u, g / u + tc], rtol=0, atol=TOL["closed_form"])
    np.testing.assert_allclose(sol.final_velocity, two_ball_velocities(m1, m2, u),
                               rtol=0, atol=TOL["closed_form"] * u)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
def test_gap_shifts_a_whole_run(alpha):
    # A striker a gap g behind a line: the run without the gap, g/u later, with the
    # striker g further on (a law of the equations: compare chainrun with itself).
    u, g = 0.6, 0.37
    kw = dict(mass=[2.0, 1.0, 1.5], stiffness=[1.5, 0.8], alpha=alpha, speed=u)
    a, b = run(Line.make(3, **kw)), run(Line.make(3, gap=[g, 0.0], **kw))
    ta, ca, ka = located(a)
    tb, cb, kb = located(b, after=g / u * (1 + 1e-9))
    np.testing.assert_array_equal(cb, ca)
    np.testing.assert_array_equal(kb, ka)
    np.testing.assert_allclose(tb, ta + g / u, rtol=0, atol=TOL["closed_form"])
    np.testing.assert_allclose(b.final_velocity, a.final_velocity, rtol=0,
                               atol=TOL["closed_form"])
    np.testing.assert_allclose(b.final_position, a.final_position + [g, 0.0, 0.0],
                               rtol=0, atol=TOL["closed_form"])


@pytest.mark.parametrize("alpha", [1.0, 1.5])
def test_touching_balls_pulled_apart_part(alpha):
    # Touching at rest, pulled apart by the forces: no contact force, two parabolas.
    m, f = np.array([1.0, 2.0]), np.array([-0.3, 0.2])
    times = np.array([0.5, 1.0, 2.0])
    sol = run(Line.make(2, mass=m, alpha=alpha, velocity=[0.0, 0.0], force=f), times,
              t_end=2.0)
    assert_ok(sol, terminal=False)
    assert located(sol)[0].size == 0
    np.testing.assert_allclose(sol.positions, f * times[:, None] ** 2 / (2 * m), rtol=0,
                               atol=TOL["closed_form"])
    np.testing.assert_allclose(sol.velocities, f * times[:, None] / m, rtol=0,
                               atol=TOL["closed_form"])


def test_pairs_closing_at_one_instant_under_a_uniform_force():
    # Balls 1-2 collide (gap 0.1), then pairs 0-1 and 2-3 meet at the same instant,
    # mirror images of each other; the force is the same on every ball, so it changes
    # no relative motion. Their predicted times differ by an ulp: a step that short
    # moved no ball, and saw the contact just closed part, again and again. The reference agrees with itself at rtol 1e-13 and 1e-12 to
    # 3e-12 on it.
    line = Line.make(6, alpha=[1.0, 1.0, 1.5, 1.0, 1.0], gap=[0.0, 0.1, 0.0, 0.3, 0.0],
                     velocity=[-0.49999999999999994, 0.0, -1.0, -0.5, 0.5, 0.0],
                     force=-0.14944540373951848)
    sol = run(line, t_end=30.0)
    assert_ok(sol, terminal=False)
    r = reference_line(line, t_max=30.0)
    np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                               atol=TOL["reference_velocity"])


@pytest.mark.parametrize("n, k, force, left", [
    (7, 3, -5e-324, Wall(1.0, 3.0)),      # half of the relative acceleration is 0
    (1, 0, 2.5685219244387945e-235, None),  # its static compression underflows
])
def test_forces_as_small_as_a_float_can_be(n, k, force, left):
    # Found by the fuzzer: a division by 0 in the kernels and a 0 to a negative power
    # in the line's scales. A force this small moves nothing a float can show: the
    # run is the run without it.
    right = Wall(1.0, 1.0, 0.05) if left is None else None
    v = np.where(np.arange(n) < k, 1.0, 0.0)  # k = 0: at rest, the scales from the force
    forced = Line.make(n, alpha=1.0, velocity=v, force=force, left=left, right=right)
    free = Line.make(n, alpha=1.0, velocity=v, left=left, right=right)
    a, b = run(forced, [10.0], t_end=10.0), run(free, [10.0], t_end=10.0)
    assert a.outcome == Outcome.STOP_TIME, a.message
    np.testing.assert_allclose(a.velocities, b.velocities, rtol=0, atol=1e-15)
    np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=1e-14)


def test_a_pair_pressed_together_stays_in_contact_when_rounding_parts_it():
    # Found by the long fuzzer run. Ball 2's force presses it into ball 1 harder than
    # ball 1's own force. At t = 14.28 their contact, overlapped within rounding, parts
    # at a speed within rounding; opened there, the free pair's overlap would never end
    # (its parabola has no root), no collision would be predicted, and the balls would
    # pass through each other. The run must keep them in contact (energy balanced).
    line = Line.make(4, mass=[0.3263181348015897, 0.6902918792318835, 0.6902918792318835,
                              1.6125278115106167],
                     stiffness=0.7916631989634783,
                     alpha=[1.0592104487984795, 1.0914373489967295, 3.0],
                     damping=[0.0, 0.10000230261160267, 0.0], damping_exponent=0.5,
                     velocity=np.zeros(4),
                     force=[-0.18351701463291276, -0.4724886569150688, 0.3275493090697703,
                            0.0])
    t_end = 20.0 * line.scales().time
    sol = run(line, [t_end], t_end=t_end)
    assert_ok(sol, terminal=False)
    e0 = line_energy(line, line.position, line.velocity)
    e1 = line_energy(line, sol.positions[-1], sol.velocities[-1]) + sol.dissipated_energy
    assert abs(e1 - e0) <= 1e-9 * max(abs(e0), float(np.abs(line.force) @ np.abs(
        sol.positions[-1] - line.position)))


def test_a_line_at_rest_under_a_force_below_its_rounding():
    # Found by the fuzzer, which runs a line for 30 of its time scales. The scales came
    # from the force and the contact of exponent 2.5 (a length of 4e-62), in which the
    # linear wall had a stiffness of 1e92 and the run ended at t = 0, non-finite. The
    # force presses ball 2 on the wall by f/k_R = 4e-154: the run ends with the balls
    # where they started, to far below 1e-15.
    line = Line.make(2, stiffness=1.0919, alpha=2.5, velocity=np.zeros(2),
                     force=[0.0, 4.18e-154], right=Wall(1.0, 1.0))
    t_end = 30.0 * line.scales().time
    sol = run(line, [t_end], t_end=t_end)
    assert_ok(sol, terminal=False)
    np.testing.assert_allclose(sol.positions[-1], line.position, rtol=0, atol=1e-15)


def test_a_ball_pressed_on_a_linear_wall_by_a_force_below_its_rounding():
    # The mirror of the line above, on a left wall, with its own mass and stiffness.
    # Ball 1, touching the wall at rest, is pushed into it by f; ball 2, untouched, stays
    # at rest. Ball 1 is then a linear oscillator about its static compression f/k_L:
    # x_1 = -(f/k_L) (1 - cos(w t)), w = sqrt(k_L/m_1), as long as it stays in contact
    # (it does: the compression never falls below 0). The motion, 1e-154 in size, is
    # resolved to the closed form's tolerance relative to its amplitude.
    f, m1, k_wall = 4.18e-154, 2.0, 0.7
    line = Line.make(2, mass=[m1, 1.0], stiffness=1.0919, alpha=2.5, velocity=np.zeros(2),
                     force=[-f, 0.0], left=Wall(k_wall, 1.0))
    times = np.linspace(0.0, 30.0, 61)
    sol = run(line, times, t_end=30.0)
    assert_ok(sol, terminal=False)
    w, amplitude = math.sqrt(k_wall / m1), f / k_wall
    np.testing.assert_allclose(sol.positions[:, 0] / amplitude, -(1.0 - np.cos(w * times)),
                               rtol=0, atol=TOL["closed_form"])
    np.testing.assert_allclose(sol.velocities[:, 0] / (amplitude * w), -np.sin(w * times),
                               rtol=0, atol=TOL["closed_form"])
    assert np.all(sol.positions[:, 1] == 0.0) and np.all(sol.velocities[:, 1] == 0.0)


@pytest.mark.parametrize("v", [
    1e-100,
    pytest.param(1e-34, marks=pytest.mark.xfail(strict=True, reason=(
        "solver defect: the wall's time is 12 eps of the unit here, above its rounding, "
        "so the scales stay the exponent-2.5 contact's; the integrator's smallest step "
        "is 8 eps of the unit, too coarse for the wall's collision: 'step size "
        "underflow at t = 0'. Lines whose fastest contact takes from eps to about 1e-12 "
        "of the unit (the bound depends on rtol and the exponents) fail so"))),
])
def test_a_ball_moving_at_a_speed_below_its_rounding_meets_a_linear_wall(v):
    # The moving twin of the line at rest above: ball 2 starts at v = 1e-100 into the
    # linear wall it touches. The scales came from the speed and the contact of exponent
    # 2.5 (a time of 7e42), in which the wall's collision lasts 4e-43 of the unit: the
    # run ended at t = 0 (non-finite, or its step too small). On a linear wall the ball
    # is a harmonic oscillator, x_2 = (v/w) sin(w t), w = sqrt(k_R/m_2), until t = pi/w,
    # when it leaves at -v (its energy kept). It then closes on ball 1, at rest, but by
    # t = 30 the contact of exponent 2.5 has pushed back with a force below
    # 1.1 (30 v)^2.5, a change of speed far below the rounding of v (1e-47 of it at
    # v = 1e-34): the ball goes on freely, x_2 = -v (t - pi/w), and ball 1 stays at rest.
    m2, k_wall = 1.0, 1.0
    line = Line.make(2, stiffness=1.0919, alpha=2.5, velocity=[0.0, v],
                     right=Wall(k_wall, 1.0))
    times = np.linspace(0.0, 30.0, 61)
    sol = run(line, times, t_end=30.0)
    assert_ok(sol, terminal=False)
    w = math.sqrt(k_wall / m2)
    on_wall = times < math.pi / w
    x2 = np.where(on_wall, np.sin(w * times), -(w * times - math.pi))  # in units of v/w
    v2 = np.where(on_wall, np.cos(w * times), -1.0)  # in units of v
    assert_close_in_time(sol.positions[:, 1] / (v / w), x2, times, TOL["closed_form"],
                         "ball 2's place")
    assert_close_in_time(sol.velocities[:, 1] / v, v2, times, TOL["closed_form"],
                         "ball 2's velocity")
    assert np.all(np.abs(sol.positions[:, 0]) <= 1e-15 * v)
    assert np.all(np.abs(sol.velocities[:, 0]) <= 1e-15 * v)


@pytest.mark.xfail(strict=True, reason=(
    "solver defect: in the wall's units the contact of exponent 2.5 has a stiffness of "
    "1e-150 and its collision lasts about 1e43 of them; the kernels end such a slow "
    "collision non-finite, here at t = 2e10 (so do two balls of exponent 2.5 and "
    "stiffness 1e-60 run in units of 1). No one unit spans both contacts' times, 1e43 "
    "apart"))
def test_a_ball_moving_at_a_speed_below_its_rounding_ends_at_rest_on_ball_1():
    # The line above, run to its terminal state: after the wall, ball 2 (at -v) meets
    # ball 1 of the same mass, at rest; momentum and energy leave two outcomes, and the
    # collision is the one that exchanges the velocities: (-v, 0).
    v = 1e-100
    line = Line.make(2, stiffness=1.0919, alpha=2.5, velocity=[0.0, v],
                     right=Wall(1.0, 1.0))
    sol = run(line)
    assert_ok(sol, terminal=True)
    np.testing.assert_allclose(sol.final_velocity / v, [-1.0, 0.0], rtol=0,
                               atol=TOL["closed_form"])


def test_a_contact_grazing_under_forces_keeps_the_energy():
    # Forces press strikers into a line at rest; contact 7 (balls 7-8), pressed at
    # first, eases to a compression of about 1e-6 near t = 6.5 and is pressed again.
    # c(t)^1.5 then has branch points close to the real axis; a series step from far
    # off did not see them in its last terms, crossed them, and lost 5e-10 of the
    # energy (1e-6 on the line the fuzzer drew). Checked against the reference.
    v = np.zeros(9)
    v[:6] = -0.6952839344444222
    f = np.array([0.0, 0.0, 0.3864294458501034, 0.0, 0.14511989985258966,
                  -0.39628154387910164, 0.1183503419072274, -0.3335239499192926,
                  0.3952204818281264]) / 5.63
    line = Line.make(9, alpha=1.5, velocity=v, force=f)
    times = np.linspace(0.0, 8.0, 9)
    sol = run(line, times, t_end=8.0)
    assert_ok(sol, terminal=False)
    e = [line_energy(line, x, u) for x, u in zip(sol.positions, sol.velocities)]
    # the energy to the 1e-11 the guide promises (docs/guide.md, Accuracy)
    np.testing.assert_allclose(e, e[0], rtol=0, atol=1e-11 * abs(e[0]))
    r = reference_line(line, t_max=8.0, times=times)
    np.testing.assert_array_less(np.abs(sol.positions - r.positions).max(axis=1),
                                 TOL["reference_position"] * (1.0 + times))
    np.testing.assert_allclose(sol.velocities, r.velocities, rtol=0,
                               atol=TOL["reference_velocity"])


def test_a_contact_closed_to_rounding_is_no_graze():
    # Found by the long fuzzer run: an active contact whose compression is -2e-15 (just
    # closed, within rounding) and falling at the series step's start made the graze
    # rule halve the step without end. The run reaches t = 1 in a dozen steps.
    line = Line.make(10, mass=[1.1289831396369512, 1.0, 0.49968117813123003, 1.0,
                               1.4286672007331265, 1.0, 1.7540069861213943,
                               0.13032144995125555, 1.0, 6.996000610866246],
                     alpha=[2.8501929113817557, 2.8501929113817557, 1.9, 1.0000000000000002,
                            2.1966249128820605, 2.6987585022618616, 1.0, 2.0271273468736037,
                            2.5],
                     velocity=[1.0] + [0.0] * 9)
    sol = run(line, t_end=1.0, max_events=1000)
    assert sol.outcome == Outcome.STOP_TIME, sol.message
    assert sol.diagnostics.steps < 100


def test_bouncing_ball_under_a_force():
    # A ball pressed on a linear wall by a constant force (gravity): parabolic flights
    # between bounces of closed-form duration; no terminal state, so t_end.
    m, k, f, v0, g = 1.3, 4.0, 0.9, -0.4, 0.2
    line = Line.make(1, mass=m, velocity=[v0], force=[f], right=Wall(k, 1.0, g))
    a = f / m
    u1 = math.sqrt(v0 * v0 + 2 * a * g)                  # speed at the wall
    t1 = (-v0 + u1) / a                                   # first touch
    tb = linear_wall_bounce(m, k, f, u1)
    fl = 2 * u1 / a
    expect = [t1, t1 + tb, t1 + tb + fl, t1 + 2 * tb + fl, t1 + 2 * tb + 2 * fl]
    t_end = expect[-1] + 0.5 * tb
    sol = run(line, [expect[1] + 0.5 * fl, t_end], t_end=t_end)
    assert_ok(sol, terminal=False)
    assert sol.end_time == pytest.approx(t_end, rel=1e-15)
    t, c, kind = located(sol)
    assert list(kind) == [EventKind.CLOSE, EventKind.OPEN] * 2 + [EventKind.CLOSE]
    np.testing.assert_allclose(t, expect, rtol=0, atol=TOL["closed_form"])
    assert sol.velocities[0, 0] == pytest.approx(0.0, abs=TOL["closed_form"])
    assert sol.positions[0, 0] == pytest.approx(g - u1 * u1 / (2 * a),
                                                abs=TOL["closed_form"])
    np.testing.assert_allclose(sol.positions[-1], sol.final_position, rtol=0, atol=0)


# ---- 2. Scaling laws --------------------------------------------------------------------
def scaling_line(c_mass: float = 1.0, c_speed: float = 1.0) -> Line:
    return Line.make(4, mass=np.array([1.0, 3.0, 0.5, 2.0]) * c_mass,
                     stiffness=np.array([1.0, 0.4, 2.0]) * c_mass, alpha=[1.5, 1.0, 2.0],
                     gap=[0.0, 0.1, 0.0], velocity=np.array([1.0, 0.0, 0.0, -0.3]) * c_speed,
                     right=Wall(0.8 * c_mass, 1.5, 0.05))


@pytest.mark.parametrize("c", [1e-3, 10.0, 7.5e4])
def test_scaling_masses_and_stiffnesses(c):
    # m x'' = F(x): every mass and stiffness times c changes nothing.
    a, b = run(scaling_line()), run(scaling_line(c_mass=c))
    assert_ok(b, terminal=True)
    np.testing.assert_allclose(b.final_velocity, a.final_velocity, rtol=0,
                               atol=TOL["scaling"])
    np.testing.assert_allclose(b.event_time, a.event_time, rtol=TOL["scaling"])
    np.testing.assert_array_equal(b.event_contact, a.event_contact)


@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
@pytest.mark.parametrize("s", [0.01, 0.5, 30.0])
def test_scaling_striker_speed(s, alpha):
    # One exponent a, no gap: x(t) -> s^p x(s^(p-1) t), p = 2/(a+1), maps solutions
    # to solutions: velocities scale with the striker's speed s, times with
    # s^((1-a)/(1+a)) (s^(-1/5) for Hertz).
    kw = dict(mass=[1.0, 3.0, 0.5, 2.0], stiffness=[1.0, 0.4, 2.0], alpha=alpha)
    a = run(Line.make(4, velocity=[1.0, 0, 0, -0.3], **kw))
    b = run(Line.make(4, velocity=[s, 0, 0, -0.3 * s], **kw))
    np.testing.assert_allclose(b.final_velocity, s * a.final_velocity, rtol=0,
                               atol=TOL["scaling"] * s)
    np.testing.assert_allclose(b.event_time, a.event_time * s ** ((1 - alpha) / (1 + alpha)),
                               rtol=TOL["scaling"])


@pytest.mark.parametrize("n", [2, 10, 25])
def test_steel_chain_in_si_units(n):
    # 25.4 mm steel beads (E = 200 GPa, nu = 0.3, rho = 7850 kg/m^3) struck at 0.5 m/s:
    # in the paper's units (mass m, time (m / (kappa u^(1/2)))^(2/5), speed u) this is
    # the paper's line, so velocities are 0.5 x those of Line.paper(n, 1, 1.5) and
    # times scale.
    u = 0.5
    mass, kappa = steel_bead()
    sol = run(Line.make(n, mass=mass, stiffness=kappa, alpha=1.5, speed=u))
    paper = simulate(Line.paper(n, 1, 1.5))
    assert_ok(sol, terminal=True)
    np.testing.assert_allclose(sol.final_velocity, u * paper.final_velocity, rtol=0,
                               atol=TOL["si"] * u)
    t_unit = (mass / (kappa * math.sqrt(u))) ** 0.4        # 3.3e-5 s here
    assert sol.end_time == pytest.approx(paper.end_time * t_unit, rel=TOL["si"])
    np.testing.assert_allclose(sol.final_position, paper.final_position * u * t_unit,
                               rtol=0, atol=TOL["si"] * u * t_unit * (1 + paper.end_time))
    if n <= 10:   # and the reference, for chainrun's paper run
        r = reference_line(paper_line(n, 1, 1.5))
        np.testing.assert_allclose(sol.final_velocity, u * r.final_velocity, rtol=0,
                                   atol=TOL["reference_velocity"] * u)


# ---- 3. Against the reference -----------------------------------------------------------
PAPER = [pytest.param(n, k, a, id=f"N{n}-K{k}-a{a}")
         for n, k, a in [(2, 1, 1.5), (3, 1, 1.0), (4, 2, 2.0), (5, 1, 1.5), (6, 3, 2.5),
                         (7, 2, 1.25), (8, 1, 3.0)]]


@pytest.mark.parametrize(("n", "k", "alpha"), PAPER)
def test_paper_lines_against_reference(n, k, alpha):
    line = Line.paper(n, k, alpha)
    sol, r = run(line), reference_line(line)
    assert_ok(sol, terminal=True)
    np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                               atol=TOL["reference_velocity"])
    assert_same_events(located(sol), (r.event_time, r.event_contact, r.event_kind),
                       TOL["reference_time"])
    assert abs(sol.end_time - r.end_time) <= TOL["reference_time"] * (1 + r.end_time)


@pytest.mark.parametrize("velocity", [[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
def test_paper_units_strikers_anywhere(velocity):
    # Unit masses and stiffnesses and velocities 0 or 1 in any order.
    line = Line.make(len(velocity), velocity=velocity, alpha=1.5)
    sol, r = run(line), reference_line(line)
    np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                               atol=TOL["reference_velocity"])


RANDOM = [pytest.param(f, s, id=f"{f}-{s}") for f in FAMILIES for s in range(3)]
#: Events up to this time (the lines' durations are of order 1) belong to the initial
#: state.
T0 = 1e-12




@pytest.mark.parametrize(("family", "seed"), RANDOM)
def test_random_lines_final_state(family, seed):
    # Masses (ratio up to 10), stiffnesses, exponents 1/1.5/2 mixed, gaps and overlaps,
    # heavy and light strikers, head-on strikers, walls, gravity with a wall, initial
    # positions: see reference.random_line.
    line, t_max = random_line(family, seed)
    sol = run(line, t_end=t_max)
    r = ref_random(family, seed)
    assert_ok(sol, terminal=r.terminal)
    assert r.terminal is (t_max is None)
    np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                               atol=TOL["reference_velocity"])
    assert abs(sol.end_time - r.end_time) <= TOL["reference_time"] * (1 + r.end_time)
    assert_close_in_time(sol.final_position, r.final_position, r.end_time,
                         TOL["reference_position"], "final position")
    # energy minus the forces' work is conserved, and momentum changes by the forces'
    # and the walls' impulses (which the solver integrates along the run)
    assert sol.diagnostics.momentum_error <= 1e-10
    e0 = line_energy(line, line.position, line.velocity)
    scale = max(abs(e0), 0.5 * float(np.sum(line.mass * line.velocity ** 2)))
    e1 = line_energy(line, sol.final_position, sol.final_velocity)
    assert abs(e1 - e0) <= TOL["energy"] * scale
    if t_max is None:    # terminal: nothing approaches; walls are bodies at rest
        v = sol.final_velocity
        assert np.all(np.diff(v) >= -1e-10)
        assert line.right is None or v[-1] <= 1e-10
        assert line.left is None or v[0] >= -1e-10


@pytest.mark.parametrize(("family", "seed"), RANDOM)
def test_random_lines_events(family, seed):
    # The located openings and closings after t = 0 (what each solver logs of its
    # initial state, such as touching balls parting at once, is its own convention):
    # same contacts, kinds and times.
    line, t_max = random_line(family, seed)
    sol = run(line, t_end=t_max)
    r = ref_random(family, seed)
    keep = r.event_time > T0
    assert_same_events(located(sol, after=T0),
                       (r.event_time[keep], r.event_contact[keep], r.event_kind[keep]),
                       TOL["reference_time"])


@pytest.mark.parametrize("family", FAMILIES)
def test_random_lines_snapshots(family):
    line, t_max = random_line(family, 0)
    end = ref_random(family, 0).end_time
    times = np.array([0.0, 0.2, 0.5, 0.9, 1.0, 1.3]) * end
    if t_max is not None:
        times = times[times <= t_max]
    sol = run(line, times, t_end=t_max)
    r = reference_line(line, t_max=t_max, times=times)
    np.testing.assert_array_equal(sol.times, times)
    for i, ti in enumerate(times):
        assert_close_in_time(sol.positions[i], r.positions[i], ti,
                             TOL["reference_position"], f"positions at t = {ti}")
        assert_close_in_time(sol.velocities[i], r.velocities[i], 0.0,
                             TOL["reference_velocity"], f"velocities at t = {ti}")


@pytest.mark.slow
@pytest.mark.parametrize("family", FAMILIES)
def test_random_lines_many(family):
    for seed in range(3, 15):
        line, t_max = random_line(family, seed)
        sol = run(line, t_end=t_max)
        r = reference_line(line, t_max=t_max)
        assert bool(sol.terminal) is r.terminal, f"seed {seed}: {sol.message}"
        np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                                   atol=TOL["reference_velocity"], err_msg=f"seed {seed}")


@pytest.mark.parametrize("alpha", [1.0, 1.5])
def test_precompressed_line_against_reference(alpha):
    # Balls at rest in their static equilibrium under a load against a wall, struck by
    # a heavier ball: the disturbance, and nothing else, moves them.
    from chainrun.solver.model import precompress

    base = Line.make(6, mass=[2.0, 1.0, 1.5, 1.0, 0.5, 1.0], alpha=alpha,
                     stiffness=[1.0, 2.0, 0.5, 1.0, 3.0], k=1, speed=0.8,
                     right=Wall(2.0, alpha))
    line = precompress(base, 0.3)
    t_max = 12.0
    sol = run(line, [2.0, 6.0], t_end=t_max)
    r = reference_line(line, t_max=t_max, times=[2.0, 6.0])
    assert_ok(sol, terminal=False)
    np.testing.assert_allclose(sol.final_velocity, r.final_velocity, rtol=0,
                               atol=TOL["reference_velocity"])
    np.testing.assert_allclose(sol.velocities, r.velocities, rtol=0,
                               atol=TOL["reference_velocity"])


def test_precompressed_line_at_rest_stays_at_rest():
    # Without a striker the equilibrium holds: nothing moves beyond rounding.
    from chainrun.solver.model import precompress

    base = Line.make(5, velocity=[0.0, 0.0, 0.0, 0.0, 0.0], stiffness=[1.0, 2.0, 0.5, 1.0],
                     alpha=1.5, right=Wall(1.0, 1.5), k=None)
    with pytest.raises(ValueError, match="ball at rest after the strikers|strikers"):
        precompress(Line.make(2, k=2, right=Wall(1.0)), 1.0)
    line = precompress(base, 0.5)
    sol = run(line, [50.0], t_end=50.0)
    assert np.max(np.abs(sol.final_velocity)) < 1e-12
    np.testing.assert_allclose(sol.final_position, line.position, rtol=0, atol=1e-12)
