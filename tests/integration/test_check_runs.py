"""``chainrun simulate --check``: the spreads stored against two runs the test makes
itself, the counts the summary line and ``chainrun info`` give against the file's
spreads, resuming, and the check runs' own files."""

from __future__ import annotations

import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

import chainrun
from chainrun.cli import main

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

#: A disordered line: masses and stiffnesses uniform in [1, 10). Its balls collide in a
#: cascade whose outcome rounding steers.
DISORDERED = """name = "disordered"
[chain]
n = 60
k = 1
alpha = 1.5
mass = {random = "uniform", low = 1.0, high = 10.0, seed = 1}
stiffness = {random = "uniform", low = 1.0, high = 10.0, seed = 2}
[output]
times = [0.0, 10.0]
"""


def simulate(*args):
    return CliRunner().invoke(main, ["simulate", *map(str, args)])


def spreads(path):
    with h5py.File(path) as f:
        return (f["results/final_velocity_spread"][()],
                f["results/separation_velocity_spread"][()],
                float(f["model/scales"].attrs["velocity"]), dict(f["results"].attrs))


def holding(final, separation, speed):
    """Balls whose two spreads are both within 1e-9 of the impact speed."""
    return int(np.sum((final <= 1e-9 * speed) & (separation <= 1e-9 * speed)))


def own_spread(a, b):
    """|a - b|, 0 where both are NaN (a ball that never separated), inf where one is."""
    out = np.abs(a - b)
    out[np.isnan(a) & np.isnan(b)] = 0.0
    out[np.isnan(a) != np.isnan(b)] = np.inf
    return out


@pytest.fixture(scope="module")
def disordered(tmp_path_factory):
    folder = tmp_path_factory.mktemp("check")
    config = folder / "disordered.toml"
    config.write_text(DISORDERED)
    result = simulate(config, "-o", folder / "out", "--check")
    assert result.exit_code == 0, result.output
    return folder, result


#: Eight steel beads of one inch, e = 0.95 (Tsuji), against a steel wall: a clean line,
#: whose errors follow the tolerance.
CRADLE = {"name": "cradle", "units": "si",
          "chain": {"n": 8, "k": 1, "speed": 0.5, "diameter": 0.0254, "material": "steel",
                    "restitution": 0.95, "damping_law": "tsuji"},
          "walls": {"right": {"material": "steel"}}}


@pytest.mark.parametrize("rtol", [1e-6, 1e-9])
def test_a_spread_estimates_the_runs_own_error(rtol):
    # The spread |v(rtol) - v(rtol/10)| estimates the run's error, and is not a bound:
    # the check run is off by about a tenth as much, so where the error follows the
    # tolerance the run's error is about 1/0.9 of its spread (docs/guide.md, "Which
    # digits hold"). The error is measured against a run at 1e-15, the smallest rtol.
    exact = chainrun.simulate({**CRADLE, "solver": {"rtol": 1e-15}})
    run = chainrun.simulate({**CRADLE, "solver": {"rtol": rtol, "check": True}})
    error = np.abs(run.final_velocity.values - exact.final_velocity.values)
    spread = run.final_velocity_spread.values
    assert 0.8 * spread.max() <= error.max() <= 2.0 * spread.max()
    assert np.all(error <= 2.0 * spread)


@pytest.mark.slow
def test_a_rounding_steered_line_has_spreads_well_above_a_billionth(disordered):
    folder, result = disordered
    final, separation, speed, attrs = spreads(folder / "out" / "run.h5")
    # two runs of the test's own, at rtol and at a tenth of it, without the check
    text = (folder / "disordered.toml").read_text()
    base = chainrun.simulate(folder / "disordered.toml")
    (folder / "tenth.toml").write_text(text + "[solver]\nrtol = 1e-13\n")
    tenth = chainrun.simulate(folder / "tenth.toml")
    assert attrs["check_rtol"] == tenth.attrs["rtol"] and attrs["check_outcome"] == "terminal"
    assert np.array_equal(final, np.abs(base.final_velocity.values - tenth.final_velocity.values))
    assert np.array_equal(separation, own_spread(base.separation_velocity.values,
                                                 tenth.separation_velocity.values))
    assert np.sum(final > 1e-8 * speed) >= 1     # far above the 1e-9 a clean line holds to
    assert holding(final, separation, speed) < 60
    line = result.stdout.splitlines()[0]
    found = re.search(r"check \(rtol 1e-13\): (\d+) of 60 balls hold to 1e-9 of the impact "
                      r"speed, largest spread (\S+) of it \(ball (\d+)\)", line)
    assert found, line
    assert int(found[1]) == holding(final, separation, speed)
    worst = np.fmax(final, separation)
    assert int(found[3]) == np.argmax(worst) + 1
    assert float(found[2]) == pytest.approx(worst.max() / speed, rel=0.06)


@pytest.mark.slow
def test_info_counts_the_balls_that_hold_from_the_file(disordered):
    folder, _ = disordered
    path = folder / "out" / "run.h5"
    final, separation, speed, _ = spreads(path)
    out = CliRunner().invoke(main, ["info", str(path)]).output
    line = next(x for x in out.splitlines() if x.startswith("check"))
    found = re.search(r"at rtol 1e-13 \(\S+ s\): (\d+) of 60 balls hold to 1e-9 of the impact "
                      r"speed; the largest spread is (\S+), ball (\d+)", line)
    assert found, line
    assert int(found[1]) == holding(final, separation, speed)
    assert int(found[3]) == np.argmax(np.fmax(final, separation)) + 1
    ds = chainrun.open_run(path)
    assert np.array_equal(ds.final_velocity_spread.values, final)
    assert np.array_equal(ds.separation_velocity_spread.values, separation)


def test_the_papers_table1_line_holds_on_every_ball(tmp_path):
    result = simulate(CONFIGS / "table1.toml", "-o", tmp_path / "t1", "--check")
    assert result.exit_code == 0, result.output
    lines = [x for x in result.stdout.splitlines() if x.startswith("k=")]
    assert len(lines) == 4
    for k, line in enumerate(lines, start=1):
        final, separation, speed, _ = spreads(tmp_path / "t1" / f"k={k}.h5")
        assert np.all(final <= 1e-9) and np.all(separation <= 1e-9)
        assert "5 of 5 balls hold to 1e-9" in line
    # the table of final velocities gives six significant digits, which the spreads
    # support; rounded to four decimals, they are the paper's Table 1 (ball 5, K = 1..4)
    row = next(x for x in result.stdout.splitlines() if x.split()[:1] == ["5"])
    shown = row.split()[1:]
    assert all(len(v.replace(".", "").lstrip("0")) == 6 for v in shown), row
    assert [round(float(v), 4) for v in shown] == [0.9888, 1.1397, 1.1126, 1.0711]
    info = CliRunner().invoke(main, ["info", str(tmp_path / "t1")]).output
    assert info.count(" 5/5") == 4


def test_resuming_computes_a_run_again_only_for_a_check_it_lacks(tmp_path):
    out = tmp_path / "t1"
    assert simulate(CONFIGS / "table1.toml", "-o", out).exit_code == 0
    with h5py.File(out / "k=1.h5") as f:
        assert "final_velocity_spread" not in f["results"]
    again = simulate(CONFIGS / "table1.toml", "-o", out, "--check")
    assert again.exit_code == 0, again.output                       # not a conflict
    assert "up to date" not in again.stdout
    with h5py.File(out / "k=1.h5") as f:
        assert "final_velocity_spread" in f["results"]
    third = simulate(CONFIGS / "table1.toml", "-o", out, "--check")
    assert third.output.count("skipped, file up to date") == 4
    plain = simulate(CONFIGS / "table1.toml", "-o", out)
    assert plain.output.count("skipped, file up to date") == 4       # the check is extra


def test_the_check_outdir_holds_each_check_runs_own_file(tmp_path):
    config = tmp_path / "cradle.toml"
    config.write_text('name = "cradle"\n[chain]\nn = 5\nk = 2\nalpha = 1.5\n[solver]\n'
                      'rtol = 1e-15\n[output]\ntimes = [0.0, 5.0]\n')
    result = simulate(config, "-o", tmp_path / "runs", "--check-outdir", tmp_path / "check")
    assert result.exit_code == 0, result.output
    # below 1e-15 the check runs ten times looser
    assert "check (rtol 1e-14)" in result.output
    main_run = chainrun.open_run(tmp_path / "runs" / "run.h5")
    check_run = chainrun.open_run(tmp_path / "check" / "run.h5")
    assert check_run.attrs["rtol"] == pytest.approx(1e-14, rel=1e-15)
    assert np.array_equal(main_run.final_velocity_spread.values,
                          np.abs(main_run.final_velocity.values - check_run.final_velocity.values))
    assert check_run.sizes["time"] == 2 and (tmp_path / "check" / "index.h5").is_file()
    # the API's check is the command's
    ds = chainrun.simulate(config, check=True)
    assert np.array_equal(ds.final_velocity_spread.values,
                          main_run.final_velocity_spread.values)


def test_an_si_checks_message_and_stop_time_carry_their_unit(tmp_path):
    """The check run's message writes its time with a unit as the run's does, and the
    file's t_end has its unit beside it."""
    config = tmp_path / "c.toml"
    config.write_text('name = "c"\nunits = "si"\n[chain]\nn = 5\nk = 1\nspeed = 0.3\n'
                      'diameter = 0.0254\nmaterial = "steel"\n[solver]\nt_end = 1.0e-4\n')
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(out), "--check"])
    assert result.exit_code == 0, result.output
    with h5py.File(out / "run.h5") as f:
        results, parameters = dict(f["results"].attrs), dict(f["parameters"].attrs)
    assert results["message"].startswith("stopped at t_end = 100 µs after ")
    assert results["check_message"].startswith("stopped at t_end = 100 µs after ")
    assert parameters["t_end"] == 1.0e-4 and parameters["t_end_unit"] == "s"
