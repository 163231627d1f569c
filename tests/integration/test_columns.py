"""A column of beads on a floor under its weight (``chain.gravity``), run: at rest it
stays at rest, struck its impact energy is the striker's, and ``info`` says what the
line is and where the energy went, the weight's potential energy apart."""

from __future__ import annotations

import re

import h5py
import numpy as np
from click.testing import CliRunner
from helpers import simulate_text

from chainrun.cli import main

COLUMN = """name = "column"
units = "si"
[chain]
n = 10
k = {k}
{speed}
diameter = 0.008
material = "chrome_steel"
gravity = 9.81
[walls.right]
material = "steel"
[solver]
t_end = 5e-3
"""


def test_a_column_at_rest_on_its_floor_stays_at_rest(tmp_path):
    out = simulate_text(tmp_path, COLUMN.format(k=0, speed=""))
    with h5py.File(out / "run.h5") as f:
        v = f["results/final_velocity"][()]
        x0, x = f["model/position"][()], f["results/final_position"][()]
        impulse = f["results/wall_impulse"][()]
        mass = f["model/mass"][()]
    # (rounding: velocities of 1e-16 m/s against those of a ball falling 5 ms, 5e-2 m/s)
    assert np.abs(v).max() < 1e-15
    assert np.abs(x - x0).max() < 1e-18 * 1e3  # m: against 2e-7 m of static compression
    # the floor held the column's weight all along: its impulse, -W t
    np.testing.assert_allclose(impulse[1], -9.81 * mass.sum() * 5e-3, rtol=1e-10)


def test_a_struck_column_shares_its_impact_energy_the_weight_apart(tmp_path):
    out = simulate_text(tmp_path, COLUMN.format(k=1, speed="speed = 0.3"))
    with h5py.File(out / "run.h5") as f:
        m = f["model/mass"][()]
        force, x0, x = f["model/force"][()], f["model/position"][()], \
            f["results/final_position"][()]
    text = CliRunner().invoke(main, ["info", str(out / "run.h5")]).stdout
    line = next(t for t in text.splitlines() if t.startswith("line"))
    assert "under gravity 9.81 m/s^2 towards ball N, resting on the right wall" in line
    assert "forces on" not in line
    energy = next(t for t in text.splitlines() if t.startswith("energy"))
    impact = 0.5 * m[0] * 0.3**2  # the striker's: the column's static state is not the impact's
    shown = float(re.search(r"impact energy ([\d.]+) µJ", energy).group(1))
    assert shown == round(impact * 1e6, 2)
    against = float(re.search(r"against the forces (-?[\d.]+)%", energy).group(1))
    assert against == round(100 * -float(force @ (x - x0)) / impact, 2)


def test_the_energy_view_draws_the_weights_potential_energy_apart(tmp_path):
    """As info shares it: the energy against the weights, -sum f (x - x(0)) at each
    snapshot, a curve of its own; the contacts' curve the rest of the stored energy."""
    from chainrun.plotting import style
    from chainrun.plotting.views import draw_view
    from chainrun.store import read_run

    out = simulate_text(tmp_path, COLUMN.format(k=1, speed="speed = 0.3")
                        + "[output]\ntimes = {start = 0, stop = 5e-3, step = 5e-4}\n")
    with h5py.File(out / "run.h5") as f:
        force, x0 = f["model/force"][()], f["model/position"][()]
        x = f["particles/chain/position/value"][:, :, 0]
        stored = f["observables/potential_energy/value"][()]
    run = read_run(out / "run.h5")
    with style():
        figure = draw_view(run, "energy")
    lines = {a.get_gid(): a for a in figure.axes[0].get_lines()}
    factor = {"µJ": 1e6, "mJ": 1e3, "nJ": 1e9}[re.search(r"\((\S+)\)",
                                                     figure.axes[0].get_ylabel()).group(1)]
    against = -(x - x0) @ force
    np.testing.assert_allclose(lines["forces_energy"].get_ydata(), against * factor,
                               rtol=1e-12, atol=1e-18 * factor)
    np.testing.assert_allclose(lines["potential_energy"].get_ydata(),
                               (stored - run.baseline_energy - against) * factor,
                               rtol=1e-9, atol=1e-12 * factor * abs(stored).max())
