"""Damped lines end to end: the experiment file's restitution, the run file, the reader.

The restitution asked for in the config must come out of the solver's two-ball
collision; the run file keeps what the damping dissipated, and the forces it gives
from the stored state are the damped law the solver integrated.
"""

from __future__ import annotations

import numpy as np
import pytest
from helpers import simulate_text

from chainrun.config import parse_experiment
from chainrun.solver import simulate
from chainrun.solver.physics import line_kinetic_energy, line_potential_energy
from chainrun.store import read_run


def _pair(law: str, e: float, speed: float, at: float | None = None, alpha: float = 1.5):
    reference = f"restitution_speed = {at}" if at is not None else ""
    text = f"""
name = "pair"
[chain]
n = 2
k = 1
speed = {speed}
mass = [1.0, 2.5]
stiffness = 3.0
alpha = {alpha}
restitution = {e}
damping_law = "{law}"
{reference}
"""
    return parse_experiment(text, "toml").runs()[0].line


def _measured(line):
    sol = simulate(line)
    assert sol.terminal
    v0 = line.velocity[0]
    return (sol.final_velocity[1] - sol.final_velocity[0]) / v0


@pytest.mark.parametrize("speed", [1e-3, 0.3, 1.0, 40.0])
@pytest.mark.parametrize("alpha", [1.0, 1.5, 2.5])
def test_the_tsuji_law_gives_the_restitution_asked_for_at_every_speed(alpha, speed):
    assert _measured(_pair("tsuji", 0.8, speed, alpha=alpha)) == pytest.approx(0.8, abs=1e-6)


@pytest.mark.parametrize("law", ["dashpot", "kuwabara-kono"])
@pytest.mark.parametrize("at", [0.05, 2.0])
def test_speed_dependent_laws_give_it_at_the_speed_they_were_set_for(law, at):
    assert _measured(_pair(law, 0.7, at, at=at)) == pytest.approx(0.7, abs=1e-6)
    # and elsewhere not: the speed matters for these laws
    other = _measured(_pair(law, 0.7, 10 * at, at=at))
    assert abs(other - 0.7) > 1e-3


def test_the_linear_dashpot_is_speed_free():
    for speed in (0.01, 1.0, 100.0):
        assert _measured(_pair("dashpot", 0.6, speed, alpha=1.0)) == pytest.approx(0.6, abs=1e-6)


def test_a_damped_run_file_keeps_the_dissipated_energy(tmp_path):
    out = simulate_text(tmp_path, """
name = "damped"
units = "si"
[chain]
n = 6
k = 1
speed = 0.5
diameter = 0.0254
material = "steel"
restitution = 0.85
damping_law = "tsuji"
[walls.right]
material = "steel"
restitution = 0.7
damping_law = "kuwabara-kono"
restitution_speed = 0.5
[output]
times = {start = 0.0, stop = 1.0e-3, step = 5.0e-6}
sensors = [3]
sensor_dt = 5.0e-6
""")
    run = read_run(out / "run.h5")
    line = parse_experiment((tmp_path / "experiment.toml").read_text(), "toml").runs()[0].line
    d = run.observables["dissipated_energy"]
    assert d.shape == run.times.shape and d[0] == 0.0 and np.all(np.diff(d) >= -1e-18)
    e0 = float(line_kinetic_energy(line.velocity, line.mass))
    x, v = np.asarray(run.positions), np.asarray(run.velocities)
    energy = line_kinetic_energy(v, line.mass) + line_potential_energy(x, line) + d
    np.testing.assert_allclose(energy, e0, rtol=1e-9)
    total = run.contact_dissipation.sum() + run.wall_dissipation.sum()
    assert total == pytest.approx(run.dissipated_energy, rel=1e-12)
    assert run.wall_dissipation[1] > 0.0 and run.wall_dissipation[0] == 0.0
    assert run.model["damping"].shape == (5,) and np.all(run.model["damping"] > 0.0)
    assert run.model["walls"]["right"]["damping"] > 0.0
    # the stored forces are the damped law: the sensor's samples on the solver's step
    forces = run.contact_forces()
    m = min(run.sensor_time.size, run.times.size)
    scale = forces.max()
    for side in (0, 1):
        np.testing.assert_allclose(forces[:m, 1 + side], run.sensor_force[:m, 0, side],
                                   rtol=1e-9, atol=1e-9 * scale)
    np.testing.assert_array_equal(run.contact_forces(stride=2), forces[:, ::2])


def test_the_summary_says_what_the_damping_took(tmp_path):
    from click.testing import CliRunner

    from chainrun.cli import main

    out = simulate_text(tmp_path, """
name = "damped"
[chain]
n = 4
k = 1
alpha = 1.5
restitution = 0.5
damping_law = "tsuji"
""")
    result = CliRunner().invoke(main, ["info", str(out / "run.h5")])
    assert result.exit_code == 0, result.output
    assert "damping   dissipated" in result.output
    assert "of the impact energy" in result.output and "dissipated " in result.output


def test_open_run_gives_the_dissipation_in_si_units(tmp_path):
    from chainrun.api import open_run

    out = simulate_text(tmp_path, """
name = "damped"
units = "si"
[chain]
n = 3
k = 1
speed = 0.5
diameter = 0.0254
material = "steel"
restitution = 0.9
damping_law = "tsuji"
[output]
times = {start = 0.0, stop = 4.0e-4, step = 2.0e-5}
""")
    ds = open_run(out / "run.h5")
    assert ds["dissipated_energy"].attrs["units"] == "J"
    assert ds["velocity"].attrs["units"] == "m/s"
    assert ds["contact_dissipation"].sizes["contact"] == 2
    assert float(ds["dissipated_energy"][-1]) == pytest.approx(ds.attrs["dissipated_energy"],
                                                               rel=1e-9)
    assert ds.attrs["dissipated_energy"] > 0.0


def test_the_run_file_keeps_the_walls_impulses(tmp_path):
    out = simulate_text(tmp_path, """
name = "bounce"
[chain]
n = 2
k = 1
mass = [1.0, 3.0]
alpha = 1.5
[walls.right]
stiffness = 1.0
""")
    run = read_run(out / "run.h5")
    # everything that reaches the wall comes back: the momentum the wall gave is the
    # line's final momentum less its initial one
    p = float(run.model["mass"] @ run.final_velocity) - 1.0
    assert run.wall_impulse[1] == pytest.approx(p, rel=1e-10)
    assert run.wall_impulse[1] < 0.0 and run.wall_impulse[0] == 0.0
