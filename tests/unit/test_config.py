"""Experiment files: parsing, validation messages, sweep expansion (chainrun.config)."""

from __future__ import annotations

import hashlib
import json
import textwrap
from pathlib import Path

import numpy as np
import pytest

from chainrun.config import (
    Chain,
    Experiment,
    Output,
    RunSpec,
    SolverSettings,
    load_experiment,
    parse_experiment,
)
from chainrun.errors import ConfigError
from chainrun.solver import DEFAULT_RTOL

CONFIGS = Path(__file__).resolve().parents[2] / "configs"

BASE_TOML = """\
name = "demo"
description = "a demo"

[chain]
n = 5
k = 1
alpha = 1.5

[output]
times = [0.0, 5.0, 10.0]

[solver]
t_end = 100.0
rtol = 1e-10
max_events = 1000
"""

BASE_YAML = """\
name: demo
description: a demo
chain:
  n: 5
  k: 1
  alpha: 1.5
output:
  times: [0, 5.0, 10]
solver:
  t_end: 100
  rtol: 1.0e-10
  max_events: 1000
"""


def toml(text: str) -> Experiment:
    return parse_experiment(textwrap.dedent(text), "toml")


def problems(text: str, fmt: str = "toml") -> list[str]:
    """The problem lines ``text`` is refused with."""
    with pytest.raises(ConfigError) as info:
        parse_experiment(textwrap.dedent(text), fmt, source="test.cfg")
    assert info.value.source == "test.cfg"
    assert all("\n" not in line for line in info.value.problems)
    return info.value.problems


def chain_toml(chain: str, extra: str = "") -> str:
    """A minimal file with the given ``[chain]`` body and more tables after it."""
    return f'name = "x"\n[chain]\n{textwrap.dedent(chain)}\n{textwrap.dedent(extra)}'


# --- valid files -------------------------------------------------------------------------


def test_toml_and_yaml_give_equal_experiments():
    a = parse_experiment(BASE_TOML, "toml")
    b = parse_experiment(BASE_YAML, "yaml")
    assert a == b
    assert hash(a) == hash(b)
    assert a.source_text == BASE_TOML and b.source_text == BASE_YAML
    assert a.chain == Chain(n=5, k=1, alpha=1.5)
    assert a.output == Output(times=(0.0, 5.0, 10.0))
    assert a.solver == SolverSettings(t_end=100.0, rtol=1e-10, max_events=1000)
    assert isinstance(a.chain.alpha, float) and isinstance(b.solver.t_end, float)
    assert all(isinstance(t, float) for t in b.output.times)


def test_models_are_frozen():
    exp = parse_experiment(BASE_TOML, "toml")
    with pytest.raises(Exception):
        exp.name = "other"  # type: ignore[misc]
    with pytest.raises(Exception):
        exp.chain.n = 3  # type: ignore[misc]


def test_defaults_when_output_and_solver_are_omitted():
    exp = toml(chain_toml("n = 3\nk = 1\nalpha = 1"))
    assert exp.description == ""
    assert exp.output.times == ()
    assert exp.solver == SolverSettings(t_end=None, rtol=DEFAULT_RTOL, max_events=None)
    assert exp.sweep == {}
    (run,) = exp.runs()
    assert run.run_id == "run"
    assert run.overrides == {}
    assert run.times.dtype == np.float64 and run.times.shape == (0,)
    assert run.config["solver"] == {"t_end": None, "rtol": DEFAULT_RTOL, "max_events": None}


def test_range_times_expand_inclusively():
    exp = toml(chain_toml("n = 3\nk = 1\nalpha = 1", "[output]\ntimes = {start = 0, stop = 60, step = 5}"))
    assert exp.output.times == tuple(float(t) for t in range(0, 61, 5))
    # stop is reached despite rounding: 0.3 / 0.1 = 2.9999999999999996
    exp = toml(chain_toml("n = 3\nk = 1\nalpha = 1", "[output]\ntimes = {start = 0, stop = 0.3, step = 0.1}"))
    assert len(exp.output.times) == 4 and exp.output.times[-1] == 0.3
    # a stop between grid points is not passed
    exp = toml(chain_toml("n = 3\nk = 1\nalpha = 1", "[output]\ntimes = {start = 1, stop = 2.9, step = 1}"))
    assert exp.output.times == (1.0, 2.0)


def test_run_without_sweep():
    (run,) = parse_experiment(BASE_TOML, "toml").runs()
    assert isinstance(run, RunSpec)
    assert (run.experiment, run.run_id, run.n, run.k, run.alpha) == ("demo", "run", 5, 1, 1.5)
    assert (run.t_end, run.rtol, run.max_events) == (100.0, 1e-10, 1000)
    np.testing.assert_array_equal(run.times, [0.0, 5.0, 10.0])
    assert run.config == {
        "name": "demo",
        "description": "a demo",
        "chain": {"n": 5, "k": 1, "alpha": 1.5},
        "output": {"times": [0.0, 5.0, 10.0]},
        "solver": {"t_end": 100.0, "rtol": 1e-10, "max_events": 1000},
    }
    canonical = json.dumps(run.config, sort_keys=True, separators=(",", ":"))
    assert run.config_hash == hashlib.sha256(canonical.encode()).hexdigest()
    assert run.source_text == BASE_TOML


def test_sweep_order_run_ids_and_hashes():
    exp = toml(
        """\
        name = "grid"
        [chain]
        n = 100
        alpha = 1.5
        [sweep]
        "chain.n" = [100, 50]
        "chain.k" = [1, 2, 3]
        """
    )
    runs = exp.runs()
    assert [r.run_id for r in runs] == [
        "n=100_k=1", "n=100_k=2", "n=100_k=3", "n=50_k=1", "n=50_k=2", "n=50_k=3",
    ]
    assert [(r.n, r.k) for r in runs] == [(100, 1), (100, 2), (100, 3), (50, 1), (50, 2), (50, 3)]
    assert runs[2].overrides == {"chain.n": 100, "chain.k": 3}
    assert "sweep" not in runs[0].config
    assert runs[4].config["chain"] == {"n": 50, "k": 2, "alpha": 1.5}
    hashes = [r.config_hash for r in runs]
    assert len(set(hashes)) == len(hashes)
    assert hashes == [r.config_hash for r in exp.runs()]  # stable
    # a swept key left out of its table takes the first swept value in the experiment
    assert exp.chain.k == 1


def test_sweep_float_and_solver_keys_and_unquoted_dotted_keys():
    exp = toml(
        """\
        name = "s"
        [chain]
        n = 5
        k = 1
        alpha = 1
        [sweep]
        chain.alpha = [1, 1.5]
        solver.rtol = [1e-10]
        """
    )
    assert exp.sweep == {"chain.alpha": (1.0, 1.5), "solver.rtol": (1e-10,)}
    assert [r.run_id for r in exp.runs()] == ["alpha=1.0_rtol=1e-10", "alpha=1.5_rtol=1e-10"]
    assert exp.runs()[1].rtol == 1e-10


def test_sweep_hash_matches_an_equivalent_single_run():
    swept = toml(chain_toml("n = 5\nk = 1\nalpha = 1.5", '[sweep]\n"chain.k" = [2]'))
    single = toml(chain_toml("n = 5\nk = 2\nalpha = 1.5"))
    assert swept.runs()[0].config_hash == single.runs()[0].config_hash


def test_shipped_configs():
    table1 = load_experiment(CONFIGS / "table1.toml")
    assert table1.name == "table1"
    assert table1.chain.n == 5 and table1.chain.alpha == 1.5
    assert "Table 1" in table1.description
    runs = table1.runs()
    assert [r.run_id for r in runs] == ["k=1", "k=2", "k=3", "k=4"]
    assert len(runs[0].times) == 61 and runs[0].times[-1] == 30.0
    assert runs[0].source_text == (CONFIGS / "table1.toml").read_text()

    example = load_experiment(CONFIGS / "example.yaml")
    assert example.chain == Chain(n=20, k=1, alpha=1.5)
    assert len(example.runs()) == 1


# --- problems, one line each ---------------------------------------------------------------


def test_unknown_key_suggests():
    assert problems(chain_toml("n = 5\nk = 1\nalhpa = 1.5")) == [
        "chain.alpha: required",
        "chain.alhpa: unknown key (did you mean 'alpha'?)",
    ]
    assert problems(chain_toml("n = 5\nk = 1\nalpha = 1.5", "[solvr]\nrtol = 1e-9")) == [
        "solvr: unknown key (did you mean 'solver'?)",
    ]


@pytest.mark.parametrize(
    "chain, expected",
    [
        ("n = 5\nk = 6\nalpha = 1.5", "chain.k: must be <= chain.n (5), got 6"),
        ("n = 0\nk = 1\nalpha = 1.5", "chain.n: must be >= 1, got 0"),
        ("n = 5\nk = -1\nalpha = 1.5", "chain.k: must be >= 0, got -1"),
        ("n = 5\nk = 1\nalpha = 0.5", "chain.alpha: must be >= 1, got 0.5"),
        ('n = "five"\nk = 1\nalpha = 1.5', "chain.n: expected an integer, got 'five'"),
        ('n = "3"\nk = 1\nalpha = 1.5', "chain.n: expected an integer, got '3'"),
        ("n = 2.5\nk = 1\nalpha = 1.5", "chain.n: expected an integer, got 2.5"),
        ("n = 5.0\nk = 1\nalpha = 1.5", "chain.n: expected an integer, got 5.0"),
        ("n = true\nk = 1\nalpha = 1.5", "chain.n: expected an integer, got True"),
        ("n = 5\nk = 1\nalpha = true", "chain.alpha: expected a number, got True"),
        ("n = 5\nk = 1\nalpha = nan", "chain.alpha: must be finite, got nan"),
        ("n = 5\nk = 1\nalpha = inf", "chain.alpha: must be finite, got inf"),
        ("n = 5\nalpha = 1.5", "chain.k: required"),
    ],
)
def test_chain_problems(chain, expected):
    assert problems(chain_toml(chain)) == [expected]


@pytest.mark.parametrize(
    "solver, expected",
    [
        ("t_end = 0", "solver.t_end: must be > 0, got 0.0"),
        ("t_end = inf", "solver.t_end: must be finite, got inf"),
        ("rtol = 1e-2", "solver.rtol: must be <= 0.001, got 0.01"),
        ("rtol = 1e-16", "solver.rtol: must be >= 1e-15, got 1e-16"),
        ("max_events = 0", "solver.max_events: must be > 0, got 0"),
        ("max_events = 1e6", "solver.max_events: expected an integer, got 1000000.0"),
    ],
)
def test_solver_problems(solver, expected):
    assert problems(chain_toml("n = 5\nk = 1\nalpha = 1", f"[solver]\n{solver}")) == [expected]


@pytest.mark.parametrize(
    "times, expected",
    [
        ("[-1.0, 2.0]", ["output.times: must be non-negative, got -1.0 at position 0"]),
        ("[0.0, 10.0, 5.0]", ["output.times: must be non-decreasing, got 5.0 after 10.0 (position 2)"]),
        ('[0.0, "x", nan]', [
            "output.times: expected a number, got 'x' at position 1",
            "output.times: must be finite, got nan at position 2",
        ]),
        ("5", ["output.times: expected a list of times or a table {start, stop, step}, got 5"]),
        ("{start = 0, stop = 10, step = 0}", ["output.times.step: must be > 0, got 0.0"]),
        ("{start = 0, stop = 10, step = -1}", ["output.times.step: must be > 0, got -1.0"]),
        ("{start = 5, stop = 1, step = 1}", ["output.times.stop: must be >= output.times.start (5.0), got 1.0"]),
        ("{start = 0, stop = 10}", ["output.times.step: required"]),
        ("{start = 0, stop = 10, step = 1, steps = 2}", ["output.times.steps: unknown key (did you mean 'step'?)"]),
    ],
)
def test_output_problems(times, expected):
    text = chain_toml("n = 5\nk = 1\nalpha = 1", f"[output]\ntimes = {times}")
    assert problems(text) == expected


def test_many_problems_are_reported_at_once():
    text = """\
        name = "../x"
        colour = "red"
        [chain]
        n = 0
        k = 1
        alhpa = 1.5
        [output]
        times = [-1.0, 10.0, 5.0]
        [solver]
        rtol = 1.0
        [sweep]
        "chain.kk" = [1]
        """
    assert problems(text) == [
        "name: must be a folder name of 1-100 letters, digits, '.', '_' or '-', "
        "not starting with '.', got '../x'",
        "chain.n: must be >= 1, got 0",
        "chain.alpha: required",
        "chain.alhpa: unknown key (did you mean 'alpha'?)",
        "output.times: must be non-negative, got -1.0 at position 0",
        "output.times: must be non-decreasing, got 5.0 after 10.0 (position 2)",
        "solver.rtol: must be <= 0.001, got 1.0",
        "colour: unknown key",
        "sweep: unknown key 'chain.kk' (did you mean 'chain.k'?)",
    ]


def test_range_and_order_checks_do_not_hide_each_other():
    assert problems(chain_toml("n = 5\nk = 6\nalpha = 0.5")) == [
        "chain.k: must be <= chain.n (5), got 6",
        "chain.alpha: must be >= 1, got 0.5",
    ]


@pytest.mark.parametrize("name", ["../x", "/abs", "", ".hidden", "a b", "x" * 101, "a/b"])
def test_unsafe_names_are_refused(name):
    (line,) = problems(chain_toml("n = 5\nk = 1\nalpha = 1").replace('"x"', json.dumps(name), 1))
    assert line.startswith("name: must be a folder name")
    assert line.endswith(f"got {name!r}") or len(name) > 100  # long values are shortened


def test_name_must_be_a_string_and_is_required():
    assert problems('name = 5\n[chain]\nn = 1\nk = 1\nalpha = 1') == ["name: expected a string, got 5"]
    assert problems('[chain]\nn = 1\nk = 1\nalpha = 1') == ["name: required"]
    assert problems('name = "x"') == ["chain: required"]
    assert problems('name = "x"\nchain = 5') == ["chain: expected a table, got 5"]


# --- sweep problems ------------------------------------------------------------------------


@pytest.mark.parametrize(
    "sweep, expected",
    [
        ('"chain.kk" = [1]', ["sweep: unknown key 'chain.kk' (did you mean 'chain.k'?)"]),
        ('"chain.k" = []', ["sweep.chain.k: must list at least one value"]),
        ('"chain.k" = 2', ["sweep.chain.k: expected a list of values, got 2"]),
        ('"chain.k" = [1, 2.5]', ["sweep.chain.k: expected an integer, got 2.5 at position 1"]),
        ('"chain.alpha" = [1.5, 1.5]', ["sweep.chain.alpha: duplicate value 1.5 at position 1"]),
        ('"chain.alpha" = [1, 1.0]', ["sweep.chain.alpha: duplicate value 1.0 at position 1"]),
        ('"solver.t_end" = [nan]', ["sweep.solver.t_end: must be finite, got nan at position 0"]),
    ],
)
def test_sweep_table_problems(sweep, expected):
    assert problems(chain_toml("n = 5\nk = 1\nalpha = 1", f"[sweep]\n{sweep}")) == expected


def test_invalid_sweep_combinations_are_named():
    text = """\
        name = "grid"
        [chain]
        alpha = 1.5
        [sweep]
        "chain.n" = [3, 5]
        "chain.k" = [1, 4, 6]
        """
    assert problems(text) == [
        "sweep (n=3, k=4): chain.k: must be <= chain.n (3), got 4",
        "sweep (n=3, k=6): chain.k: must be <= chain.n (3), got 6",
        "sweep (n=5, k=6): chain.k: must be <= chain.n (5), got 6",
    ]


def test_sweep_value_out_of_range_and_base_problem_together():
    text = chain_toml("n = 5\nk = 1\nalpha = 0.5", '[sweep]\n"solver.rtol" = [1e-12, 0.1]')
    assert problems(text) == [
        "chain.alpha: must be >= 1, got 0.5",
        "sweep (rtol=0.1): solver.rtol: must be <= 0.001, got 0.1",
    ]


def test_a_swept_base_value_is_overridden_not_checked():
    exp = toml(chain_toml("n = 5\nk = 9\nalpha = 1", '[sweep]\n"chain.k" = [1, 2]'))
    assert [r.k for r in exp.runs()] == [1, 2]


# --- syntax and files ----------------------------------------------------------------------


def test_toml_syntax_error_names_its_line():
    (line,) = problems('name = "x"\n[chain]\nn = \n')
    assert line.startswith("line 3: ")
    assert "Invalid value" in line and "(at line" not in line


def test_yaml_syntax_error_names_its_line():
    (line,) = problems("name: x\nchain:\n  n: 3\n   k: 1\n", "yaml")
    assert line.startswith("line 4: ")
    (line,) = problems("name: x\nchain: [1,\n", "yaml")
    assert line.startswith("line 3: ")


@pytest.mark.parametrize(
    "text, expected",
    [
        ("- 1\n- 2\n", "top level: expected a table of keys, got list [1, 2]"),
        ("", "top level: expected a table of keys, got an empty file"),
        ("just text\n", "top level: expected a table of keys, got str 'just text'"),
        # an experiment in TOML read as YAML is one string
        ('name = "c"\n[chain]\nn = 5\n', "top level: expected a table of keys, got str "
         "'name = \"c\" [chain] n = 5' (this looks like TOML: name the file .toml)"),
    ],
)
def test_top_level_must_be_a_mapping(text, expected):
    assert problems(text, "yaml") == [expected]


def test_yaml_exponent_without_a_dot_is_explained():
    text = BASE_YAML.replace("1.0e-10", "1e-10")
    (line,) = problems(text, "yaml")
    assert line.startswith("solver.rtol: expected a number, got '1e-10' (")
    assert "1.0e-12" in line


def test_missing_file(tmp_path):
    with pytest.raises(ConfigError) as info:
        load_experiment(tmp_path / "absent.toml")
    assert info.value.problems == ["no such file"]
    assert info.value.source == str(tmp_path / "absent.toml")


def test_unknown_extension(tmp_path):
    path = tmp_path / "exp.json"
    path.write_text("{}")
    with pytest.raises(ConfigError) as info:
        load_experiment(path)
    assert info.value.problems == ["unknown file type '.json' (expected .toml, .yaml or .yml)"]


@pytest.mark.parametrize("suffix, text", [(".toml", BASE_TOML), (".yaml", BASE_YAML), (".yml", BASE_YAML)])
def test_load_from_each_extension(tmp_path, suffix, text):
    path = tmp_path / f"demo{suffix}"
    path.write_text(text)
    exp = load_experiment(path)
    assert exp == parse_experiment(BASE_TOML, "toml")
    assert exp.source_text == text
    assert exp.runs()[0].source_text == text


def test_error_from_a_file_names_the_file(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(chain_toml("n = 0\nk = 1\nalpha = 1"))
    with pytest.raises(ConfigError) as info:
        load_experiment(path)
    assert str(info.value) == f"{path}: chain.n: must be >= 1, got 0"


def test_module_is_free_of_click():
    package = Path(__file__).resolve().parents[2] / "chainrun" / "config"
    for path in package.glob("*.py"):
        assert "click" not in path.read_text(), path


def test_a_run_file_given_for_an_experiment_is_named_as_such(tmp_path):
    path = tmp_path / "run.h5"
    path.write_bytes(b"")
    with pytest.raises(ConfigError) as info:
        load_experiment(path)
    assert info.value.problems == [
        "unknown file type '.h5' (a run file or analysis file: an experiment file is "
        "expected here) (expected .toml, .yaml or .yml)"]
