"""The gallery (``make gallery``): its registry, its measurements against closed forms
and independent computations, the damped items' energy balance, and smoke runs of
items' pipelines."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from scipy import special

import chainrun
from chainrun import artefacts
from chainrun.analysis import gallery_measure as gm
from chainrun.analysis import recipe
from chainrun.cli import main
from chainrun.config import load_experiment
from chainrun.runner import run_file, simulate_run
from chainrun.solver import EventKind
from chainrun.solver import restitution as two_body
from chainrun.store import read_run
from helpers import driven_sweep

ROOT = Path(__file__).resolve().parents[2]


# ----------------------------------------------------------------------- the registry
def test_every_gallery_config_is_read_and_every_experiment_has_one():
    used = set(artefacts.experiments(artefacts.GALLERY))
    files = {f"gallery/{p.stem}" for p in (ROOT / "configs" / "gallery").glob("*.toml")}
    assert used == files
    for experiment in used:
        spec = load_experiment(ROOT / "configs" / f"{experiment}.toml")
        assert f"gallery/{spec.name}" == experiment


def test_gallery_artefacts_have_recipes_modules_and_outputs():
    for a in artefacts.GALLERY:
        assert a.name.startswith("gallery-")
        assert callable(recipe(a))
        assert all(o.startswith(("gallery/", "gallery-comparison.")) for o in a.outputs)
    assert artefacts.GALLERY[-1].needs == tuple(a.name for a in artefacts.GALLERY[:-1])
    assert not set(artefacts.ARTEFACTS) & set(artefacts.GALLERY)   # make figures unchanged


def test_make_rules_list_the_gallery_apart():
    rules = artefacts.make_rules(results="R").splitlines()
    paper = next(l for l in rules if l.startswith("ARTEFACT_OUTPUTS :="))
    gallery = next(l for l in rules if l.startswith("GALLERY_OUTPUTS :="))
    assert "gallery" not in paper
    assert "R/gallery/solitary.png" in gallery and "R/gallery-comparison.md" in gallery
    line = next(l for l in rules if l.startswith("R/analysis/gallery-dimer.h5:"))
    assert "R/runs/gallery/dimer-0.35/index.h5" in line
    assert "chainrun/analysis/gallery_measure.py" in line
    assert "chainrun/analysis/pulse.py" in line


# ------------------------------------------------------------- closed forms and limits
def test_long_wave_prefactors_are_one_law():
    # The precompressed law tends to the unprecompressed one: c0 sqrt(8/15) f^(1/6).
    assert gm.long_wave_sound_prefactor() * math.sqrt(8 / 15) == pytest.approx(
        gm.long_wave_prefactor(), rel=1e-14)
    f = 1e12
    assert gm.nesterenko_precompressed_ratio(f) == pytest.approx(
        math.sqrt(8 / 15) * f ** (1 / 6), rel=1e-3)
    assert gm.nesterenko_precompressed_ratio(1 + 1e-4) == pytest.approx(1.0, abs=1e-4)
    assert gm.long_wave_prefactor("5.1") / gm.long_wave_prefactor() == pytest.approx(
        0.9 ** (-1 / 6))


def test_paper_to_si_reproduces_a_steel_chain_speed():
    """A speed c F^(1/6) in the paper's units, converted by hand through the line's own
    scales, equals PAPER_TO_SI times the SI group."""
    E, nu, rho, d = 2.0e11, 0.3, 7800.0, 0.01
    k = E * math.sqrt(d) / (3 * (1 - nu**2))
    m = rho * math.pi * d**3 / 6
    V = 0.37                                  # any impact speed sets the scales
    T = (m**2 / (k**2 * V)) ** 0.2
    F0 = k ** 0.4 * m ** 0.6 * V ** 1.2
    F = 12.0                                  # N
    speed = 1.0 * (F / F0) ** (1 / 6) * d / T  # c = 1 * f^(1/6) balls per unit time
    assert speed == pytest.approx(gm.PAPER_TO_SI * gm.daraio_group(F, E, nu, rho, d),
                                  rel=1e-12)


def test_hertz_contact_time_factor_by_the_beta_function():
    integral = 0.4 * special.beta(0.4, 0.5)   # int_0^1 (1 - x^(5/2))^(-1/2) dx
    assert gm.hertz_contact_time_factor() == pytest.approx(2 * integral * 1.25**0.4,
                                                           rel=1e-12)


def test_restitution_energy_split_drift():
    assert gm.restitution([1, 2], [1, 1], [-1, -0.25]) == pytest.approx(0.5)
    assert gm.energy_split([1, 2, 1], [1, 1, 2], 2) == (0.5, 1.0, 2.0)
    np.testing.assert_allclose(gm.drift([0.0, 1.0], [1.0, -2.0], 0.5, 1.5), [1.0, -1.0])


def test_wall_contact_ends_where_the_force_returns_to_zero():
    U, O, C, R, E = (EventKind.UNLOAD, EventKind.OPEN, EventKind.CLOSE, EventKind.RELEASE,
                     EventKind.ENGAGE)
    # damped: the collision ends at the unloading; the opening comes after it
    assert gm.wall_contact([1.0, 1.1], [3, 3], [U, O], 3) == (1.0, 1.1, 1)
    # two loadings, one damped and one elastic; other contacts' events are ignored
    assert gm.wall_contact([2.5, 1.1, 0.5, 2.0, 1.0], [3, 3, 2, 3, 3], [O, O, C, C, U],
                           3) == (2.5, 2.5, 2)
    # released by the noise floor, engaged again, opened
    assert gm.wall_contact([1.0, 2.0, 3.0], [0, 0, 0], [R, E, O], 0) == (3.0, 3.0, 2)
    end, opened, count = gm.wall_contact([], [], [], 0)
    assert math.isnan(end) and math.isnan(opened) and count == 0


# ------------------------------------------------------------- against the solver
def test_two_balls_against_the_solver():
    """A heavy impurity struck directly: two balls, the elastic two-body outcome."""
    ds = chainrun.simulate(chain={"n": 2, "k": 1, "alpha": 1.5, "mass": [1.0, 4.0]})
    v1, v2 = gm.two_ball(1.0, 4.0)
    np.testing.assert_allclose(ds.final_velocity.values, [v1, v2], atol=1e-12)
    before, on, after = gm.energy_split([1.0, 4.0], ds.final_velocity.values, 2)
    assert on == pytest.approx(0.5 * 4 * 4 / 25, rel=1e-10)   # 4M/(1+M)^2 of 1/2
    assert before + on + after == pytest.approx(0.5, rel=1e-11)


def test_one_bead_on_a_wall_lasts_hertz_time_and_bounces_back_whole():
    ds = chainrun.simulate(chain={"n": 1, "velocity": 1.0, "alpha": 1.5},
                           walls={"right": {"stiffness": 1.0}})
    # elastic: the bead leaves as fast as it came, to the solver's accuracy (rtol 1e-12)
    assert gm.restitution([1.0], [1.0], ds.final_velocity.values) == pytest.approx(1.0,
                                                                                 abs=1e-10)
    release = float(ds.event_time.values[-1])
    assert release == pytest.approx(gm.hertz_contact_time_factor(), rel=1e-9)


def _run(tmp_path, text: str):
    """Simulate a one-run experiment given as TOML text; its run file, read back."""
    path = tmp_path / "experiment.toml"
    path.write_text('name = "t"\n' + text)
    (spec,) = load_experiment(path).runs()
    summary = simulate_run(spec, tmp_path)
    assert summary.ok, summary.message
    return read_run(run_file(tmp_path, spec))


def _wall_energy_balance(run):
    """|final kinetic + dissipated - initial kinetic| / initial, and the same for the
    dissipation split by contact and wall."""
    m, v0, v = run.model["mass"], run.model["velocity"], run.final_velocity
    e0 = 0.5 * np.sum(m * v0**2)
    parts = run.wall_dissipation.sum() + (0.0 if run.contact_dissipation is None
                                         else run.contact_dissipation.sum())
    return (abs(0.5 * np.sum(m * v**2) + run.dissipated_energy - e0) / e0,
            abs(parts - run.dissipated_energy) / e0)


def test_one_bead_on_a_linear_dashpot_wall_is_the_closed_form(tmp_path):
    """A bead on a spring-dashpot wall (alpha = 1, beta = 0): e = exp(-gamma tau_c), the
    force vanishing at tau_c = 2 atan2(w, gamma) / w (Schwager and Poeschel 2007)."""
    m, kappa, eta, v = 1.0, 1.0, 0.6, 1.0
    run = _run(tmp_path, f"""
[chain]
n = 1
alpha = 1.5
velocity = {v}
[walls.right]
stiffness = {kappa}
alpha = 1.0
damping = {eta}
""")
    gamma = eta / (2.0 * math.sqrt(m * kappa))   # in units of sqrt(kappa/m)
    w = math.sqrt(1.0 - gamma**2)
    tau_c = 2.0 * math.atan2(w, gamma) / w
    e = math.exp(-gamma * tau_c)
    assert gm.restitution([m], [v], run.final_velocity) == pytest.approx(e, abs=1e-10)
    # the right wall of a line of N balls is contact N
    end, opened, count = gm.wall_contact(run.event_time, run.event_contact, run.event_kind, 1)
    assert end == pytest.approx(tau_c * math.sqrt(m / kappa), rel=1e-9)
    assert opened > end and count == 1
    assert run.dissipated_energy == pytest.approx(0.5 * m * v * v * (1 - e * e), rel=1e-9)
    assert run.wall_dissipation[1] == pytest.approx(run.dissipated_energy, rel=1e-12)


def test_one_damped_bead_on_a_wall_is_the_two_body_law(tmp_path):
    """The gallery's damped wall (Tsuji, e = 0.95) with one bead: the restitution and the
    contact time of the two-body integration, and energy kept with the dissipation."""
    run = _run(tmp_path, """
units = "si"
[chain]
n = 1
velocity = 0.2
diameter = 0.008
material = "chrome_steel"
[walls.right]
material = "steel"
restitution = 0.95
damping_law = "tsuji"
""")
    wall = run.model["walls"]["right"]
    law = (wall["damping"], wall["damping_exponent"], wall["stiffness"], wall["alpha"],
           run.model["mass"][0], 0.2)
    e = gm.restitution(run.model["mass"], run.model["velocity"], run.final_velocity)
    assert two_body.restitution(*law) == pytest.approx(0.95, abs=1e-10)
    assert e == pytest.approx(0.95, abs=1e-10)
    end, _, count = gm.wall_contact(run.event_time, run.event_contact, run.event_kind, 1)
    assert end == pytest.approx(two_body.contact_duration(*law), rel=1e-9)
    assert count == 1
    balance, split = _wall_energy_balance(run)
    assert balance < 1e-10 and split < 1e-12


def test_damped_column_keeps_energy_and_rebounds_less_than_one_bead(tmp_path):
    """Five beads on a wall, e = 0.9 (Tsuji) everywhere: kinetic + dissipated energy is
    the impact energy, the dissipation is that of the contacts and the wall, and the
    column's restitution is below one bead's."""
    run = _run(tmp_path, """
[chain]
n = 5
velocity = 1.0
alpha = 1.5
restitution = 0.9
damping_law = "tsuji"
[walls.right]
stiffness = 1.0
restitution = 0.9
damping_law = "tsuji"
""")
    assert run.terminal
    balance, split = _wall_energy_balance(run)
    assert balance < 1e-10 and split < 1e-12
    e = gm.restitution(run.model["mass"], run.model["velocity"], run.final_velocity)
    assert 0.0 < e < 0.9
    assert np.all(np.diff(run.final_velocity) >= -1e-12)   # all moving apart


def test_tsuji_column_restitution_does_not_depend_on_the_speed(tmp_path):
    """Hertz contacts with Tsuji's damping have no scale of speed: the column's
    restitution is the same at any impact speed (the gallery's damped speed sweep)."""
    es = []
    for v in (0.3, 7.0):
        (tmp_path / f"v{v}").mkdir()
        run = _run(tmp_path / f"v{v}", f"""
[chain]
n = 4
velocity = {v}
alpha = 1.5
restitution = 0.95
damping_law = "tsuji"
[walls.right]
stiffness = 1.0
restitution = 0.95
damping_law = "tsuji"
""")
        es.append(gm.restitution(run.model["mass"], run.model["velocity"],
                                 run.final_velocity))
    assert es[0] == pytest.approx(es[1], abs=1e-10)


def test_head_on_symmetric_line_is_antisymmetric_and_keeps_momentum():
    v0 = [1.0] + [0.0] * 5 + [-1.0]
    ds = chainrun.simulate(chain={"n": 7, "alpha": 1.5, "velocity": v0})
    v = ds.final_velocity.values
    np.testing.assert_allclose(v, -v[::-1], atol=1e-13)
    assert abs(v.sum()) < 1e-13


# -------------------------------------------------------------------------- pipeline
@pytest.mark.slow
def test_head_on_item_from_configs_to_figure(tmp_path):
    """simulate -> analyze -> plot for one gallery item, through the commands."""
    runner = CliRunner()
    item = artefacts.get("gallery-head-on")
    for experiment in item.experiments:
        out = artefacts.run_dir(experiment, tmp_path)
        done = runner.invoke(main, ["simulate", str(ROOT / "configs" / f"{experiment}.toml"),
                                    "-o", str(out)])
        assert done.exit_code == 0, done.output
    done = runner.invoke(main, ["analyze", item.name, "--results", str(tmp_path)])
    assert done.exit_code == 0, done.output
    done = runner.invoke(main, ["plot", item.name, "--results", str(tmp_path)])
    assert done.exit_code == 0, done.output
    for path in artefacts.output_paths(item, tmp_path):
        assert path.stat().st_size > 0
    from chainrun.store import read_analysis

    values = read_analysis(artefacts.analysis_path(item.name, tmp_path)).values
    assert values["symmetry_error"] < 1e-12
    assert values["unequal_momentum"] == pytest.approx(0.5, abs=1e-12)
    for mu in (0.25, 0.5, 2.0, 4.0):   # energy is conserved: the two shares make 1
        assert values[f"impurity_{mu:g}_reflected"] + values[
            f"impurity_{mu:g}_transmitted"] == pytest.approx(1.0, abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["gallery-wall", "gallery-cradle"])
def test_damped_items_from_configs_to_figure(tmp_path, name):
    """The damped cradle and columns through the commands: the energy balance of every
    damped run, one bead against the two-body law, the trends the pages quote."""
    runner = CliRunner()
    item = artefacts.get(name)
    for experiment in item.experiments:
        out = artefacts.run_dir(experiment, tmp_path)
        done = runner.invoke(main, ["simulate", str(ROOT / "configs" / f"{experiment}.toml"),
                                    "-o", str(out)])
        assert done.exit_code == 0, done.output
    for command in ("analyze", "plot"):
        done = runner.invoke(main, [command, item.name, "--results", str(tmp_path)])
        assert done.exit_code == 0, done.output
    from chainrun.store import read_analysis

    values = read_analysis(artefacts.analysis_path(item.name, tmp_path)).values
    balances = [v for k, v in values.items() if "energy_balance" in k]
    assert balances and max(balances) < 1e-10
    if name == "gallery-cradle":
        for k in range(1, 5):
            # damping takes energy, never momentum: the K strikers' momentum stays
            assert sum(values[f"scaled_{n}_K{k}_damped"] for n in range(1, 6)) == \
                pytest.approx(k, abs=1e-10)
            assert 0.0 < values[f"dissipated_K{k}_damped"] < 0.5
        return
    assert values["one_e_error_damped"] < 1e-9 and values["one_t_rel_error_damped"] < 1e-9
    e = [values[f"column_e_{n}_damped"] for n in (1, 2, 5, 20)]
    assert e[0] == pytest.approx(0.95, abs=1e-9) and e == sorted(e, reverse=True)
    assert values["column_duration_us_20_damped"] > 10 * values["column_duration_us_1_damped"]
    assert values["speed_e_spread_damped"] < 1e-12   # Tsuji: no scale of speed
    kk = [values[f"speed_e_{c}cms_kk"] for c in (5, 20, 80, 320)]
    assert kk == sorted(kk, reverse=True)             # viscoelastic: falls with the speed


# ----------------------------------------------------------------------- transmission
#: A small driven dimer chain in paper units standing in for the gallery's steel and
#: aluminium one: masses 1 and 0.5, K = 1.5 at rest, so its bands end at 0.276 (acoustic)
#: and 0.390-0.477 (optical). Driven in the acoustic band, mid-gap and above the top band.
SMALL_DIMER = driven_sweep("transmission-dimer", 10, [0.15, 0.2, 0.33, 0.6],
                           mass=[1.0, 0.5], description="A small dimer chain, driven.")


def test_transmission_page_keeps_and_draws_which_points_are_not_steady(tmp_path):
    """The gallery's transmission page draws from its analysis file alone: the file keeps
    each point's ``steady`` flag and the rule behind it, and the page draws the points
    that are not steady hollow, as ``chainrun plot`` does a sweep's."""
    from chainrun.analysis import analyze
    from chainrun.analysis.transmission import MIN_PERIODS, STEADY
    from chainrun.plotting import draw, style
    from chainrun.runner import simulate_experiment
    from chainrun.store import read_analysis

    config = tmp_path / "transmission-dimer.toml"
    config.write_text(SMALL_DIMER)
    runs = artefacts.run_dir("gallery/transmission-dimer", tmp_path)
    simulate_experiment(load_experiment(config), runs, jobs=1)
    data = read_analysis(analyze("gallery-transmission", results=tmp_path))
    measured = chainrun.transmission(runs)
    steady = data.arrays["curve/steady"]
    assert steady.dtype == bool and steady.shape == (4, 2)   # (frequency, sensor)
    np.testing.assert_array_equal(
        steady, measured.steady.transpose("frequency", "sensor").values)
    assert steady.any() and not steady.all()   # above the top band the far end is not
    assert data.attrs["curve"] == {"residual_fraction": STEADY, "min_periods": MIN_PERIODS}
    for s, ball in enumerate(data.arrays["curve/sensor"]):
        assert data.values[f"not_steady_{ball}"] == np.sum(~steady[:, s])

    with style():
        figure = draw("gallery-transmission", data)
    axes = figure.axes[0]
    drawn = {a.get_gid(): a for a in axes.get_lines() if a.get_gid()}
    for s, ball in enumerate(data.arrays["curve/sensor"]):
        line = drawn[f"transmission/{ball}"]
        assert line.get_markerfacecolor() == line.get_color()   # steady: filled
        if steady[:, s].all():
            assert f"not_steady/{ball}" not in drawn
            continue
        hollow = drawn[f"not_steady/{ball}"]
        x, y = hollow.get_data()
        np.testing.assert_array_equal(x, line.get_xdata()[~steady[:, s]])
        np.testing.assert_array_equal(y, data.arrays["curve/transmission"][~steady[:, s], s])
        assert hollow.get_markerfacecolor() == "white"
        assert hollow.get_marker() == line.get_marker()
    labels = [t.get_text() for t in figure.legends[0].get_texts()]
    assert any(label.startswith("hollow: not steady") for label in labels), labels
