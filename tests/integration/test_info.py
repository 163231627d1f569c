"""``chainrun info``: the summary of a run file or an output folder, checked against the
file's own arrays read with h5py and against conservation of energy."""

from __future__ import annotations

import math
import re
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from chainrun.cli import main

CONFIGS = Path(__file__).resolve().parents[2] / "configs"


@pytest.fixture(scope="module")
def table1(tmp_path_factory):
    """Table 1's four runs (N = 5, K = 1..4, Hertz) in an output folder."""
    out = tmp_path_factory.mktemp("info") / "table1"
    result = CliRunner().invoke(main, ["simulate", str(CONFIGS / "table1.toml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return out


def info(*args):
    return CliRunner().invoke(main, ["info", *map(str, args)])


def field(text: str, label: str) -> str:
    return next(line for line in text.splitlines() if line.startswith(label))


def _simulate(tmp_path, text: str, out: str = "out") -> Path:
    """The output folder of ``chainrun simulate`` on an experiment written as ``text``."""
    config = tmp_path / f"{out}.toml"
    config.write_text(text)
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(tmp_path / out)])
    assert result.exit_code == 0, result.output
    return tmp_path / out


def test_a_run_file_is_summarised_from_its_own_arrays(table1):
    path = table1 / "k=2.h5"
    with h5py.File(path) as f:
        v = f["results/final_velocity"][()]
        kinds = f["events/kind"][()]
        end = f["results"].attrs["end_time"]
    result = info(path)
    assert result.exit_code == 0, result.output
    out = result.stdout
    assert "N = 5 balls, the first K = 2" in field(out, "model")
    assert "Hertz" in field(out, "model") and "paper units" in field(out, "model")
    assert f"terminal state at t = {end:.6g}" in field(out, "outcome")
    assert field(out, "cost").startswith(f"cost      {kinds.size} events")
    balls = field(out, "balls")
    assert f"largest forward velocity: ball {np.argmax(v) + 1} at {v.max():.6g}" in balls
    assert f"largest backward velocity: ball {np.argmin(v) + 1} at {v.min():.6g}" in balls
    # backward and forward faster than 1% of the impact speed (the paper's threshold)
    counts = re.search(r"(\d+) rebound and (\d+) ejected .* (\d+) left behind", out)
    assert [int(c) for c in counts.groups()] == [
        int(np.sum(v < -0.01)), int(np.sum(v > 0.01)), int(np.sum(np.abs(v) <= 0.01))]


def shares(out: str) -> dict[str, float]:
    """The energy line's shares, by name, in percent."""
    text = field(out, "energy").split(":", 1)[1]
    return {name.strip(): float(value) for name, value in
            re.findall(r"([a-z ]+?) (-?[\d.]+)%", text)}


def test_the_energy_shares_account_for_the_whole_impact_energy(table1):
    """At the terminal state every contact is open: the kinetic shares of the rebounding,
    ejected and left-behind balls add up to the impact energy K/2."""
    for k in range(1, 5):
        with h5py.File(table1 / f"k={k}.h5") as f:
            v = f["results/final_velocity"][()]
        got = shares(info(table1 / f"k={k}.h5").stdout)
        assert got["in contacts"] == 0.0  # (no walls: the line's contacts alone)
        assert got["rebound"] == pytest.approx(100 * np.sum(v[v < -0.01] ** 2) / k, abs=0.006)
        assert sum(got.values()) == pytest.approx(100.0, abs=0.02)


def test_an_output_folder_has_a_line_per_run(table1):
    """A sweep of K is no ensemble: a line per run, and no statistics over them (those
    are for the same line over random seeds, tests/integration/test_ensembles.py)."""
    result = info(table1)
    assert result.exit_code == 0, result.output
    lines = result.stdout.splitlines()
    assert lines[0].endswith(": 4 runs")
    rows = [line.split() for line in lines[2:6]]
    assert [r[0] for r in rows] == [f"k={k}.h5" for k in range(1, 5)]
    for k, row in enumerate(rows, start=1):
        with h5py.File(table1 / f"k={k}.h5") as f:
            v = f["results/final_velocity"][()]
        assert (int(row[1]), int(row[2]), row[3]) == (5, k, "terminal")
        assert float(row[-1]) == pytest.approx(v.max(), rel=1e-5)
    assert len(lines) == 6 and "standard deviation" not in result.stdout
    # the columns right-aligned under their titles, "forward (paper units)" the widest
    assert lines[1].endswith("forward (paper units)")
    assert len({len(line) for line in lines[1:6]}) == 1
    # the folder named by its index is the folder
    assert info(table1 / "index.h5").stdout == result.stdout


def test_a_sweeps_table_gives_each_runs_swept_value_in_its_unit(tmp_path):
    """The folder's table has a column of each swept key (N and K have theirs): an SI
    speed in one prefix, its value as the run's file gives it."""
    out = _simulate(tmp_path, 'name = "s"\nunits = "si"\n[chain]\nn = 6\nk = 1\nspeed = 0.1\n'
                    'diameter = 0.008\nmaterial = "steel"\n[sweep]\n'
                    '"chain.speed" = [0.05, 0.2]\n"chain.n" = [6, 7]\n')
    lines = info(out).stdout.splitlines()
    assert lines[1].split()[:5] == ["file", "speed", "(mm/s)", "N", "K"]
    rows = {line.split()[0]: line.split()[1:3] for line in lines[2:6]}
    assert sorted(rows.values()) == [["200", "6"], ["200", "7"], ["50", "6"], ["50", "7"]]


def test_a_damped_sweeps_lines_give_each_runs_dissipated_share(tmp_path):
    out = _simulate(tmp_path, 'name = "e"\nunits = "si"\n[chain]\nn = 5\nk = 1\nspeed = 0.5\n'
                    'diameter = 0.0254\nmaterial = "steel"\nrestitution = 0.9\n'
                    'damping_law = "tsuji"\n[sweep]\n"chain.restitution" = [0.5, 1.0]\n')
    lines = info(out).stdout.splitlines()
    assert lines[1].split()[-1] == "dissipated"
    shares = {}
    for line in lines[2:4]:
        with h5py.File(out / line.split()[0]) as f:
            m, v = f["model/mass"][0], f["model/velocity"][0]  # the striker's
            lost = f["results/contact_dissipation"][()].sum() / (0.5 * m * v**2)
        shares[line.split()[0]] = (float(line.split()[-1].rstrip("%")), 100 * lost)
    assert shares["restitution=1.0.h5"][0] == 0.0
    share, lost = shares["restitution=0.5.h5"]
    assert share == pytest.approx(lost, abs=0.01) and share > 10.0


def test_a_folder_of_long_run_ids_keeps_its_columns(tmp_path):
    from helpers import simulate_text

    out = simulate_text(tmp_path, 'name = "long"\n[chain]\nn = 4\nk = 1\nalpha = 1.5\n'
                                  'damping_law = "tsuji"\n[solver]\nt_end = 1.0\n'
                                  '[sweep]\n"chain.restitution" = [0.9, 0.95]\n'
                                  '"chain.speed" = [0.125]\n')
    lines = info(out).stdout.splitlines()
    head, rows = lines[1], lines[2:4]
    assert len(max(rows, key=len).split()[0]) > 24          # ids longer than the column
    # every column of numbers ends where its heading does: N = 4 and K = 1 under theirs
    for name, value in (("N", "4"), ("K", "1")):
        end = head.index(f" {name} ") + 1 + len(name)
        assert all(row[:end].split()[-1] == value and row[end] == " " for row in rows), \
            (head, rows)
    assert all(" at t_end " in row for row in rows)


def test_what_is_not_a_run_is_refused_in_one_line(tmp_path):
    bad = tmp_path / "bad.h5"
    bad.write_bytes(b"not hdf5 at all")
    for path in (bad, tmp_path):
        result = info(path)
        assert result.exit_code == 2
        assert result.stderr.startswith("chainrun: error: ")
        assert len(result.stderr.strip().splitlines()) == 1
        assert "Traceback" not in result.output
    assert info(tmp_path / "missing.h5").exit_code == 2


def _run(tmp_path, config: str) -> Path:
    """The first run file of an example experiment."""
    out = tmp_path / Path(config).stem
    result = CliRunner().invoke(main, ["simulate", str(CONFIGS / config), "-o", str(out)])
    assert result.exit_code == 0, result.output
    return sorted(p for p in out.glob("*.h5") if p.name != "index.h5")[0]


def _energies_from_the_file(path: Path) -> dict[str, float]:
    """The shares of the impact energy, computed here from the file's own arrays: its
    masses, initial and final velocities, contacts, walls and what it dissipated."""
    with h5py.File(path) as f:
        m, v0, x0 = (f[f"model/{k}"][()] for k in ("mass", "velocity", "position"))
        kappa, alpha, gap, force = (f[f"model/{k}"][()] for k in ("stiffness", "alpha",
                                                                 "gap", "force"))
        walls = {side: dict(f[f"model/walls/{side}"].attrs) for side in f["model/walls"]}
        v, x = f["results/final_velocity"][()], f["results/final_position"][()]
        dissipated = float(f["results"].attrs["dissipated_energy"])

    def elastic(x):
        parts = [(x[:-1] - x[1:] - gap, kappa, alpha)]
        for side, w in walls.items():
            d = -x[0] - w["gap"] if side == "left" else x[-1] - w["gap"]
            parts.append((np.array([d]), w["stiffness"], w["alpha"]))
        return sum(float(np.sum(k * np.clip(d, 0, None) ** (a + 1) / (a + 1)))
                   for d, k, a in parts)

    def potential(x):
        return elastic(x) - float(force @ x)

    base = potential(x0) if np.any(x0) else 0.0
    impact = 0.5 * float(m @ v0**2) + potential(x0) - base
    # stored against the external forces, apart from the contacts' own
    against = -float(force @ (x - x0))
    ejected = v > 0.01 * np.max(np.abs(v0))
    rebound = v < -0.01 * np.max(np.abs(v0))
    kinetic = 0.5 * m * v**2
    return {"rebound": kinetic[rebound].sum() / impact,
            "ejected": kinetic[ejected].sum() / impact,
            "left behind": kinetic[~rebound & ~ejected].sum() / impact,
            "in contacts and walls" if walls else "in contacts":
                (potential(x) - base - against) / impact,
            **({"against the forces": against / impact} if np.any(force) else {}),
            "dissipated": dissipated / impact}


@pytest.mark.parametrize("config", ["examples/dimer.toml", "examples/wall.toml",
                                    "examples/damped-cradle.toml", "examples/precompressed.toml",
                                    "examples/newtons-cradle.toml"])
def test_every_line_shares_its_own_impact_energy(tmp_path, config):
    path = _run(tmp_path, config)
    out = info(path).stdout
    want = _energies_from_the_file(path)
    got = shares(out)
    if "kinetic" in got:  # stopped before its terminal state: no fates to sort by
        want = {"kinetic": sum(want.pop(k) for k in ("rebound", "ejected", "left behind")),
                **want}
        assert "before the terminal state" in field(out, "balls")
    for name, value in want.items():
        if name in got or abs(value) > 5e-5:
            assert got[name] == pytest.approx(100 * value, abs=0.006), name
    assert sum(got.values()) == pytest.approx(100.0, abs=0.02)


def test_an_si_run_speaks_si(tmp_path):
    path = _run(tmp_path, "examples/damped-cradle.toml")
    out = info(path).stdout
    with h5py.File(path) as f:
        end = f["results"].attrs["end_time"]
        v = f["results/final_velocity"][()]
    assert "paper units" not in out and "SI units" in field(out, "model")
    assert "steel spheres of 25.4 mm" in field(out, "line")
    assert "masses 67" in field(out, "line") and " g;" in field(out, "line")
    assert f"t = {end * 1e6:.6g} µs" in field(out, "outcome")
    assert f"at {v.max() * 1e3:.6g} mm/s" in field(out, "balls")
    assert re.search(r"impact energy [\d.]+ mJ", field(out, "energy"))


def test_a_checked_runs_velocities_show_the_digits_its_table_shows(tmp_path):
    config = tmp_path / "cradle.toml"
    config.write_text('name = "cradle"\nunits = "si"\n[chain]\nn = 8\nk = 1\nspeed = 0.5\n'
                      'diameter = 0.0254\nmaterial = "steel"\nrestitution = 0.95\n'
                      'damping_law = "tsuji"\n[walls.right]\nmaterial = "steel"\n'
                      '[solver]\nrtol = 1e-5\n')
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(tmp_path / "out"),
                                       "--check"])
    assert result.exit_code == 0, result.output
    table = {line.split()[0]: line.split()[1] for line in result.stdout.splitlines()
             if line[:1].isdigit()}
    balls = field(info(tmp_path / "out" / "run.h5").stdout, "balls")
    shown = re.findall(r"ball (\d+) at (\S+) mm/s", balls)
    assert shown == [("1", table["1"])]  # every ball rebounds from the wall; ball 1 fastest
    assert len(table["1"].split(".")[1]) == 2  # -412.36: its spread cuts a digit of six
    for ball, value in shown:
        assert value == table[ball], (ball, value, table[ball])


def test_an_si_runs_accuracy_and_counts_say_what_they_measure(tmp_path):
    """61 stainless beads of 8 mm struck at 0.1 m/s: 11 of the balls behind the wave end
    within rounding of rest, at velocities in (-1e-13, 0) m/s, and more drift back at
    less than 1% of the impact speed. Balls rebound and are ejected, each way, faster
    than the paper's 1% (1 mm/s here), counted here from the file; |dP| is a momentum
    in N s (rounding's: below 1e-14 of the striker's momentum), and the run ends at a
    time with its unit, in the file as in words."""
    out = _simulate(tmp_path, 'name = "sol"\nunits = "si"\n[chain]\nn = 61\nk = 1\n'
                    'speed = 0.1\ndiameter = 0.008\nmaterial = "stainless_steel"\n')
    with h5py.File(out / "run.h5") as f:
        v = f["results/final_velocity"][()]
        m = f["model/mass"][()]
        results = dict(f["results"].attrs)
    text = info(out / "run.h5").stdout
    assert np.any((v < 0) & (v >= -1e-13)) and np.any((v < 0) & (v > -1e-3))
    counts = re.search(r"(\d+) rebound and (\d+) ejected \(backward and forward faster than "
                       r"1% of the impact speed, 1 mm/s\), (\d+) left behind", text)
    assert counts is not None, text
    assert [int(c) for c in counts.groups()] == [
        int(np.sum(v < -1e-3)), int(np.sum(v > 1e-3)), int(np.sum(np.abs(v) <= 1e-3))]
    dp = re.search(r"\|dP\| = ([\d.e+-]+) N s", field(text, "accuracy"))
    assert dp is not None and float(dp.group(1)) <= 1e-14 * m[0] * 0.1
    assert results["end_time_unit"] == "s"
    assert results["message"] == (f"terminal state reached at t = "
                                  f"{results['end_time'] * 1e3:.6g} ms after 60 events")


def test_a_precompressed_runs_summary_names_its_precompression(tmp_path):
    """The line's precompression (a static force on the first ball at rest, held by
    the right wall) is said as one, and each peak force is said to include it."""
    out = _simulate(tmp_path, 'name = "pre"\nunits = "si"\n[chain]\nn = 30\nk = 1\n'
                    'speed = 0.1\ndiameter = 0.008\nmaterial = "stainless_steel"\n'
                    'precompression = 1.0\n[walls.right]\n[output]\nsensors = [10, 20]\n'
                    'sensor_dt = 1e-7\n[solver]\nt_end = 6e-4\n')
    text = info(out / "run.h5").stdout
    assert "precompressed 1 N (a static force on ball 2, held by the right wall)" in field(
        text, "line")
    assert "forces on" not in field(text, "line")
    peaks = [line for line in text.splitlines() if "peak contact force" in line]
    assert len(peaks) == 2 and all("(the static 1 N included)" in line for line in peaks)


def test_the_pulses_of_a_steel_chain_are_the_solitary_waves(tmp_path):
    """Sensors in a chain of steel beads struck at 0.5 m/s: each records the solitary
    wave, whose peak contact force is 0.63955 in the paper's units (0.640 printed in
    its section 5a), here in newtons through the paper's scales."""
    out = tmp_path / "sol"
    config = tmp_path / "sol.toml"
    config.write_text('name = "sol"\nunits = "si"\n[chain]\nn = 40\nk = 1\nspeed = 0.5\n'
                      'diameter = 0.0254\nmaterial = "steel"\n[output]\nsensors = [15, 25]\n'
                      'sensor_dt = 2.0e-7\n[solver]\nt_end = 1.2e-3\n')
    assert CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)]).exit_code == 0
    out_text = info(out / "run.h5").stdout
    young, poisson, rho, d, v = 207e9, 0.30, 7850.0, 0.0254, 0.5  # materials: steel
    k = young * d**0.5 / (3 * (1 - poisson**2))
    m = rho * np.pi * d**3 / 6
    force = k**0.4 * m**0.6 * v**1.2
    lines = [line for line in out_text.splitlines() if "peak contact force" in line]
    assert [line.split(": peak")[0].split()[-1] for line in lines] == ["15", "25"]
    for line in lines:
        newtons = float(re.search(r"peak contact force ([\d.]+) N", line).group(1))
        assert newtons == pytest.approx(0.63955 * force, rel=2e-4)
    speed = float(re.search(r"wave speed ([\d.]+) m/s \(a fit through 2 sensors",
                            out_text).group(1))
    # the same line given by its masses and stiffness, without diameters: the same
    # wave, its speed in balls per second (the spacing of the beads is their diameter)
    config.write_text(f'name = "sol"\nunits = "si"\n[chain]\nn = 40\nk = 1\nspeed = 0.5\n'
                      f'mass = {m!r}\nstiffness = {k!r}\nalpha = 1.5\n[output]\n'
                      'sensors = [15, 25]\nsensor_dt = 2.0e-7\n[solver]\nt_end = 1.2e-3\n')
    out = tmp_path / "by-mass"
    assert CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)]).exit_code == 0
    per_second = float(re.search(r"wave speed ([\d.]+) balls/s \(a fit through 2 sensors",
                                 info(out / "run.h5").stdout).group(1))
    assert per_second * d == pytest.approx(speed, rel=1e-5)


def test_a_pulse_width_keeps_the_digits_its_sampling_supports(tmp_path):
    """The same steel chain's sensor sampled every 0.5 µs and every 0.05 µs: the width
    printed from the coarser samples is the finer's, to fewer digits."""
    from helpers import simulate_text

    shown = []
    for dt in ("5.0e-7", "5.0e-8"):
        (tmp_path / dt).mkdir()
        out = simulate_text(tmp_path / dt, 'name = "w"\nunits = "si"\n[chain]\nn = 30\n'
                            'k = 1\nspeed = 0.5\ndiameter = 0.01\nmaterial = "steel"\n'
                            f'[output]\nsensors = [20]\nsensor_dt = {dt}\n'
                            '[solver]\nt_end = 5.0e-4\n')
        shown.append(re.search(r"width \(FWHM\) ([\d.]+) µs", info(out / "run.h5").stdout)
                     .group(1))
    coarse, fine = shown
    decimals = len(coarse.partition(".")[2])
    assert decimals < len(fine.partition(".")[2])
    assert len(coarse.replace(".", "")) < 5   # not the five digits of a measured force
    assert abs(float(fine) - float(coarse)) <= 10.0 ** -decimals


def test_a_driven_run_reports_its_steady_response_not_pulses(tmp_path):
    # The example's 2 kHz run: its drive in the run's units, and each sensor's steady
    # amplitude at the drive's frequency as chainrun.transmission measures it.
    import chainrun

    out = tmp_path / "driven"
    config = (CONFIGS / "examples" / "driven-dimer.toml").read_text()
    config = config.replace('"walls.left.motion.frequency" = [2000.0, 5000.0]',
                            '"walls.left.motion.frequency" = [2000.0]')
    (tmp_path / "driven.toml").write_text(config)
    result = CliRunner().invoke(main, ["simulate", str(tmp_path / "driven.toml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    path = next(p for p in out.glob("*.h5") if p.name != "index.h5")
    text = info(path).output
    assert "the left wall moves by 10 nm sin(2 pi f t), f = 2 kHz, ramp 1 ms" in text
    assert "pulses" not in text
    steady = chainrun.transmission(path)
    # and the pulses' measures refuse it, for its file, its Dataset and its folder
    from chainrun.errors import ChainrunError

    for run in (path, chainrun.open_run(path), out):
        with pytest.raises(ChainrunError, match="driven .* chainrun.transmission"):
            chainrun.pulses(run)
    assert steady.steady.any() and not steady.steady.all()
    for ball in (1, 10, 20):
        a = float(steady.amplitude.sel(sensor=ball, harmonic=1)) * 1e3
        line = next(s for s in text.splitlines() if f"ball {ball}: amplitude" in s)
        if bool(steady.steady.sel(sensor=ball)):
            assert re.search(rf"amplitude {a:#.4g} mN", line), (line, a)
        else:  # one digit: what the fit leaves is more than a tenth of the amplitude
            shown = float(re.search(r"amplitude ([\d.]+) mN", line).group(1))
            assert len(f"{shown:g}".replace(".", "").strip("0")) == 1, line
            assert abs(shown - a) <= 0.5 * 10.0 ** math.floor(math.log10(a)), (line, a)
            assert "(not steady: " in line


def test_a_driven_precompressed_line_shares_what_it_took_up_not_the_static_load(tmp_path):
    # A line under a static load F0 = 1 whose left wall is shaken by A = 1e-6: the
    # load's work F0 w(t) swings far above what the shaking puts in (about (A omega)^2),
    # and the run stops where the wall is drawn back (w(t_end) = -A). Taken off the
    # drives' work and the contacts' energy alike, every share lies in [0, 1] and they
    # add up to 1; the load's work is F0 w(t_end) in closed form.
    import math

    from chainrun.analysis.summary import summarize
    from chainrun.store import read_run
    from tests.helpers import driven_sweep

    f, ramp = 0.05, 20.0
    t_end = ramp + 3.75 / f  # after the ramp, at 2 pi f t = 2 pi (an integer) + 3 pi / 2
    text = driven_sweep("shaken", 6, [f], ramp=ramp, t_end=t_end)
    (tmp_path / "shaken.toml").write_text(text)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["simulate", str(tmp_path / "shaken.toml"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    path = next(p for p in out.glob("*.h5") if p.name != "index.h5")
    s = summarize(read_run(path))
    w_end = 1e-6 * math.sin(2 * math.pi * f * t_end)
    assert s.static_load == pytest.approx(1.0 * w_end, rel=1e-9)
    assert 0.0 < s.drive_work < 1e-3 * abs(s.static_load)
    # (the balance holds to the rounding of the static state's energy, of order 1:
    # about 1e-3 of the 1e-13 the shaking puts in)
    shares = [s.energy[name] for name in ("rebound", "ejected", "left behind", "contacts")]
    assert all(-1e-2 <= share <= 1.0 + 1e-2 for share in shares), s.energy
    assert sum(shares) == pytest.approx(1.0, abs=1e-2)
    said = info(path).output
    assert "(beyond the static load's -1e-06, which the walls' return gives back)" in said


def test_info_says_a_balance_is_within_its_rounding_as_the_run_line_does(tmp_path):
    # a wall of amplitude 0: nothing moves, and what |dE|/E measures is the rounding of
    # the static state's energy (of order 1), as the run's own line says
    import warnings

    from tests.helpers import driven_sweep

    text = driven_sweep("still", 6, [0.05], t_end=50.0).replace("amplitude = 1.0e-6",
                                                               "amplitude = 0.0")
    (tmp_path / "still.toml").write_text(text)
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = CliRunner().invoke(main, ["simulate", str(tmp_path / "still.toml"), "-o",
                                           str(out)])
    assert result.exit_code == 0, result.output
    said = re.search(r"\(within its rounding, ([\d.e+-]+)\)", result.output)
    assert said, result.output
    path = next(p for p in out.glob("*.h5") if p.name != "index.h5")
    assert f"(within its rounding, {said.group(1)}; projection corrected" in info(path).output


def test_info_says_when_it_fits_fewer_harmonics_than_transmission(tmp_path):
    # f = 0.05 sampled every 4: the third harmonic, 0.15, is above the sensors' Nyquist
    # frequency 1 / (2 * 4) = 0.125, the second is not: info fits two and says so
    import warnings

    from tests.helpers import driven_sweep

    text = driven_sweep("slow", 6, [0.05], sensor_dt=4.0, ramp=20.0, t_end=400.0)
    (tmp_path / "slow.toml").write_text(text)
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert CliRunner().invoke(main, ["simulate", str(tmp_path / "slow.toml"), "-o",
                                         str(out)]).exit_code == 0
    path = next(p for p in out.glob("*.h5") if p.name != "index.h5")
    assert "(fitted with 2 harmonics, not chainrun.transmission's 3" in info(path).output


def test_every_balls_velocity_is_printed_on_request_for_any_n(tmp_path):
    """A line of 25 balls (longer than simulate's table) gets its table from
    ``info --velocities``: a row per ball, each the file's final velocity."""
    out = tmp_path / "long"
    config = tmp_path / "long.toml"
    config.write_text('name = "long"\n[chain]\nn = 25\nk = 1\nalpha = 1.5\n')
    assert CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)]).exit_code == 0
    with h5py.File(out / "run.h5") as f:
        v = f["results/final_velocity"][()]
    text = CliRunner().invoke(main, ["info", str(out / "run.h5"), "--velocities"]).stdout
    table = text.split("final velocities (paper units)\n")[1].splitlines()
    assert table[0].split() == ["n", "run"]
    rows = [line.split() for line in table[1:26]]
    assert [int(r[0]) for r in rows] == list(range(1, 26))
    np.testing.assert_allclose([float(r[1]) for r in rows], v, atol=5e-5)


def test_a_sensor_on_a_walls_contact_is_the_force_on_the_wall_not_a_point_of_the_wave(
        tmp_path):
    """A sensor on the last ball, against a right wall, measures the wall's contact as
    the wave reflects (about twice the wave's force): the speed is fitted through the
    other sensors alone, as a run without it gives it, and info says so."""
    def run(sensors):
        out = tmp_path / str(len(sensors))
        config = tmp_path / f"w{len(sensors)}.toml"
        config.write_text('name = "w"\n[chain]\nn = 30\nk = 1\nalpha = 1.5\n[walls.right]\n'
                          f'[output]\nsensors = {sensors}\nsensor_dt = 0.01\n'
                          '[solver]\nt_end = 60.0\n')
        assert CliRunner().invoke(main, ["simulate", str(config), "-o", str(out)]).exit_code == 0
        return out / "run.h5"

    from chainrun.analysis.pulse import measure_pulses

    with_wall, without = measure_pulses(run([10, 20, 30])), measure_pulses(run([10, 20]))
    assert list(with_wall.on_wall) == [False, False, True]
    assert with_wall.speed.value == without.speed.value and with_wall.speed.points == 2
    assert with_wall.peak_force[2] > 1.5 * with_wall.peak_force[1]
    text = info(tmp_path / "3" / "run.h5").stdout
    assert "ball 30: peak force on the wall (where the wave reflects)" in text
