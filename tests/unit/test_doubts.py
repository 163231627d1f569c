"""Valid inputs that are probably not meant (``chainrun.config.doubts``) and runs whose
energy balance is far off (``chainrun.check.energy_doubt``): warned of, and run."""

from __future__ import annotations

import numpy as np
import pytest

from chainrun.check import ENERGY_DOUBT, energy_doubt
from chainrun.config import load_experiment
from chainrun.config.doubts import doubts
from chainrun.runner import sweep_specs

BEADS = """name = "beads"
units = "si"
[chain]
n = 10
k = 1
speed = 0.5
diameter = {diameter}
material = "steel"
{chain}
[walls.right]
material = "steel"
gap = {gap}
[solver]
t_end = 1.0e-3
"""


def doubts_of(tmp_path, diameter=0.02, gap=0.0, chain=""):
    path = tmp_path / "beads.toml"
    path.write_text(BEADS.format(diameter=diameter, gap=gap, chain=chain))
    return doubts(sweep_specs(load_experiment(path)))


def test_real_beads_raise_no_doubt(tmp_path):
    # a gap of a few beads and an overlap of a micrometre are experiments
    assert doubts_of(tmp_path, gap=0.05, chain="gap = -1.0e-6") == []


def test_millimetres_typed_as_metres_are_named(tmp_path):
    # 20 m spheres of steel: (pi/6) 20^3 7850 kg = 3.29e7 kg
    (line,) = doubts_of(tmp_path, diameter=20.0)
    assert line.startswith("chain.diameter: spheres of 20 m (ball 1: 3.29e+07 kg)")
    assert "(20 mm would be 0.02)" in line
    (line,) = doubts_of(tmp_path, gap=5.0)
    assert line.startswith("walls.right.gap: a gap of 5 m, 250 diameters")
    (line,) = doubts_of(tmp_path, chain="gap = [0, 0, 3.0, 0, 0, 0, 0, 0, 0]")
    assert line.startswith("chain.gap (contact 3, balls 3-4): a gap of 3 m")


def test_an_overlap_deeper_than_hertz_holds_is_named(tmp_path):
    (line,) = doubts_of(tmp_path, gap=-1.0)
    assert line.startswith("walls.right.gap: an overlap of 1 m, 50 times the diameter; "
                           "the spheres would be inside one another")
    (line,) = doubts_of(tmp_path, chain="gap = -0.004")
    assert line.startswith("chain.gap (contact 1, balls 1-2): an overlap of 4 mm, 0.2 of "
                           "the diameter") and line.endswith("(and 8 more)")


SHAKEN = """name = "shaken"
[chain]
n = 6
k = 0
alpha = 1.5
precompression = 1.0
[walls.left]
motion = {{amplitude = {amplitude}, frequency = {frequency}}}
[walls.right]
[output]
sensors = [1, 6]
sensor_dt = {sensor_dt}
[solver]
t_end = 100.0
"""


def shaken_doubts(tmp_path, amplitude=1e-6, frequency=0.05, sensor_dt=0.5):
    path = tmp_path / "shaken.toml"
    path.write_text(SHAKEN.format(amplitude=amplitude, frequency=frequency,
                                  sensor_dt=sensor_dt))
    return doubts(sweep_specs(load_experiment(path)))


def test_an_impact_far_past_hertz_is_named(tmp_path):
    """Two equal spheres meeting at w press together by c = (5 mu w^2 / (4 kappa))^(2/5),
    mu = m / 2, kappa = E d^(1/2) / (3 (1 - nu^2)): at 300 m/s (0.3 m/s typed in mm/s)
    about a tenth of a steel bead's diameter; at 10 m/s well below a hundredth."""
    young, poisson, rho, d = 207e9, 0.30, 7850.0, 0.02  # materials: steel
    mass = rho * np.pi * d**3 / 6
    kappa = young * d**0.5 / (3 * (1 - poisson**2))

    def doubts_at(speed):
        path = tmp_path / "fast.toml"
        path.write_text(f'name = "fast"\nunits = "si"\n[chain]\nn = 5\nk = 1\n'
                        f'speed = {speed}\ndiameter = {d}\nmaterial = "steel"\n')
        return doubts(sweep_specs(load_experiment(path)))

    (line,) = doubts_at(300.0)
    depth = (5 * (mass / 2) * 300.0**2 / (4 * kappa)) ** 0.4
    assert line.startswith(f"chain.speed: balls 1 and 2 meet at 300 m/s and would press "
                           f"together by {depth * 1e3:.4g} mm, {100 * depth / d:.2g}% of their "
                           f"diameter")
    assert line.endswith("speeds in an SI file are in m/s (300 mm/s would be 0.3)")
    assert doubts_at(10.0) == []


def test_a_shaken_line_sampled_well_raises_no_doubt(tmp_path):
    # 40 samples a period (paper units: a line of masses is judged for its drive too)
    assert shaken_doubts(tmp_path) == []


def test_a_wall_that_does_not_move_is_named(tmp_path):
    (line,) = shaken_doubts(tmp_path, amplitude=0.0)
    assert line.startswith("walls.left.motion.amplitude: 0, so the wall does not move")


def test_sensors_too_slow_for_the_drive_are_named(tmp_path):
    # f = 0.05 sampled every 4: 5 samples a period, fewer than the 7 a fit of three
    # harmonics needs; below 1 / (6 f) = 3.333 it would do
    (line,) = shaken_doubts(tmp_path, sensor_dt=4.0)
    assert line.startswith("output.sensor_dt: 4 samples the left wall's 0.05 5 times a period")
    assert line.endswith("(a sensor_dt below 3.333)")


def test_a_far_off_energy_balance_is_a_doubt():
    assert energy_doubt(1e-11) is None and energy_doubt(ENERGY_DOUBT) is None
    assert energy_doubt(2.3e-4).startswith("its energy balance is off by 2.3e-04")


def test_the_energy_rounding_bounds_what_a_rounding_of_the_positions_moves():
    # a precompressed line between walls: its positions carry the static compressions,
    # and moving each by one unit in its last place moves the stored energy by at most
    # the sum of the forces times those units, the estimate energy_rounding gives
    import numpy as np

    from chainrun.solver.model import Line, Wall, precompress
    from chainrun.solver.physics import energy_rounding, line_potential_energy

    line = precompress(Line.make(20, alpha=1.5, velocity=np.zeros(20), left=Wall(1.0, 1.5),
                                 right=Wall(1.0, 1.5)), 5.0)
    x = line.position
    floor = energy_rounding(x, line)
    u = float(line_potential_energy(x, line))
    rng = np.random.default_rng(1)
    moved = [abs(float(line_potential_energy(x + rng.choice([-1.0, 1.0], x.size)
                                             * np.spacing(np.abs(x)), line)) - u)
             for _ in range(50)]
    assert 0.0 < max(moved) <= floor
    assert floor <= 1e3 * np.finfo(float).eps * u * line.n  # and not wildly above it
