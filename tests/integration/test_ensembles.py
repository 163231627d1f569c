"""Ensembles over random seeds: a generator's seed swept, or a replica count; the runs
read as one Dataset (``chainrun.open_sweep``), summarised (``chainrun info``) and drawn
(``chainrun plot``) as an ensemble."""

from __future__ import annotations

import re

import numpy as np
import pytest
from click.testing import CliRunner
from helpers import simulate_text

import chainrun
from chainrun.cli import main
from chainrun.config import parse_experiment
from chainrun.errors import ConfigError
from chainrun.plotting import style
from chainrun.analysis.ensemble import ensemble, is_ensemble
from chainrun.plotting.views import draw_ensemble
from chainrun.store import read_index, read_run

DISORDER = """name = "disorder"
[chain]
n = 24
k = 1
alpha = 1.5
mass = {random = "uniform", low = 1.0, high = 3.0, seed = 11}
stiffness = {random = "uniform", low = 1.0, high = 2.0, seed = 40}
[output]
times = {start = 0, stop = 60, step = 3}
[sweep]
"""


def assert_mean_and_sd(line: str, mean: float, sd: float) -> None:
    """``line`` gives ``mean +- sd``: the deviation to two significant digits, the mean
    to the same decimal place, each within half a unit of that place."""
    shown_mean, shown_sd = re.search(r"(-?[\d.]+) \+- ([\d.]+)", line).groups()
    decimals = len(shown_sd.partition(".")[2])
    assert len(shown_mean.partition(".")[2]) == decimals, line
    digits = shown_sd.replace(".", "").lstrip("0")
    assert len(digits if "." in shown_sd else digits.rstrip("0")) <= 2, line
    half = 0.5 * 10.0 ** -decimals * (1 + 1e-9)
    assert abs(float(shown_mean) - mean) <= half, line
    assert abs(float(shown_sd) - sd) <= half, line


@pytest.fixture(scope="module")
def seeds(tmp_path_factory):
    """Eight disordered lines, their masses' seed swept."""
    text = DISORDER + '"chain.mass.seed" = [1, 2, 3, 4, 5, 6, 7, 8]\n'
    return simulate_text(tmp_path_factory.mktemp("seeds"), text, "disorder")


def test_a_swept_seed_draws_each_runs_values_with_its_own_seed(seeds):
    for seed in range(1, 9):
        run = read_run(seeds / f"mass_seed={seed}.h5")
        want = np.random.default_rng(seed).uniform(1.0, 3.0, 24)  # the generator's rule
        np.testing.assert_array_equal(run.line.mass, want)
        np.testing.assert_array_equal(  # the stiffnesses keep the file's seed
            run.line.stiffness, np.random.default_rng(40).uniform(1.0, 2.0, 23))
        assert run.parameters["overrides"] == {"chain.mass.seed": seed}


def test_open_sweep_is_the_runs_side_by_side(seeds):
    ds = chainrun.open_sweep(seeds)
    files = [read_run(seeds / str(row["file"])) for row in read_index(seeds / "index.h5")]
    assert ds.sizes["run"] == 8 and ds.final_velocity.dims == ("run", "ball")
    assert list(ds["chain.mass.seed"].values) == list(range(1, 9))
    assert list(ds.run.values) == [f"mass_seed={s}" for s in range(1, 9)]
    finals = np.array([f.final_velocity for f in files])
    np.testing.assert_array_equal(ds.final_velocity.values, finals)
    np.testing.assert_allclose(ds.final_velocity.mean("run").values, finals.mean(axis=0),
                               rtol=1e-15, atol=1e-17)
    # the event logs, of different lengths, stay readable run by run
    counts = [f.event_time.size for f in files]
    assert len(set(counts)) > 1 and list(ds.event_count.values) == counts
    for r, f in enumerate(files):
        np.testing.assert_array_equal(ds.event_time.isel(run=r)[:counts[r]], f.event_time)
        np.testing.assert_array_equal(ds.event_contact.isel(run=r)[:counts[r]],
                                      f.event_contact)
        assert np.all(ds.event_contact.isel(run=r)[counts[r]:] == -1)
    assert list(ds.outcome.values) == ["terminal"] * 8
    assert ds.attrs["experiment"] == "disorder" and "outcome" not in ds.attrs


def test_info_and_plot_treat_the_folder_as_an_ensemble(seeds, tmp_path):
    files = [read_run(seeds / str(row["file"])) for row in read_index(seeds / "index.h5")]
    out = CliRunner().invoke(main, ["info", str(seeds)]).stdout
    rebound = next(line for line in out.splitlines() if "rebound (balls)" in line)
    # backward faster than 1% of the impact speed
    counts = [int(np.sum(f.final_velocity < -0.01 * np.abs(f.line.velocity).max()))
              for f in files]
    assert_mean_and_sd(rebound, np.mean(counts), np.std(counts, ddof=1))
    assert is_ensemble(files)
    with style(colour=True):
        figure = draw_ensemble(ensemble(files), files[0])
    finals = np.array([f.final_velocity for f in files])
    (mean_line,) = [a for a in figure.axes[0].get_lines() if a.get_gid() == "final_velocity/mean"]
    np.testing.assert_allclose(mean_line.get_ydata(), finals.mean(axis=0), rtol=1e-12)
    assert len(figure.axes) == 1  # an elastic line keeps its energy: nothing to draw
    result = CliRunner().invoke(main, ["plot", str(seeds), "--what", "final", "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert (tmp_path / "ensemble.png").is_file() and not (tmp_path / "sweep-final.png").exists()


def test_an_ensemble_stopped_at_t_end_says_its_velocities_are_not_final(tmp_path):
    """Three replicas stopped at t_end = 30, before their terminal state: the info's
    numbers and the figure's axis are the balls' at t = 30, the counts by velocity."""
    text = (DISORDER.replace("stop = 60", "stop = 30")
            .replace("[sweep]\n", "[solver]\nt_end = 30\n[sweep]\n") + "replicas = 3\n")
    out = simulate_text(tmp_path, text, "stopped")
    files = [read_run(out / str(row["file"])) for row in read_index(out / "index.h5")]
    assert not any(f.terminal for f in files)
    text = CliRunner().invoke(main, ["info", str(out)]).stdout
    stats = text.split("over the 3 runs")[1]
    assert "final" not in stats and "rebound (balls)" not in stats
    assert "ejected" not in stats and "left behind" not in stats
    rebounding = next(line for line in stats.splitlines() if "rebounding at t = 30 (balls)" in line)
    counts = [int(np.sum(f.final_velocity < -0.01 * np.abs(f.line.velocity).max()))
              for f in files]
    assert_mean_and_sd(rebounding, np.mean(counts), np.std(counts, ddof=1))
    assert "largest forward velocity at t = 30 " in stats
    kinetic = next(line for line in stats.splitlines() if "energy kinetic at t = 30 (%)" in line)
    shares = [100 * 0.5 * np.sum(f.line.mass * f.final_velocity**2) / (0.5 * f.line.mass[0])
              for f in files]   # the kinetic energy at t = 30, of one striker's m_1 / 2
    assert_mean_and_sd(kinetic, np.mean(shares), np.std(shares, ddof=1))
    with style(colour=True):
        figure = draw_ensemble(ensemble(files), files[0])
    assert figure.axes[0].get_ylabel() == "velocity at t = 30 (paper units)"


def test_an_ensemble_at_its_terminal_state_keeps_final(seeds):
    files = [read_run(seeds / str(row["file"])) for row in read_index(seeds / "index.h5")]
    assert all(f.terminal for f in files)
    with style(colour=True):
        figure = draw_ensemble(ensemble(files), files[0])
    assert figure.axes[0].get_ylabel() == "final velocity (paper units)"
    text = CliRunner().invoke(main, ["info", str(seeds)]).stdout
    assert "rebound (balls)" in text and "terminal state" not in text


def test_replicas_move_every_random_seed_on():
    specs = parse_experiment(DISORDER + "replicas = 3\n", "toml").runs()
    assert [s.run_id for s in specs] == ["replica=0", "replica=1", "replica=2"]
    for r, spec in enumerate(specs):
        assert spec.overrides == {"replica": r}
        np.testing.assert_array_equal(
            spec.line.mass, np.random.default_rng(11 + r).uniform(1.0, 3.0, 24))
        np.testing.assert_array_equal(
            spec.line.stiffness, np.random.default_rng(40 + r).uniform(1.0, 2.0, 23))
    assert len({s.config_hash for s in specs}) == 3


@pytest.mark.parametrize(("sweep", "message"), [
    ("replicas = 0", "sweep.replicas: expected a number of runs from 1 to 10000, got 0"),
    ('replicas = 2\n"chain.mass.seed" = [1, 2]',
     "sweep.replicas: give replicas or a sweep of seeds (chain.mass.seed), not both"),
    ('"chain.alpha.seed" = [1, 2]',
     "sweep.chain.alpha.seed: chain.alpha is not a generator table"),
    ('"chain.mass.colour" = [1, 2]', "sweep: unknown key 'chain.mass.colour'"),
])
def test_bad_ensembles_are_named(sweep, message):
    with pytest.raises(ConfigError) as exc:
        parse_experiment(DISORDER + sweep + "\n", "toml")
    assert message in str(exc.value)


def test_a_line_without_random_values_has_no_replicas():
    text = 'name = "x"\n[chain]\nn = 4\nk = 1\nalpha = 1.5\n[sweep]\nreplicas = 3\n'
    with pytest.raises(ConfigError, match="sweep.replicas: the chain draws no random values"):
        parse_experiment(text, "toml")


def test_a_damped_ensemble_draws_the_energy_it_keeps(tmp_path):
    """Three replicas of a damped disordered line: the energy left in the line, as a
    share of each run's impact energy m_1 v_1^2 / 2 (one striker at speed 1)."""
    text = DISORDER.replace("n = 24", "n = 10") + "replicas = 3\n"
    text = text.replace("[output]", 'restitution = 0.8\ndamping_law = "tsuji"\n[output]')
    out = simulate_text(tmp_path, text, "damped")
    files = [read_run(out / str(row["file"])) for row in read_index(out / "index.h5")]
    stats = ensemble(files)
    with style(colour=True):
        figure = draw_ensemble(stats, files[0])
    left = np.array([(f.observables["kinetic_energy"] + f.observables["potential_energy"])
                     / (0.5 * f.line.mass[0]) for f in files])
    (energy,) = [a for a in figure.axes[1].get_lines() if a.get_gid() == "energy/mean"]
    np.testing.assert_allclose(energy.get_ydata(), 100 * left.mean(axis=0), rtol=1e-12)
    assert energy.get_ydata()[0] == pytest.approx(100.0) and energy.get_ydata()[-1] < 90


@pytest.fixture(scope="module")
def beads(tmp_path_factory):
    """An ensemble of SI lines with force sensors: the beads' diameters drawn by seed,
    each line its own time scale, the runs ending at different times."""
    return simulate_text(tmp_path_factory.mktemp("beads"), """name = "beads"
units = "si"
[chain]
n = 16
k = 1
speed = 0.5
diameter = {random = "uniform", low = 0.015, high = 0.025, seed = 1}
material = "steel"
restitution = 0.95
damping_law = "tsuji"
[output]
times = {start = 0, stop = 1e-3, step = 1e-5}
sensors = [5, 10, 15]
sensor_dt = 5e-7
[sweep]
"chain.diameter.seed" = [1, 2, 3]
""")


def test_pulses_of_an_ensemble_are_each_runs_along_run(beads):
    """The ensemble read as one Dataset: its runs share one sample axis, and ``pulses``
    measures each run as from its own file, along ``run``, whether given the sweep,
    one run of it, or the folder."""
    ds = chainrun.open_sweep(beads)
    assert ds.sizes["sample"] == 2001 and not ds.sensor_force.isnull().any()
    # every number along run says what it is, and its unit where it has one
    for name in ("end_time", "diagnostics_wall_time", "diagnostics_steps", "outcome",
                 "chain.diameter.seed"):
        assert ds[name].attrs["long_name"], name
    assert ds.end_time.attrs["units"] == ds.diagnostics_wall_time.attrs["units"] == "s"
    assert "units" not in ds["chain.diameter.seed"].attrs  # a seed is a number
    measured = chainrun.pulses(ds)
    assert measured.peak_force.dims == ("run", "sensor")
    assert list(measured["chain.diameter.seed"].values) == [1, 2, 3]
    for r, seed in enumerate([1, 2, 3]):
        alone = chainrun.pulses(beads / f"diameter_seed={seed}.h5")
        for name in ("peak_force", "arrival_time", "width", "wave_speed_si"):
            np.testing.assert_array_equal(measured[name].isel(run=r).values,
                                          alone[name].values)
        np.testing.assert_array_equal(chainrun.pulses(ds.isel(run=r)).wave_speed_si,
                                      alone.wave_speed_si)
    assert np.all(np.isfinite(measured.wave_speed_si.values))
    assert measured.wave_speed_si.attrs["units"] == "m/s"
    np.testing.assert_array_equal(chainrun.pulses(beads).peak_force, measured.peak_force)


def test_info_of_an_ensemble_averages_its_pulses(beads):
    out = CliRunner().invoke(main, ["info", str(beads)]).stdout
    measured = chainrun.pulses(beads)
    rows = {"wave speed": (measured.wave_speed_si.values, 1.0),
            "peak force at ball 10": (measured.peak_force.sel(sensor=10).values, 1.0),
            "width (FWHM) at ball 10": (measured.width.sel(sensor=10).values, 1e6),
            "arrival at ball 15": (measured.arrival_time.sel(sensor=15).values, 1e6)}
    for label, (values, factor) in rows.items():
        line = next(line for line in out.splitlines() if line.strip().startswith(label))
        assert_mean_and_sd(line, factor * values.mean(), factor * values.std(ddof=1))
    assert "m/s" in next(line for line in out.splitlines() if "wave speed" in line)
    assert "µs" in next(line for line in out.splitlines() if "arrival at ball 15" in line)
    assert "µs" in next(line for line in out.splitlines() if "width (FWHM) at ball 5" in line)
