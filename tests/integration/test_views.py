"""Views of any run (``chainrun plot RUN``): what is drawn is what the file holds, read
back from the figures' artists and compared with the file read by h5py."""

from __future__ import annotations

import hashlib
import re

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from helpers import simulate_text

from chainrun.cli import main
from chainrun.plotting import render_run, style
from chainrun.plotting.views import VIEWS, draw_view
from chainrun.store import read_run

WAVE = """name = "wave"
[chain]
n = 30
k = 2
alpha = 1.5
[output]
times = {start = 0, stop = 40, step = 0.5}
"""


@pytest.fixture(scope="module")
def wave(tmp_path_factory):
    path = simulate_text(tmp_path_factory.mktemp("views"), WAVE) / "run.h5"
    with h5py.File(path) as f:
        raw = dict(v=f["particles/chain/velocity/value"][:, :, 0],
                   x=f["particles/chain/position/value"][:, :, 0],
                   t=f["particles/chain/velocity/time"][()],
                   final=f["results/final_velocity"][()],
                   kinetic=f["observables/kinetic_energy/value"][()],
                   stored=f["observables/potential_energy/value"][()])
    return path, raw


def artist(figure, gid):
    axes = figure.axes[0]
    return next(a for a in axes.get_children() if a.get_gid() == gid)


def test_the_spacetime_image_is_the_velocity_snapshots(wave):
    path, raw = wave
    with style():
        figure = draw_view(read_run(path), "spacetime")
    image = artist(figure, "velocity")
    np.testing.assert_array_equal(image.get_array(), raw["v"].T)
    left, right, bottom, top = image.get_extent()
    assert (left, right) == (raw["t"][0], raw["t"][-1]) and (bottom, top) == (0.5, 30.5)
    assert "velocity" in figure.axes[1].get_ylabel()  # the colour bar


def test_final_velocities_and_profiles_are_the_files(wave):
    path, raw = wave
    run = read_run(path)
    with style():
        final = draw_view(run, "final", log=True)
        profiles = draw_view(run, "profiles")
    line = artist(final, "final_velocity")
    np.testing.assert_array_equal(line.get_xdata(), np.arange(1, 31))
    np.testing.assert_array_equal(line.get_ydata(), raw["final"])
    assert final.axes[0].get_yscale() == "symlog"
    drawn = [a for a in profiles.axes[0].get_lines() if str(a.get_gid()).startswith("velocity/")]
    assert 2 <= len(drawn) <= 6
    for a in drawn:
        np.testing.assert_array_equal(a.get_ydata(), raw["v"][int(a.get_gid().split("/")[1])])


def test_profiles_are_spread_over_the_run_until_its_terminal_state(tmp_path):
    """Snapshots long after the terminal state hold the same velocities: the profiles
    are drawn at snapshots until the first at or after it, the last of them that."""
    out = simulate_text(tmp_path, 'name = "late"\n[chain]\nn = 10\nk = 1\nalpha = 1.5\n'
                                  '[output]\ntimes = {start = 0, stop = 100, step = 1}\n')
    run = read_run(out / "run.h5")
    assert run.terminal and run.end_time < 30.0  # (10 balls: the wave is out by t ~ 15)
    with style():
        profiles = draw_view(run, "profiles")
    picked = [int(a.get_gid().split("/")[1]) for a in profiles.axes[0].get_lines()
              if str(a.get_gid()).startswith("velocity/")]
    first_after = int(np.flatnonzero(run.times >= run.end_time)[0])
    assert picked[-1] == first_after and len(picked) == 6


def test_the_energy_view_shows_energy_conserved(wave):
    path, raw = wave
    with style(colour=True):
        figure = draw_view(read_run(path), "energy")
    np.testing.assert_array_equal(artist(figure, "kinetic_energy").get_ydata(), raw["kinetic"])
    np.testing.assert_array_equal(artist(figure, "potential_energy").get_ydata(), raw["stored"])
    total = artist(figure, "total_energy").get_ydata()
    np.testing.assert_allclose(total, 1.0, rtol=1e-9)  # K = 2 balls at velocity 1: K/2


def test_plot_writes_every_view_the_same_bytes_twice(wave, tmp_path):
    path, _ = wave
    first = render_run(path, out=tmp_path / "a")
    second = render_run(path, out=tmp_path / "b")
    drawn = [v for v in VIEWS if v != "sensors"]  # the run has no sensors
    assert [p.name for p in first] == [f"run-{v}{s}" for v in drawn for s in (".png", ".pdf")]
    digest = [hashlib.sha256(p.read_bytes()).digest() for p in first]
    assert digest == [hashlib.sha256(p.read_bytes()).digest() for p in second]


def test_the_command_draws_a_run_and_refuses_what_it_cannot(wave, tmp_path):
    path, _ = wave
    runner = CliRunner()
    result = runner.invoke(main, ["plot", str(path), "--what", "final", "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run-final.pdf", "run-final.png"]
    result = runner.invoke(main, ["plot", str(path), "--what", "nonsense"])
    assert result.exit_code == 2 and "no view 'nonsense'" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_a_sweep_draws_chosen_balls_against_the_swept_key(tmp_path):
    from pathlib import Path

    from chainrun.plotting.views import draw_sweep
    from chainrun.store import read_index

    table1 = Path(__file__).resolve().parents[2] / "configs" / "table1.toml"
    out = tmp_path / "table1"
    runner = CliRunner()
    assert runner.invoke(main, ["simulate", str(table1), "-o", str(out)]).exit_code == 0
    rows = read_index(out / "index.h5")
    finals = {}
    for row in rows:
        with h5py.File(out / row["file"]) as f:
            finals[int(row["k"])] = f["results/final_velocity"][()]
    with style():
        figure = draw_sweep([read_run(out / row["file"]) for row in rows], balls=(1, 2, -1))
    for ball, column in ((1, 0), (2, 1), (-1, -1)):
        line = artist(figure, f"final_velocity/chain.k/{ball}")
        np.testing.assert_array_equal(line.get_xdata(), [1, 2, 3, 4])
        np.testing.assert_array_equal(line.get_ydata(), [finals[k][column] for k in (1, 2, 3, 4)])
    # the swept key in words and as written, whole-number ticks, and a title that
    # does not give the K of one run for the whole sweep
    assert figure.axes[0].get_xlabel() == "K, balls that strike (chain.k)"
    assert np.all(np.mod(figure.axes[0].get_xticks(), 1.0) == 0.0)
    assert "K =" not in figure.get_suptitle() and "N = 5" in figure.get_suptitle()
    from chainrun.plotting.views import draw_sweep_runs

    with style():
        panels = draw_sweep_runs([read_run(out / row["file"]) for row in rows])
    assert [ax.get_title() for ax in panels.axes] == ["k=1", "k=2", "k=3", "k=4"]
    assert len({ax.get_ylim() for ax in panels.axes}) == 1  # one scale: runs compare
    for k, ax in enumerate(panels.axes, start=1):
        (line,) = [a for a in ax.get_lines() if a.get_gid() == f"final_velocity/k={k}"]
        np.testing.assert_array_equal(line.get_ydata(), finals[k])
    result = runner.invoke(main, ["plot", str(out), "--what", "final", "--balls", "1,-1"])
    assert result.exit_code == 0, result.output
    assert (out / "figures" / "sweep-final.png").is_file()
    assert (out / "figures" / "sweep-runs.png").is_file()
    result = runner.invoke(main, ["plot", str(out), "--balls", "first"])
    assert result.exit_code == 2 and "--balls 'first'" in result.stderr
    for balls, bad in (("0", 0), ("1,99", 99), ("-6", -6)):  # table 1: lines of 5 balls
        result = runner.invoke(main, ["plot", str(out), "--what", "sweep-final",
                                      "--balls", balls])
        assert result.exit_code == 2
        assert f"no run has ball {bad} (N = 5;" in result.stderr


def test_a_sweep_of_the_impact_speed_draws_its_pulses_with_their_power_laws(tmp_path):
    """A Hertz line struck at speeds over two decades: its equations scale, so that
    the solitary wave's speed goes exactly as v^(1/5), its peak force as v^(6/5) and
    its width as v^(-1/5) (Nesterenko); the figure's curves are the pulses ``info``
    gives for each run, and their legends the fitted exponents."""
    from chainrun.analysis.pulse_sweep import power_law, pulse_sweep

    out = simulate_text(tmp_path, """name = "speeds"
[chain]
n = 40
k = 1
alpha = 1.5
[output]
sensors = [15, 25]
sensor_dt = 0.005
[solver]
t_end = 60.0
[sweep]
"chain.speed" = [0.1, 0.3, 1.0, 3.0, 10.0]
""")
    result = CliRunner().invoke(main, ["plot", str(out), "--what", "sweep-pulses"])
    assert result.exit_code == 0, result.output
    assert (out / "figures" / "sweep-pulses.png").is_file()
    from chainrun.analysis.pulse import measure_pulses
    from chainrun.plotting.pulses import draw_sweep_pulses
    from chainrun.store import read_index

    runs = [read_run(out / row["file"]) for row in read_index(out / "index.h5")]
    speeds = [run.parameters["overrides"]["chain.speed"] for run in runs]
    pulses = [measure_pulses(run) for run in runs]
    with style(colour=True):
        figure = draw_sweep_pulses(pulse_sweep(runs, pulses, "chain.speed"), "title")
    order = np.argsort(speeds)

    def drawn(gid):
        return next(a for ax in figure.axes for a in ax.get_lines() if a.get_gid() == gid)

    force = drawn("pulses/force/25")
    np.testing.assert_allclose(force.get_xdata(), np.sort(speeds))
    np.testing.assert_array_equal(force.get_ydata(),
                                  [pulses[i].peak_force[1] for i in order])
    assert power_law(force.get_xdata(), force.get_ydata()) == pytest.approx(1.2, abs=1e-4)
    width = drawn("pulses/time/25")
    assert power_law(width.get_xdata(), width.get_ydata()) == pytest.approx(-0.2, abs=1e-3)
    legends = [t.get_text() for ax in figure.axes for t in ax.get_legend().get_texts()]
    assert "fitted through the sensors (slope 0.200)" in legends
    assert "ball 25 (slope 1.200)" in legends
    assert all(ax.get_xscale() == "log" for ax in figure.axes)
    # and the folder's table gives each run's wave speed and last peak force
    table = CliRunner().invoke(main, ["info", str(out)]).stdout
    assert "wave (balls/time)" in table and "peak force, ball 25" in table


def test_a_power_law_is_fitted_through_its_points():
    from chainrun.analysis.pulse_sweep import power_law

    x = np.array([0.5, 2.0, 7.0])
    assert power_law(x, 3.0 * x**0.7) == pytest.approx(0.7, abs=1e-12)
    assert np.isnan(power_law([1.0], [2.0])) and np.isnan(power_law([1.0, 1.0], [2.0, 3.0]))


def test_a_sweeps_runs_drawn_on_several_processes_are_the_bytes_of_one(tmp_path,
                                                                      monkeypatch):
    import importlib

    plot_command = importlib.import_module("chainrun.cli.plot")  # (the module, not the command)

    out = simulate_text(tmp_path, """name = "s"
[chain]
n = 5
k = 1
alpha = 1.5
[output]
times = [0.0, 5.0, 10.0]
[sweep]
"chain.k" = [1, 2, 3]
""")
    drawn = {}
    for workers in (2, 1):
        monkeypatch.setattr(plot_command, "MAX_PLOT_WORKERS", workers)
        monkeypatch.setattr(plot_command.os, "cpu_count", lambda: 2)
        result = CliRunner().invoke(main, ["plot", str(out), "--what", "final,energy",
                                           "-o", str(tmp_path / f"w{workers}")])
        assert result.exit_code == 0, result.output
        lines = result.stdout.splitlines()
        assert [line.split(":")[0] for line in lines[:3]] == [
            str(out / f"k={k}.h5") for k in (1, 2, 3)]  # in the runs' order
        drawn[workers] = {p.name: p.read_bytes() for p in (tmp_path / f"w{workers}").iterdir()}
    assert len(drawn[1]) == 16 and drawn[2] == drawn[1]  # (3 runs x 2 views + 2 of the sweep) x PNG, PDF


def test_an_artefact_name_is_an_artefact_even_beside_a_folder_of_that_name(tmp_path,
                                                                           monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fig05").mkdir()
    result = CliRunner().invoke(main, ["plot", "fig05", "--results", str(tmp_path / "r")])
    assert result.exit_code == 2
    assert "chainrun analyze fig05" in result.stderr  # the artefact's own message


def test_the_force_image_and_displacements_are_the_files(wave):
    path, raw = wave
    run = read_run(path)
    with style():
        forces = draw_view(run, "forces")
        displacements = draw_view(run, "displacements")
    c = raw["x"][:, :-1] - raw["x"][:, 1:]
    expected = np.where(c > 0, np.abs(c) ** 1.5, 0.0)  # Hertz: c_+^(3/2)
    np.testing.assert_allclose(artist(forces, "force").get_array(), expected.T, rtol=1e-14,
                               atol=0)
    lines = [a for a in displacements.axes[0].get_lines()
             if str(a.get_gid()).startswith("displacement/")]
    for a in lines:
        np.testing.assert_array_equal(a.get_ydata(), raw["x"][int(a.get_gid().split("/")[1])])


#: A precompressed line against a wall, struck by one ball.
LOADED = """name = "p"
[chain]
n = 12
k = 1
alpha = 1.5
precompression = 0.2
[walls.right]
[output]
times = {start = 0, stop = 20, step = 0.5}
[solver]
t_end = 20
"""


def test_a_loaded_lines_force_image_is_the_change_from_its_static_load(tmp_path):
    """A precompressed line: the contact forces at t = 0 are the static load, and the
    image is each force's change from it, on a scale centred at no change."""
    out = simulate_text(tmp_path, LOADED)
    run = read_run(out / "run.h5")
    with style():
        figure = draw_view(run, "forces")
    # the contacts, and the right wall's (unit stiffness, pressed by the last ball)
    c = np.hstack([run.positions[:, :-1] - run.positions[:, 1:], run.positions[:, -1:]])
    force = np.where(c > 0, np.abs(c) ** 1.5, 0.0)  # Hertz: c_+^(3/2)
    np.testing.assert_allclose(force[0, 1:], 0.2, rtol=1e-12)  # (the striker arrives)
    image = artist(figure, "force")
    np.testing.assert_allclose(image.get_array(), (force - force[0]).T, rtol=0, atol=1e-12)
    low, high = image.get_clim()
    assert low == -high and high == pytest.approx(np.abs(force - force[0]).max())
    assert "since t = 0" in figure.axes[-1].get_ylabel()
    # its displacements likewise: the change since t = 0, not the static compressions'
    # ramp along the line
    with style():
        figure = draw_view(run, "displacements")
    lines = [a for a in figure.axes[0].get_lines() if str(a.get_gid()).startswith("displ")]
    assert lines and figure.axes[0].get_ylabel().startswith("displacement since t = 0")
    for a in lines:
        i = int(a.get_gid().split("/")[1])
        np.testing.assert_array_equal(a.get_ydata(), run.positions[i] - run.positions[0])


def test_the_sensor_view_is_the_mean_force_stored(tmp_path):
    out = simulate_text(tmp_path, """name = "s"
[chain]
n = 12
k = 1
alpha = 1.5
[output]
sensors = [4, 9]
sensor_dt = 0.05
sensor_end = 30.0
""")
    with h5py.File(out / "run.h5") as f:
        mean = f["sensors/mean_force"][()]
        t = f["sensors/time"][()]
    with style():
        figure = draw_view(read_run(out / "run.h5"), "sensors")
    for s, ball in enumerate((4, 9)):
        line = artist(figure, f"sensor/{ball}")
        np.testing.assert_array_equal(line.get_xdata(), t)
        np.testing.assert_array_equal(line.get_ydata(), mean[:, s])
    written = render_run(out / "run.h5", out=tmp_path / "fig")
    assert sorted(p.name for p in written) == [
        "run-final.pdf", "run-final.png", "run-sensors.pdf", "run-sensors.png"]


def test_strided_forces_read_only_their_balls_and_agree(wave):
    path, _ = wave
    run = read_run(path)
    np.testing.assert_array_equal(run.contact_forces(4), run.contact_forces()[:, ::4])


DAMPED_SI = """name = "beads"
units = "si"
[chain]
n = 12
k = 1
speed = 0.3
diameter = 0.008
material = "stainless_steel"
restitution = 0.8
damping_law = "tsuji"
[walls.right]
material = "steel"
[output]
times = {start = 0.0, stop = 2.0e-4, step = 4.0e-6}
sensors = [4, 8]
sensor_dt = 1.0e-7
[solver]
t_end = 2.0e-4
"""

#: the factor of each unit a label may show, from its SI base (worked by hand)
FACTORS = {"s": 1.0, "ms": 1e3, "µs": 1e6, "ns": 1e9, "m/s": 1.0, "mm/s": 1e3,
           "µm/s": 1e6, "m": 1.0, "mm": 1e3, "µm": 1e6, "nm": 1e9, "N": 1.0, "mN": 1e3,
           "kN": 1e-3, "J": 1.0, "mJ": 1e3, "µJ": 1e6, "nJ": 1e9}


@pytest.fixture(scope="module")
def beads(tmp_path_factory):
    return read_run(simulate_text(tmp_path_factory.mktemp("si"), DAMPED_SI) / "run.h5")


def unit_of(label: str) -> float:
    """The factor from SI of the unit in a label ``"name (unit)"``."""
    unit = label.rsplit("(", 1)[1].rstrip(")")
    return FACTORS[unit]


def texts(figure) -> list[str]:
    out = [figure.get_suptitle()] if figure.get_suptitle() else []
    for axes in figure.axes:
        out += [axes.get_xlabel(), axes.get_ylabel(), axes.get_title()]
        legend = axes.get_legend()
        if legend is not None:
            out += [t.get_text() for t in legend.get_texts()]
    return out


def test_an_si_run_is_drawn_in_si_with_readable_prefixes(beads):
    with style(colour=True):
        figures = {view: draw_view(beads, view) for view in VIEWS}
    for view, figure in figures.items():
        assert not any("paper units" in text for text in texts(figure)), view
    # each axis's data are the file's times the factor its label's unit says
    spacetime = figures["spacetime"]
    image = artist(spacetime, "velocity")
    left, right, _, _ = image.get_extent()
    factor = unit_of(spacetime.axes[0].get_xlabel())
    assert factor == 1e6  # t_end = 200 µs
    assert (left, right) == pytest.approx((0.0, beads.times[-1] * factor))
    speed = unit_of(spacetime.axes[1].get_ylabel())
    np.testing.assert_allclose(image.get_array(), np.asarray(beads.velocities).T * speed)
    sensors = figures["sensors"]
    for s, ball in enumerate(beads.sensor_balls):
        line = artist(sensors, f"sensor/{ball}")
        np.testing.assert_allclose(line.get_xdata(),
                                   beads.sensor_time * unit_of(sensors.axes[0].get_xlabel()))
        np.testing.assert_allclose(line.get_ydata(), beads.sensor_force[:, s].mean(axis=1)
                                   * unit_of(sensors.axes[0].get_ylabel()))
    assert "stainless steel spheres of 8 mm" in figures["final"].axes[0].get_title()
    assert "300 mm/s" in figures["final"].axes[0].get_title()


def test_an_si_sweeps_runs_are_named_by_their_values_with_units(tmp_path):
    """The run speed=0.05 of a sweep in SI is "speed 50 mm/s" in its figures' titles
    and in the sweep's panels; a sweep in the paper's units keeps its run ids."""
    from chainrun.plotting.views import draw_sweep_runs

    out = simulate_text(tmp_path, 'name = "s"\nunits = "si"\n[chain]\nn = 5\nk = 1\n'
                                  'diameter = 0.008\nmaterial = "steel"\n'
                                  '[sweep]\n"chain.speed" = [0.05, 1.0]\n')
    runs = [read_run(out / name) for name in ("speed=0.05.h5", "speed=1.0.h5")]
    with style():
        final = draw_view(runs[0], "final")
        panels = draw_sweep_runs(runs)
    assert final.axes[0].get_title().startswith("s (speed 50 mm/s)\n")
    assert [ax.get_title() for ax in panels.axes] == ["speed 50 mm/s", "speed 1 m/s"]
    # speeds twenty times apart: each run over its own impact speed, or the slower
    # run's panel would be a flat line on the faster one's scale
    assert panels.get_supylabel() == "final velocity / impact speed"
    for ax, run, speed in zip(panels.axes, runs, (0.05, 1.0)):
        (line,) = [a for a in ax.get_lines() if str(a.get_gid()).startswith("final_velocity/")]
        np.testing.assert_array_equal(line.get_ydata(), run.final_velocity / speed)


def test_every_view_of_a_run_writes_its_times_and_velocities_in_one_prefix(tmp_path):
    """Struck at 1 m/s, the last ball leaves at 0.985 m/s, and the sensors stop at
    0.8 ms while the snapshots go on to 1.6 ms: one run's views all read m/s and ms,
    the prefixes of its impact speed and its last time."""
    out = simulate_text(tmp_path, 'name = "p"\nunits = "si"\n[chain]\nn = 20\nk = 1\n'
                                  'speed = 1.0\ndiameter = 0.008\nmaterial = "steel"\n'
                                  '[output]\ntimes = {start = 0, stop = 1.6e-3, step = 1e-4}\n'
                                  'sensors = [5]\nsensor_dt = 1e-6\nsensor_end = 8e-4\n')
    run = read_run(out / "run.h5")
    assert 0.9 < run.final_velocity.max() < 1.0
    with style():
        labels = {view: [label for ax in draw_view(run, view).axes
                         for label in (ax.get_xlabel(), ax.get_ylabel()) if label]
                  for view in ("spacetime", "profiles", "final", "sensors")}
    units = {re.search(r"\(([^()]*)\)$", label).group(1) for these in labels.values()
             for label in these if "time" in label or "velocity" in label}
    assert units == {"ms", "m/s"}, labels


def test_the_force_view_has_a_walls_contact_the_force_its_sensor_measured(tmp_path):
    """A right wall's contact is the force view's row N, the force of its law at the
    stored positions: the force the solver measured on the last ball's wall side at
    the same times (a sensor, sampled on the snapshots' grid), which peaks well above
    the solitary wave's as the wave reflects."""
    from chainrun.solver.physics import wall_forces

    out = simulate_text(tmp_path, 'name = "w"\nunits = "si"\n[chain]\nn = 20\nk = 1\n'
                                  'speed = 0.1\ndiameter = 0.008\nmaterial = "steel"\n'
                                  '[walls.right]\n[output]\n'
                                  'times = {start = 0, stop = 8e-4, step = 2e-6}\n'
                                  'sensors = [20]\nsensor_dt = 2e-6\nsensor_end = 8e-4\n'
                                  '[solver]\nt_end = 8e-4\n')
    run = read_run(out / "run.h5")
    with style():
        figure = draw_view(run, "forces")
    image = artist(figure, "force")
    rows = np.asarray(image.get_array())
    assert rows.shape[0] == run.n  # contacts 1..N-1 and the wall's
    _, _, bottom, top = image.get_extent()
    assert (bottom, top) == (0.5, run.n + 0.5)
    wall = wall_forces(np.asarray(run.positions), run.line)[:, 1]
    np.testing.assert_array_equal(rows[-1], wall)
    sensed = run.sensor_force[:, 0, 1]  # ball 20, its side away from ball 1: the wall
    common = min(sensed.size, wall.size)
    np.testing.assert_allclose(run.sensor_time[:common], run.times[:common], rtol=1e-12)
    np.testing.assert_allclose(wall[:common], sensed[:common], rtol=1e-9,
                               atol=1e-9 * sensed.max())
    assert wall.max() > 1.5 * rows[5].max()  # (the wave reflects off it)
    assert "20 the wall" in figure.axes[0].get_ylabel()


def test_a_title_gives_each_wall_its_own_restitution(beads):
    # the balls' restitution comes before the walls, so that it is not read as a wall's
    import copy
    from types import SimpleNamespace

    from chainrun.plotting.views import describe

    assert describe(beads).endswith("restitution 0.8 (Tsuji), right wall")
    parameters = copy.deepcopy(beads.parameters)
    parameters["config_resolved"]["walls"]["right"].update(restitution=0.5,
                                                          damping_law="tsuji")
    run = SimpleNamespace(line=beads.line, units=beads.units, parameters=parameters)
    assert describe(run).endswith(
        "restitution 0.8 (Tsuji), right wall (restitution 0.5, Tsuji)")
    # swept, a wall's restitution is left out, and the balls' stays
    assert describe(run, ["walls.right.restitution"]).endswith(
        "restitution 0.8 (Tsuji), right wall")
    assert describe(run, ["chain.restitution"]).endswith(
        "1 striker at 300 mm/s, Hertz contacts, right wall (restitution 0.5, Tsuji)")


def test_a_wrapped_legend_label_keeps_equations_and_units_whole():
    from chainrun.plotting.views import _LEGEND_WRAP, _wrap

    lines = _wrap("in contacts and walls, since t = 0").splitlines()
    assert lines == ["in contacts and walls, since", "t = 0"]
    lines = _wrap("the drive's sine at 2 kHz, amplitude 10 µm, from rest").splitlines()
    assert all(len(line) <= _LEGEND_WRAP for line in lines)
    assert not any(line.endswith(("2", "10")) for line in lines)


def test_curves_differ_in_colour_and_style_and_ball_axes_are_whole_numbers(beads):
    with style(colour=True):
        profiles = draw_view(beads, "profiles")
        sensors = draw_view(beads, "sensors")
    for figure in (profiles, sensors):
        lines = [a for a in figure.axes[0].get_lines() if a.get_gid()]
        assert len(lines) >= 2
        assert len({a.get_color() for a in lines}) == len(lines)
        # a dash pattern each (get_linestyle says "--" for every dashed one)
        assert len({str(a._unscaled_dash_pattern) for a in lines}) == len(lines)
    ticks = profiles.axes[0].get_xticks()
    assert np.all(ticks == np.round(ticks))


def test_the_energy_sum_of_a_damped_run_is_flat(beads):
    with style(colour=True):
        figure = draw_view(beads, "energy")
    factor = unit_of(figure.axes[0].get_ylabel())
    obs = beads.observables
    np.testing.assert_allclose(artist(figure, "dissipated_energy").get_ydata(),
                               obs["dissipated_energy"] * factor)
    total = artist(figure, "total_energy").get_ydata() / factor
    initial = 0.5 * float(beads.line.mass @ beads.line.velocity ** 2)
    assert obs["dissipated_energy"][-1] > 0.2 * initial  # the damping took a real share
    np.testing.assert_allclose(total, initial, rtol=1e-9)


def test_no_two_of_ninety_curves_look_alike():
    """Eleven sensors or profiles must not repeat the first curve's colour and style."""
    from matplotlib.figure import Figure

    with style(colour=True):
        axes = Figure().add_subplot()
        lines = [axes.plot([0, 1], [i, i])[0] for i in range(90)]
        looks = {(a.get_color(), str(a._unscaled_dash_pattern)) for a in lines}
    assert len(looks) == 90


def test_a_log_scale_keeps_every_point_inside_and_no_empty_half(wave):
    path, raw = wave
    with style():
        axes = draw_view(read_run(path), "final", log=True).axes[0]
    bottom, top = axes.get_ylim()
    v = raw["final"]
    assert top > v.max() and bottom < v.min()
    forward = v.copy()
    forward[forward < 0] = 0.0
    from chainrun.plotting.views import _symlog
    from matplotlib.figure import Figure

    axes = Figure().add_subplot()
    axes.plot(np.arange(v.size), forward)
    _symlog(axes, forward)
    bottom, top = axes.get_ylim()
    assert bottom == 0.0 and top > forward.max()
    # every ball rebounding: no empty positive half, and the linear part about 0 ends
    # on a decade (0.01 below 0.0763), not between the labels of 0 and its neighbour
    back = np.array([-88.0, -7.6, -0.31, -0.0763])
    axes = Figure().add_subplot()
    axes.plot(np.arange(back.size), back)
    _symlog(axes, back)
    bottom, top = axes.get_ylim()
    assert top == 0.0 and bottom < back.min()
    assert axes.yaxis.get_transform().linthresh == 0.01


def test_a_long_legend_stands_outside_the_axes(beads, tmp_path):
    """Six profiles, or the energy view's long labels, would hide curves inside: many
    entries stand beside the axes, a few long ones below them, where they take none of
    the axes' width."""
    loaded = read_run(simulate_text(tmp_path, LOADED) / "run.h5")
    with style(colour=True):
        figure = draw_view(beads, "profiles")
        energy = draw_view(loaded, "energy")  # "in contacts and walls (above the static..."
    legend = figure.axes[0].get_legend()
    figure.canvas.draw()  # (a legend's place is known once drawn)
    box = legend.get_window_extent()
    assert box.x0 >= figure.axes[0].get_window_extent().x1
    energy.canvas.draw()
    axes = energy.axes[0].get_window_extent()
    below = energy.axes[0].get_legend().get_window_extent()
    assert below.y1 <= axes.y0 and axes.width >= 0.75 * energy.bbox.width


def test_a_driven_precompressed_line_draws_what_it_took_up(tmp_path):
    # A line under a static load of 1 shaken by 1e-6 (about (A omega)^2 = 1e-13 taken
    # up): the load's work F0 w(t) (amplitude 1e-6) is off the drives' work and the
    # contacts' energy, which stay at the scale of what the shaking puts in, never
    # below 0 beyond the balance's rounding (about 2e-16).
    from helpers import driven_sweep

    text = driven_sweep("shaken", 6, [0.05], ramp=20.0, t_end=95.0).replace(
        "[solver]", '[output.times]\nstart = 0.0\nstop = 95.0\nstep = 0.5\n[solver]')
    out = simulate_text(tmp_path, text)
    run = read_run(next(p for p in out.glob("*.h5") if p.name != "index.h5"))
    with style(colour=True):
        figure = draw_view(run, "energy")
    assert figure.axes[0].get_ylabel() == "energy (paper units)"
    work = artist(figure, "drive_work").get_ydata()
    stored = artist(figure, "potential_energy").get_ydata()
    assert 1e-14 < work.max() < 1e-11
    assert work.min() > -1e-15 and stored.min() > -1e-15
    assert "static load" in artist(figure, "drive_work").get_label()


#: a line shaken above its band (the top at f = 2 sqrt(1.5) / 2 pi = 0.39): the first
#: ball's force oscillates from end to end of the axes, the last's barely
SHAKEN = """name = "shaken"
[chain]
n = 10
k = 0
alpha = 1.5
precompression = 1.0
[walls.left]
motion = {amplitude = 0.001, frequency = 0.6}
[walls.right]
[output]
sensors = [1, 10]
sensor_dt = 0.05
[solver]
t_end = 60.0
"""


def test_a_legend_hides_no_curve(beads, tmp_path):
    """A driven line's force sensors oscillate from end to end of the axes, where no
    place inside is free of them: the legend stands below the axes. A struck line's
    pulses leave it a place inside."""
    shaken = read_run(simulate_text(tmp_path, SHAKEN) / "run.h5")
    with style(colour=True):
        figures = {"shaken": draw_view(shaken, "sensors"), "beads": draw_view(beads, "sensors")}
    for name, figure in figures.items():
        figure.draw_without_rendering()
        axes = figure.axes[0]
        box = axes.get_legend().get_window_extent()
        for line in axes.get_lines():
            path = line.get_transform().transform_path(line.get_path())
            assert not path.intersects_bbox(box, filled=False), (name, line.get_label())
    assert figures["shaken"].axes[0].get_legend().get_window_extent().y1 <= \
        figures["shaken"].axes[0].get_window_extent().y0
    inside = figures["beads"].axes[0].get_window_extent()
    box = figures["beads"].axes[0].get_legend().get_window_extent()
    assert inside.x0 <= box.x0 and box.x1 <= inside.x1 and inside.y0 <= box.y0 <= inside.y1


def test_five_long_legend_entries_go_below_the_axes(tmp_path):
    # a damped driven line's energy view: kinetic, contacts, dissipated, the drives' work
    # and the sum, two of them long; beside the axes they took half the figure's width
    from helpers import driven_sweep

    text = driven_sweep("damped", 6, [0.05], ramp=20.0, t_end=60.0).replace(
        'alpha = 1.5\n', 'alpha = 1.5\ndamping = 0.05\n', 1).replace(
        "[solver]", '[output.times]\nstart = 0.0\nstop = 60.0\nstep = 0.5\n[solver]')
    out = simulate_text(tmp_path, text)
    run = read_run(next(p for p in out.glob("*.h5") if p.name != "index.h5"))
    with style(colour=True):
        figure = draw_view(run, "energy")
    assert len(figure.axes[0].get_legend().get_texts()) == 5
    figure.canvas.draw()
    axes = figure.axes[0].get_window_extent()
    legend = figure.axes[0].get_legend().get_window_extent()
    assert legend.y1 <= axes.y0 and axes.width >= 0.75 * figure.bbox.width


def test_a_bending_power_law_says_its_slopes_from_run_to_run():
    from chainrun.analysis.pulse_sweep import _curve, local_slopes
    from chainrun.plotting.pulses import _label

    x = np.array([0.1, 1.0, 10.0])
    y = np.array([1.0, 10.0**0.18, 10.0**0.18 * 10.0**0.2])  # slopes 0.18, then 0.2
    np.testing.assert_allclose(local_slopes(x, y), [0.18, 0.2], rtol=1e-12)
    assert _label(_curve("wave", x, y, True), True) == "wave (slope 0.190, 0.180 → 0.200)"
    assert _label(_curve("wave", x, x**0.2, True), True) == "wave (slope 0.200)"
