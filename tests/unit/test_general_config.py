"""Experiment files of the general line: generators, checks by key and index, SI units and
materials, walls, precompression, sweeps of the new keys, and what the run file records."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import h5py
import numpy as np
import pytest
from click.testing import CliRunner

from chainrun import generators, runner, store
from chainrun.cli import main
from chainrun.config import load_experiment, parse_experiment
from chainrun.errors import ConfigError
from chainrun.materials import MATERIALS
from chainrun.solver import Diagnostics, Outcome, Solution, physics
from chainrun.solver.model import Line, Wall, precompress, strikers

EXAMPLES = Path(__file__).resolve().parents[2] / "configs" / "examples"
HEAD = 'name = "x"\n'


def problems(text: str) -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_experiment(text, "toml")
    return info.value.problems


def line_of(text: str, source: str = "<string>") -> Line:
    (spec,) = parse_experiment(text, "toml", source).runs()
    return spec.line


# --- generators --------------------------------------------------------------------------


@pytest.mark.parametrize("value, expected", [
    (2.0, [2, 2, 2, 2, 2]),
    ([1, 2, 3, 4, 5], [1, 2, 3, 4, 5]),
    ({"pattern": [1.0, 0.5]}, [1, 0.5, 1, 0.5, 1]),
    ({"taper": 0.5, "start": 8.0}, [8, 4, 2, 1, 0.5]),
    ({"value": 1.0, "impurity": {"at": 2, "value": 0.1}}, [1, 0.1, 1, 1, 1]),
    ({"value": 1.0, "impurity": {"at": [1, 5], "value": 3}}, [3, 1, 1, 1, 3]),
    ({"pattern": [1, 2], "impurity": [{"at": 1, "value": 9}, {"at": 4, "value": 7}]},
     [9, 2, 1, 7, 1]),
])
def test_generators_expand(value, expected):
    np.testing.assert_array_equal(generators.expand(generators.check(value), 5), expected)


def test_random_values_are_reproducible_and_in_range():
    spec = generators.check({"random": "uniform", "low": 0.5, "high": 2.0, "seed": 1})
    a, b = generators.expand(spec, 1000), generators.expand(spec, 1000)
    np.testing.assert_array_equal(a, b)
    assert a.min() >= 0.5 and a.max() < 2.0
    other = generators.expand(generators.check(
        {"random": "uniform", "low": 0.5, "high": 2.0, "seed": 2}), 1000)
    assert not np.array_equal(a, other)
    log = generators.expand(generators.check(
        {"random": "lognormal", "median": 2.0, "sigma": 0.1, "seed": 3}), 4001)
    assert np.all(log > 0) and abs(np.median(log) / 2.0 - 1) < 0.02


def test_values_from_files_relative_to_the_config(tmp_path):
    np.save(tmp_path / "m.npy", np.array([1.0, 2.0, 3.0, 4.0]))
    (tmp_path / "k.csv").write_text("# stiffnesses\n1.0, 2.0\n3.0\n")
    config = tmp_path / "e.toml"
    config.write_text(HEAD + '[chain]\nn = 4\nk = 1\nalpha = 1.5\nmass = {file = "m.npy"}\n'
                      'stiffness = {file = "k.csv"}\n')
    (spec,) = load_experiment(config).runs()
    np.testing.assert_array_equal(spec.line.mass, [1, 2, 3, 4])
    np.testing.assert_array_equal(spec.line.stiffness, [1, 2, 3])
    # the data's hash is part of the configuration: other data is another computation
    assert len(spec.config["chain"]["mass"]["sha256"]) == 64
    np.save(tmp_path / "m.npy", np.array([1.0, 2.0, 3.0, 5.0]))
    (again,) = load_experiment(config).runs()
    assert again.config_hash != spec.config_hash
    with pytest.raises(ConfigError, match="changed since"):
        dataclasses.replace(spec).line  # a spec builds its line when it runs


@pytest.mark.parametrize("chain, expected", [
    ("mass = [1, 1, -1, 1]", "chain.mass[2]: must be > 0, got -1.0"),
    ("mass = [1, 1, 1]", "chain.mass: expected a number or a list of 4 values, got a list of 3"),
    ("stiffness = {taper = 0.5, start = -1}", "chain.stiffness[0]: must be > 0, got -1.0"),
    ("alpha = 1e6", "chain.alpha: must be <= 10 (a steeper law stiffens so abruptly that the "
                    "solver's steps shrink without end), got 1000000.0"),
    ("alpha = [1.5, 0.5, 1.5]", "chain.alpha[1]: must be >= 1, got 0.5"),
    ("mass = {value = 1, impurity = {at = 9, value = 2}}",
     "chain.mass.impurity.at: 9 is beyond the 4 values"),
    ("mass = {pattern = []}", "chain.mass.pattern: expected a non-empty list, got []"),
    ("mass = {taper = 0.9}", "chain.mass.start: required (the first value)"),
    ("mass = {random = 'uniform', low = 1, high = 2}",
     "chain.mass.seed: required (the same seed gives the same values)"),
    ("mass = {value = 1, pattern = [1]}",
     "chain.mass: a table needs exactly one of value, pattern, taper, random, file "
     "(got 'value' and 'pattern')"),
    ("mass = {file = 'nowhere.npy'}", None),
    ("diameter = 0.01\nmaterial = 'steel'", 'chain.diameter: needs units = "si" (real spheres)'),
])
def test_wrong_values_name_their_key_and_index(chain, expected):
    alpha = "" if "alpha" in chain else "alpha = 1.5\n"
    lines = problems(HEAD + f"[chain]\nn = 4\nk = 1\n{alpha}{chain}\n")
    if expected is None:
        assert lines[0].startswith("chain.mass.file: no such file")
    else:
        assert expected in lines


def test_a_wrong_value_is_one_line_and_exit_2_without_traceback(tmp_path):
    config = tmp_path / "bad.toml"
    config.write_text(HEAD + "[chain]\nn = 4\nk = 1\nalpha = 1.5\nmass = [1, 1, -1, 1]\n")
    result = CliRunner().invoke(main, ["simulate", str(config), "-o", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert result.stderr.strip() == f"{config}: chain.mass[2]: must be > 0, got -1.0"
    assert "Traceback" not in result.output


# --- lines without a terminal state need t_end -------------------------------------------


@pytest.mark.parametrize("extra, why", [
    ("force = 0.1\n", "chain.force keeps doing work"),
    ("force = {value = 0.0, impurity = {at = 2, value = 1.0}}\n", "chain.force keeps doing work"),
    ("[walls.left]\n[walls.right]\n", "the line is held between two walls"),
])
def test_no_terminal_state_needs_t_end(extra, why):
    text = HEAD + f"[chain]\nn = 4\nk = 1\nalpha = 1.5\n{extra}"
    (line,) = [x for x in problems(text) if x.startswith("solver.t_end")]
    assert why in line and "no terminal state" in line
    parse_experiment(text + "[solver]\nt_end = 5.0\n", "toml")  # fine with a stop time


# --- SI: materials and Hertz -------------------------------------------------------------


def test_hertz_of_identical_spheres():
    for m in MATERIALS.values():
        d = 0.0254
        kappa = physics.hertz_stiffness(m.young, m.poisson, d / 2, m.young, m.poisson, d / 2)
        assert kappa == pytest.approx(m.young * math.sqrt(d) / (3 * (1 - m.poisson**2)),
                                      rel=1e-14)


def test_every_preset_cites_its_source():
    assert {"steel", "stainless_steel", "chrome_steel", "brass", "aluminium", "glass", "ptfe",
            "tungsten_carbide"} <= set(MATERIALS)
    for m in MATERIALS.values():
        assert "[" in m.source and m.young > 0 and 0 < m.poisson < 0.5 and m.density > 0


def test_si_cradle_masses_and_stiffnesses():
    steel = MATERIALS["steel"]
    line = line_of(HEAD + 'units = "si"\n[chain]\nn = 5\nk = 1\nspeed = 0.5\n'
                   'diameter = 0.0254\nmaterial = "steel"\n[walls.right]\nmaterial = "brass"\n')
    np.testing.assert_allclose(line.mass, steel.density * math.pi * 0.0254**3 / 6, rtol=1e-15)
    np.testing.assert_allclose(line.stiffness, steel.young * math.sqrt(0.0254)
                               / (3 * (1 - steel.poisson**2)), rtol=1e-14)
    np.testing.assert_array_equal(line.alpha, 1.5)
    np.testing.assert_array_equal(line.velocity, [0.5, 0, 0, 0, 0])
    brass = MATERIALS["brass"]
    e_star = 1 / ((1 - steel.poisson**2) / steel.young + (1 - brass.poisson**2) / brass.young)
    assert line.right.stiffness == pytest.approx(4 / 3 * e_star * math.sqrt(0.0127), rel=1e-14)


def test_si_mixed_materials_and_explicit_constants():
    line = line_of(HEAD + 'units = "si"\n[chain]\nn = 3\nvelocity = [1.0, 0.0, 0.0]\n'
                   'diameter = [0.01, 0.02, 0.01]\nyoung = 1e9\npoisson = 0.25\n'
                   'density = 1000\n')
    r1, r2 = 0.005, 0.01
    e_star = 1e9 / (2 * (1 - 0.25**2))
    assert line.stiffness[0] == pytest.approx(4 / 3 * e_star * math.sqrt(r1 * r2 / (r1 + r2)))
    assert line.mass[1] == pytest.approx(1000 * math.pi * 0.02**3 / 6)


@pytest.mark.parametrize("chain, expected", [
    ("diameter = 0.01\nmaterial = 'steel'\nstiffness = 1e9",
     "chain.stiffness: set by the material and diameter (Hertz, alpha = 3/2); give one or "
     "the other"),
    ("material = 'steel'", "chain.diameter: required with a material (m)"),
    ("diameter = 0.01\nmaterial = 'steel'\nyoung = 1e9",
     "chain.young: give chain.material or explicit constants, not both"),
    ("diameter = 0.01\nyoung = 1e9", "chain.poisson: required with explicit constants "
                                     "(or give chain.material)"),
    ("diameter = 0.01\nmaterial = ['steel', 'glass', 'wood']",
     "chain.material[2]: unknown material 'wood'"),
    ("diameter = 0.01\nmaterial = ['steel', 'glas', 'steel']",
     "chain.material[1]: unknown material 'glas' (did you mean 'glass'?)"),
    ("material = 'steel'\ndiameter = {random = 'uniform', low = 0.01, hi = 0.02}",
     "chain.diameter.hi: unknown key for a 'random' table (did you mean 'high'?)"),
])
def test_si_conflicts(chain, expected):
    lines = problems(HEAD + f'units = "si"\n[chain]\nn = 3\nk = 1\n{chain}\n')
    assert any(line.startswith(expected) for line in lines), lines


SI_CRADLE = '[chain]\nn = 3\nk = 1\nspeed = 0.5\ndiameter = 0.0254\nmaterial = "steel"\n'


@pytest.mark.parametrize("written", ["SI", "Si", "si"])
def test_units_in_any_case_are_the_same_units(written):
    # was: "SI" refused ("expected one of 'paper', 'si'")
    exp = parse_experiment(HEAD + f'units = "{written}"\n' + SI_CRADLE, "toml")
    (spec,) = exp.runs()
    assert exp.units == spec.units == "si"
    (canonical,) = parse_experiment(HEAD + 'units = "si"\n' + SI_CRADLE, "toml").runs()
    assert spec.config_hash == canonical.config_hash
    np.testing.assert_array_equal(spec.line.mass, canonical.line.mass)
    # and the line is still checked as an SI line
    assert problems(HEAD + f'units = "{written}"\n' + SI_CRADLE + "stiffness = 1e9\n") == [
        "chain.stiffness: set by the material and diameter (Hertz, alpha = 3/2); give one "
        "or the other"]
    assert parse_experiment(HEAD + 'units = "Paper"\n[chain]\nn = 3\nk = 1\nalpha = 1\n',
                            "toml").units == "paper"


def test_units_must_be_known():
    assert problems(HEAD + 'units = "metric"\n[chain]\nn = 3\nk = 1\nalpha = 1\n') == [
        "units: expected one of 'paper', 'si' (in any case), got 'metric'"]
    assert problems(HEAD + 'units = "SIS"\n[chain]\nn = 3\nk = 1\nalpha = 1\n') == [
        "units: expected one of 'paper', 'si' (in any case), got 'SIS' (did you mean 'si'?)"]


# --- one ball: no contact between balls ---------------------------------------------------


def test_one_ball_against_a_wall_needs_only_the_walls_exponent():
    # was: refused with "chain.alpha: required", though one ball has no contact with
    # another; the wall's own alpha is all its contact needs
    text = HEAD + "[chain]\nn = 1\nk = 1\n[walls.right]\nalpha = 1.0\ngap = 0.5\n"
    (spec,) = parse_experiment(text, "toml").runs()
    assert spec.line.right == Wall(1.0, 1.0, 0.5) and spec.line.alpha.size == 0
    assert spec.alpha == 1.0
    # linear wall: it comes back at its speed after half a period, pi
    from chainrun.solver import simulate

    sol = simulate(spec.line)
    assert sol.terminal and sol.final_velocity[0] == pytest.approx(-1.0, abs=1e-12)
    assert sol.end_time == pytest.approx(0.5 + math.pi, abs=1e-10)


def test_one_ball_wall_takes_the_chains_exponent_or_asks_for_its_own():
    # was: a wall next to one ball took alpha = 3/2 whatever chain.alpha said
    text = HEAD + "[chain]\nn = 1\nk = 1\nalpha = 1.0\n[walls.left]\n[walls.right]\n" \
                  "[solver]\nt_end = 10.0\n"
    line = line_of(text)
    assert line.left.alpha == line.right.alpha == 1.0
    assert problems(HEAD + "[chain]\nn = 1\nk = 1\n[walls.left]\nalpha = 2.0\n"
                    "[walls.right]\n[solver]\nt_end = 10.0\n") == [
        "walls.right.alpha: required: a line of one ball has no contact whose exponent the "
        "wall could take (or give chain.alpha)"]


def test_one_free_ball_needs_no_exponent():
    (spec,) = parse_experiment(HEAD + "[chain]\nn = 1\nk = 1\n", "toml").runs()
    assert spec.line.n == 1 and math.isnan(spec.alpha)
    # two balls do touch: their contact needs its law
    assert problems(HEAD + "[chain]\nn = 2\nk = 1\n") == ["chain.alpha: required"]
    swept = HEAD + '[chain]\nn = 1\nk = 1\n[sweep]\n"chain.n" = [1, 3]\n'
    assert problems(swept) == ["sweep (n=3): chain.alpha: required"]


# --- precompression ----------------------------------------------------------------------


def _contact_forces(line: Line) -> np.ndarray:
    """F_0 (left wall, or 0), F_1..F_{N-1}, F_N (right wall, or 0) at the initial state."""
    x = line.position
    inner = np.clip(x[:-1] - x[1:] - line.gap, 0, None) ** line.alpha * line.stiffness
    left = 0.0 if line.left is None else line.left.stiffness * max(
        -x[0] - line.left.gap, 0.0) ** line.left.alpha
    right = 0.0 if line.right is None else line.right.stiffness * max(
        x[-1] - line.right.gap, 0.0) ** line.right.alpha
    return np.concatenate(([left], inner, [right]))


@pytest.mark.parametrize("k", [0, 1, 3])
def test_precompressed_balls_are_in_equilibrium(k):
    rng = np.random.default_rng(k)
    n = 12
    velocity = np.zeros(n)
    velocity[:k] = 1.0
    line = Line.make(n, mass=rng.uniform(0.5, 2, n), stiffness=rng.uniform(0.5, 2, n - 1),
                     alpha=rng.choice([1.0, 1.5, 2.5], n - 1), gap=rng.uniform(0, 0.1, n - 1),
                     velocity=velocity, right=Wall(3.0, 1.5, 0.05))
    load = 0.7
    p = precompress(line, load)
    assert strikers(p) == k
    F = _contact_forces(p)
    net = F[:-1] - F[1:] + p.force  # F_{j-1} - F_j + f_j for every ball
    np.testing.assert_allclose(net[k:], 0.0, atol=1e-14)
    np.testing.assert_allclose(F[k + 1:], load, rtol=1e-14)
    # the strikers meet ball K+1 as without the load
    if k:
        np.testing.assert_array_equal(p.position[:k], p.position[k])
    assert not p.has_terminal_state


def test_precompression_needs_a_wall_and_t_end():
    text = HEAD + "[chain]\nn = 4\nk = 1\nalpha = 1.5\nprecompression = 1.0\n"
    lines = problems(text + "[solver]\nt_end = 1.0\n")
    assert lines == ["chain.precompression: precompression needs a right wall to push against"]
    lines = problems(text + "[walls.right]\n")
    assert lines == ["solver.t_end: required: chain.precompression keeps pushing, so the run "
                     "has no terminal state"]
    line = line_of(text + "[walls.right]\n[solver]\nt_end = 1.0\n")
    assert line.force[1] == 1.0 and line.position[-1] == 1.0


def test_precompression_between_two_walls_loads_every_contact():
    rng = np.random.default_rng(7)
    n = 9
    line = Line.make(n, mass=rng.uniform(0.5, 2, n), stiffness=rng.uniform(0.5, 2, n - 1),
                     alpha=rng.choice([1.0, 1.5, 2.5], n - 1), gap=rng.uniform(-0.05, 0.1, n - 1),
                     k=0, left=Wall(2.0, 1.0, 0.3), right=Wall(3.0, 1.5, 0.05))
    load = 0.7
    p = precompress(line, load)
    F = _contact_forces(p)
    np.testing.assert_allclose(F, load, rtol=1e-14)  # both walls' contacts included
    assert not np.any(p.force) and not np.any(p.velocity)
    # the balls sit where the one-wall precompression puts them; only the left wall moves
    one = precompress(dataclasses.replace(line, left=None), load)
    np.testing.assert_array_equal(p.position, one.position)
    assert p.left.stiffness == 2.0 and p.left.alpha == 1.0 and p.right == line.right
    assert not p.has_terminal_state


def test_precompression_between_two_walls_from_a_file():
    text = (HEAD + "[chain]\nn = 4\nk = 0\nalpha = 1.5\nprecompression = 2.0\n"
            "[walls.left]\n[walls.right]\n")
    assert problems(text) == ["solver.t_end: required: the line is held between two walls, "
                              "so the run has no terminal state"]
    line = line_of(text + "[solver]\nt_end = 1.0\n")
    np.testing.assert_allclose(_contact_forces(line), 2.0, rtol=1e-14)
    assert not np.any(line.force)
    # strikers cannot be held at rest; the left wall's place is the load's to set
    striking = text.replace("k = 0", "k = 1") + "[solver]\nt_end = 1.0\n"
    assert problems(striking) == [
        "chain.precompression: precompression between two walls holds every ball at rest "
        "in its static state: the line must start at rest (k = 0); ball 1 moves"]
    placed = text.replace("[walls.left]\n", "[walls.left]\ngap = 0.1\n")
    assert problems(placed + "[solver]\nt_end = 1.0\n") == [
        "walls.left.gap: set by chain.precompression between two walls (the left wall is "
        "placed where every contact carries the load); leave it out"]


def test_a_line_at_rest_is_terminal_at_once():
    (spec,) = parse_experiment(HEAD + "[chain]\nn = 5\nk = 0\nalpha = 1.5\n", "toml").runs()
    assert spec.k == 0 and strikers(spec.line) == 0
    assert spec.line.has_terminal_state and not np.any(spec.line.velocity)


# --- paper configs stay as they were; sweeps of new keys --------------------------------


def test_paper_config_has_the_paper_line_and_its_old_hash():
    (spec,) = parse_experiment(HEAD + "[chain]\nn = 5\nk = 2\nalpha = 1.5\n", "toml").runs()
    assert spec.is_paper and spec.units == "paper"
    assert spec.config["chain"] == {"n": 5, "k": 2, "alpha": 1.5} and "walls" not in spec.config
    line = spec.line
    assert line.is_paper and line.n == 5 and strikers(line) == 2


def test_each_combination_is_validated_and_its_line_built_once(monkeypatch):
    text = (HEAD + "[chain]\nn = 6\nk = 1\nalpha = 1.5\nmass = {random = \"uniform\", "
            "low = 0.5, high = 1.5, seed = 1}\nrestitution = 0.9\ndamping_law = \"tsuji\"\n"
            "[walls.right]\n[output]\ntimes = [0.0, 1.0]\n[sweep]\nreplicas = 3\n"
            "\"solver.rtol\" = [1e-10, 1e-12]\n")
    exp = parse_experiment(text, "toml")
    import chainrun.config.run as run
    from chainrun.config import Chain, SolverSettings, Walls

    def again(*args, **kwargs):
        raise AssertionError("checked or built again")

    monkeypatch.setattr(run, "line_of", again)
    for model in (Chain, Walls, SolverSettings):
        monkeypatch.setattr(model, "model_validate", again)
    specs = exp.runs()
    assert len(specs) == 6 and not any(s.is_paper for s in specs)
    lines = [s.line for s in specs]  # carried from the check, not built again
    assert specs[0].for_check().line is lines[0]
    assert len({float(line.mass[0]) for line in lines}) == 3


def test_sweeps_of_new_keys():
    exp = parse_experiment(HEAD + "[chain]\nn = 4\nk = 1\nalpha = 1.5\n[walls.right]\n"
                           "[solver]\nt_end = 3.0\n[sweep]\n\"chain.speed\" = [0.5, 2.0]\n"
                           "walls.right.gap = [0.0, 0.1]\nchain.precompression = [1.0]\n",
                           "toml")
    specs = exp.runs()
    assert [s.run_id for s in specs] == [
        "speed=0.5_right_gap=0.0_precompression=1.0", "speed=0.5_right_gap=0.1_precompression=1.0",
        "speed=2.0_right_gap=0.0_precompression=1.0", "speed=2.0_right_gap=0.1_precompression=1.0"]
    assert len({s.config_hash for s in specs}) == 4
    last = specs[-1].line
    assert last.velocity[0] == 2.0 and last.right.gap == 0.1 and last.force[1] == 1.0
    assert specs[-1].config["walls"] == {"right": {"gap": 0.1}}


def test_a_sweep_names_the_combination_that_fails():
    lines = problems(HEAD + "[chain]\nn = 4\nk = 1\nalpha = 1.5\n[sweep]\n"
                     "\"chain.force\" = [0.0, 1.0]\n")
    assert lines == ["sweep (force=1.0): solver.t_end: required: chain.force keeps doing work, "
                     "so the run has no terminal state"]


# --- the run file records the model ------------------------------------------------------


def _fake_solution(spec) -> Solution:
    n = spec.n
    diag = Diagnostics(steps=1, rejected_steps=0, events=0, momentum_error=0.0,
                       energy_error=0.0, energy_correction=0.0, wall_time=0.0, max_window=1,
                       rtol=spec.rtol, velocity_floor=1e-12)
    z = np.zeros(n)
    return Solution(n=n, k=spec.k, alpha=spec.alpha, outcome=Outcome.STOP_TIME, message="m",
                    end_time=1.0, terminal=False, final_position=z, final_velocity=z,
                    separation_time=z, separation_velocity=z, event_time=np.zeros(0),
                    event_contact=np.zeros(0, np.int64), event_kind=np.zeros(0, np.int8),
                    times=np.asarray(spec.times), positions=np.zeros((len(spec.times), n)),
                    velocities=np.zeros((len(spec.times), n)), diagnostics=diag)


def test_si_run_file_records_model_units_and_scales(tmp_path):
    (spec,) = parse_experiment(HEAD + 'units = "si"\n[chain]\nn = 5\nk = 1\nspeed = 0.5\n'
                               'diameter = 0.0254\nmaterial = "steel"\n[walls.right]\n'
                               'material = "steel"\n[output]\ntimes = [0.0, 1e-5]\n',
                               "toml").runs()
    path = tmp_path / "run.h5"
    runner.write_run(path, spec, _fake_solution(spec), velocity_floor=1e-12)
    run = store.read_run(path)
    assert run.units == "si"
    np.testing.assert_array_equal(run.model["mass"], spec.line.mass)
    np.testing.assert_array_equal(run.model["stiffness"], spec.line.stiffness)
    assert run.model["walls"]["right"]["stiffness"] == spec.line.right.stiffness
    assert "left" not in run.model["walls"]
    scales = spec.line.scales()
    assert run.model["scales"]["time"] == scales.time
    with h5py.File(path) as h5:
        assert h5["particles/chain/position/value"].attrs["unit"] == "m"
        assert h5["particles/chain/velocity/value"].attrs["unit"] == "m/s"
        assert h5["particles/chain/position/time"].attrs["unit"] == "s"
        assert h5["model/mass"].attrs["unit"] == "kg"
        assert h5["model/force"].attrs["unit"] == "N"


def test_old_run_files_without_a_model_still_read(tmp_path):
    (spec,) = parse_experiment(HEAD + "[chain]\nn = 3\nk = 1\nalpha = 1.5\n", "toml").runs()
    path = tmp_path / "run.h5"
    runner.write_run(path, spec, _fake_solution(spec), velocity_floor=1e-12)
    with h5py.File(path, "a") as h5:
        del h5["model"]
    run = store.read_run(path)
    assert run.model is None and run.units == "paper"


# --- the example configs -----------------------------------------------------------------


@pytest.mark.parametrize("config", sorted(EXAMPLES.glob("*.toml")), ids=lambda p: p.stem)
def test_example_configs(config, tmp_path):
    specs = load_experiment(config).runs()
    for spec in specs:
        assert spec.line.n == spec.n
    from chainrun.solver import simulate

    spec = specs[0]
    sol = simulate(spec.line, spec.times[:2], t_end=spec.t_end, max_events=10**6)
    assert sol.outcome.ok


def test_stored_contact_forces_follow_the_lines_law(tmp_path):
    # The forces a run file gives from its positions (the views draw them) use each
    # contact's stiffness, exponent and gap: at the sensor's sample times they equal the
    # forces the solver sampled on its own step.
    from helpers import simulate_text

    from chainrun.store import read_run

    out = simulate_text(tmp_path, """
name = "forces"
units = "si"
[chain]
n = 6
k = 1
speed = 0.4
diameter = [0.02, 0.02, 0.01, 0.02, 0.03, 0.02]
material = ["steel", "steel", "brass", "steel", "glass", "steel"]
gap = [0.0, 1.0e-6, 0.0, 2.0e-6, 0.0]
[walls.right]
material = "steel"
gap = 1.0e-6
[output]
times = {start = 0.0, stop = 4.0e-4, step = 2.0e-6}
sensors = [3, 5]
sensor_dt = 2.0e-6
""")
    run = read_run(out / "run.h5")
    forces = run.contact_forces()
    assert forces.shape == (201, 5)
    m = min(len(run.sensor_time), len(run.times))  # (samples go on to the run's end)
    assert m > 50
    np.testing.assert_allclose(run.sensor_time[:m], run.times[:m], rtol=1e-12)
    scale = np.max(np.abs(forces))
    for s, ball in enumerate((3, 5)):
        for side in (0, 1):
            np.testing.assert_allclose(forces[:m, ball - 2 + side],
                                       run.sensor_force[:m, s, side], rtol=1e-9,
                                       atol=1e-9 * scale)
    assert np.max(forces) > 0.0
    strided = run.contact_forces(stride=2)
    np.testing.assert_array_equal(strided, forces[:, ::2])
