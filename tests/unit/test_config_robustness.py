"""Experiment files at the edges: what fuzzing found, names, run ids and size limits.

Each test of the first part is a case ``tests/property/test_fuzz.py`` found escaping
``parse_experiment`` as another exception than ``ConfigError`` (or hanging), kept as
a plain regression test.
"""

from __future__ import annotations

import math
import os
import re
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from chainrun.config import (
    MAX_RUNS,
    MAX_TEXT,
    MAX_VALUES,
    MAX_SNAPSHOTS,
    MAX_ALPHA,
    SWEEPABLE_KEYS,
    Chain,
    Experiment,
    Output,
    SolverSettings,
    load_experiment,
    parse_experiment,
)
from chainrun.errors import ConfigError

CHAIN = 'name = "x"\n[chain]\nn = 3\nk = 1\nalpha = 1.5\n'
YCHAIN = "name: x\nchain: {n: 3, k: 1, alpha: 1.5}\n"


def problems(text: str, fmt: str = "toml") -> list[str]:
    with pytest.raises(ConfigError) as info:
        parse_experiment(text, fmt, source="t")
    for line in info.value.problems:
        assert len(line.splitlines()) == 1 and "\n" not in line, repr(line)
    return info.value.problems


# --- what fuzzing found ---------------------------------------------------------------------


def test_an_integer_too_large_for_a_float():
    # was: OverflowError from float(int)
    assert problems(CHAIN.replace("alpha = 1.5", "alpha = " + "9" * 400)) == [
        "chain.alpha: must be finite, got <an integer of about 400 digits>"]
    assert problems(CHAIN + "[output]\ntimes = [0, " + "9" * 400 + "]\n") == [
        "output.times: must be finite, got <an integer of about 400 digits> at position 1"]


@pytest.mark.parametrize("key, table", [("n", "chain"), ("max_events", "solver")])
def test_integers_must_fit_in_int64(key, table):
    # was: accepted, then OverflowError in numpy or HDF5 (int64) during the run
    text = CHAIN + ("[solver]\n" if table == "solver" else "")
    text = text.replace("n = 3", f"n = {2**63}") if key == "n" else text + f"max_events = {2**63}\n"
    assert problems(text) == [
        f"{table}.{key}: must be a 64-bit integer (at most 2**63 - 1), got {2**63}"]
    ok = CHAIN.replace("n = 3", f"n = {2**63 - 1}")
    assert parse_experiment(ok, "toml").chain.n == 2**63 - 1


def test_integers_beyond_python_conversion_limit():
    # was: ValueError "Exceeds the limit (4300 digits) for integer string conversion"
    digits = sys.get_int_max_str_digits() + 1
    assert problems(CHAIN.replace("n = 3", "n = " + "9" * digits)) == [
        f"cannot read a value (an integer of more than {digits - 1} digits)"]
    (line,) = problems(YCHAIN.replace("n: 3", "n: " + "9" * digits), "yaml")
    assert line.startswith("line 2: cannot read '999") and line.endswith("(column 12)")
    # hexadecimal has no such limit: the value is read, and is too large
    (line,) = problems(CHAIN.replace("n = 3", "n = 0x" + "f" * 5000))
    assert line == "chain.n: must be a 64-bit integer (at most 2**63 - 1), got " \
                   "<an integer of about 6021 digits>"


@pytest.mark.parametrize("step", ["5e-324", "1e-308", "1e-300"])
def test_a_range_of_too_many_times(step):
    # was: OverflowError from round(inf), or a long wait
    (line,) = problems(CHAIN + f"[output]\ntimes = {{start = 0, stop = 1e300, step = {step}}}\n")
    assert re.fullmatch(r"output\.times: a range of \S+ times is too many \(at most 10000000\)",
                        line)


def test_a_key_in_the_wrong_table_is_pointed_to_its_own():
    text = 'name = "x"\nn = 20\n[chain]\nn = 3\nk = 1\nalpha = 1.5\nsensors = [2]\n'
    assert sorted(problems(text)) == [
        "chain.sensors: unknown key (did you mean 'output.sensors'?)",
        "n: unknown key (did you mean 'chain.n'?)"]


def test_a_nested_key_joined_by_an_underscore_is_pointed_to_its_dotted_name():
    text = ('name = "x"\n[chain]\nn = 3\nk = 0\nalpha = 1.0\n[walls.left]\n'
            'motion_frequency = 2000.0\n[walls.right]\n[solver]\nt_end = 1.0\n')
    assert problems(text) == [
        "walls.left.motion_frequency: unknown key (did you mean 'walls.left.motion.frequency'?)"]


def test_a_key_that_cannot_be_swept_is_not_called_unknown():
    (line,) = problems(CHAIN + '[sweep]\n"walls.left.material" = ["steel", "glass"]\n')
    assert line.startswith("sweep: 'walls.left.material' cannot be swept (of walls.left, "
                           "these can: walls.left.stiffness, ")
    assert line.count("walls.left.material") == 1
    (line,) = problems(CHAIN + '[sweep]\n"output.sensors" = [[1], [2]]\n')
    assert line == "sweep: 'output.sensors' cannot be swept"


def test_a_range_one_past_the_limit_says_its_count():
    (line,) = problems(CHAIN + "[output]\ntimes = {start = 0, stop = 1, step = 1e-7}\n")
    assert line == "output.times: a range of 10000001 times is too many (at most 10000000)"


@pytest.mark.parametrize("dt, end, each", [(0.1, 1e-3, 1), (6e-4, 1e-3, 2)])
def test_a_sensor_sampled_too_rarely_to_see_a_pulse(dt, end, each):
    # 0.1 for 0.1 us: one sample, and info said only "no whole pulse recorded"
    (line,) = problems(CHAIN + f"[output]\nsensors = [2]\nsensor_dt = {dt}\n"
                               f"sensor_end = {end}\n")
    assert line == (f"output.sensor_dt: every {dt:g} up to {end:g} (output.sensor_end) gives "
                    f"{each} sample{'s' * (each != 1)} a sensor, too few to see a pulse in "
                    "(at least 3); sample more often (is it in the run's units?)")


@pytest.mark.parametrize("fmt, text", [
    ("toml", 'name = "x"\nchain = ' + "[" * 5000 + "]" * 5000),
    ("toml", 'name = "x"\nchain = ' + "{a = " * 5000 + "1" + "}" * 5000),
    ("yaml", "name: x\nchain: " + "[" * 5000 + "]" * 5000),
    ("yaml", "name: x\nchain: " + "{a: " * 150 + "1" + "}" * 150),
])
def test_deep_nesting(fmt, text):
    # was: RecursionError (and PyYAML takes time quadratic in the depth of [[[...]]])
    start = time.perf_counter()
    (line,) = problems(text, fmt)
    assert "nested" in line and "deep" in line
    assert time.perf_counter() - start < 2.0


LAUGHS = "a0: &a0 [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]\n" for i in range(1, 10))
TOO_MANY = (f"more than {MAX_VALUES} values, counting each alias as the whole value it "
            "stands for")


@pytest.mark.parametrize("use", [
    "name: *a9\nchain: {n: *a9, k: 1, alpha: 1.5}\ndescription: *a9\n",
    "name: x\nchain: {n: 3, k: 1, alpha: *a9}\noutput: {times: *a9}\n",
    "name: x\nchain: {n: 3, k: 1, alpha: 1.5}\n",       # defined, never used
])
def test_the_loader_refuses_a_billion_laughs(use):
    # was: accepted by the loader (9**9 values in ten lines, each list shared), and
    # bounded only because every message shows a value a few levels deep
    start = time.perf_counter()
    lines = problems(LAUGHS + use, "yaml")
    assert time.perf_counter() - start < 1.0
    assert lines == [f"line 7: {TOO_MANY} (column 5)"]    # a6: 9**7 values


def test_the_loader_counts_values_up_to_its_limit():
    # a6 alone stands for 9**7 > MAX_VALUES values; a5 for 9**6 < MAX_VALUES
    assert 9**6 < MAX_VALUES < 9**7
    five = "".join(LAUGHS.splitlines(keepends=True)[:6])
    lines = problems(five + "name: x\nchain: {n: 3, k: 1, alpha: 1.5}\n", "yaml")
    assert lines == [f"a{i}: unknown key" for i in range(6)]


def test_the_loader_refuses_a_value_that_contains_itself():
    # was: accepted, and a sweep table containing itself raised RecursionError
    assert problems(YCHAIN + "sweep: &s {chain: *s}", "yaml") == [
        "line 3: an alias inside the value it names: a value cannot contain itself "
        "(column 8)"]
    assert problems(YCHAIN + "description: &d [1, [2, *d]]", "yaml") == [
        "line 3: an alias inside the value it names: a value cannot contain itself "
        "(column 14)"]


def test_yaml_merge_key_bomb():
    # was: nested "<<" merges copied 9**9 entries (minutes, gigabytes) in PyYAML before
    # 6.0.4; the loader refuses the document before it merges anything
    text = "a0: &a0 {k: 1}\n" + "".join(
        f"a{i}: &a{i} {{<<: [" + ", ".join([f"*a{i - 1}"] * 9) + "]}\n" for i in range(1, 10))
    start = time.perf_counter()
    lines = problems(YCHAIN + text, "yaml")
    assert time.perf_counter() - start < 1.0
    assert lines == [f"line 9: {TOO_MANY} (column 14)"]
    merged = YCHAIN.replace("chain: {n: 3, k: 1, alpha: 1.5}",
                            "base: &b {n: 3, k: 1}\nchain: {<<: *b, alpha: 1.5}")
    assert problems(merged, "yaml") == ["base: unknown key"]


@pytest.mark.parametrize("fmt", ["toml", "yaml"])
def test_a_file_too_long_is_refused_before_it_is_read(fmt, tmp_path):
    text = (CHAIN if fmt == "toml" else YCHAIN) + "#" * MAX_TEXT + "\n"
    start = time.perf_counter()
    assert problems(text, fmt) == [
        f"more than {MAX_TEXT} characters, too long for an experiment file (give long "
        "lists as data files, {file = ...})"]
    path = tmp_path / f"long.{fmt}"
    path.write_text(text)
    with pytest.raises(ConfigError) as info:
        load_experiment(path)
    assert info.value.problems == problems(text, fmt)
    assert time.perf_counter() - start < 2.0


@pytest.mark.parametrize("text, expected", [
    ("name: x\nchain:\n\tn: 3\n", "line 3: a tab: YAML does not allow tabs for "
     "indentation; indent with spaces (column 1)"),
    ("name: x\nchain:\n  n: 3\n  \tk: 1\n", "line 4: a tab: YAML does not allow tabs "
     "for indentation; indent with spaces (column 3)"),
    ("name: x\nchain: {n: 3,\tk: 1}\n", "line 2: a tab where YAML allows only spaces "
     "(column 14)"),
])
def test_a_tab_in_yaml_is_named(text, expected):
    # was: PyYAML's "found character '\\t' that cannot start any token (while scanning
    # for the next token)"
    assert problems(text, "yaml") == [expected]


@pytest.mark.parametrize("text, expected", [
    ("alpha: 2001-13-45", "line 2: cannot read '2001-13-45': month must be in 1..12 (column 8)"),
    ("alpha: !!int abc", "line 2: cannot read 'abc': invalid literal for int() with base 10: "
                         "'abc' (column 8)"),
    ("alpha: !!float x", "line 2: cannot read 'x': could not convert string to float: 'x' "
                         "(column 8)"),
])
def test_yaml_values_that_cannot_be_converted(text, expected):
    # was: ValueError from PyYAML's constructors, with no line
    assert problems(f"name: x\n{text}\n", "yaml") == [expected]


@pytest.mark.parametrize("key", ["a\nb", "a\rb", "a\u2028b", "a\x85b", "a\x1cb", "\x00"])
def test_keys_with_line_breaks_stay_on_one_line(key):
    # was: the key printed raw, breaking the "one line per problem" rule
    escaped = repr(key)[1:-1]
    toml_key = "".join(f"\\u{ord(c):04X}" if not c.isprintable() else c for c in key)
    assert problems(CHAIN + f'"{toml_key}" = 1\n') == [f"chain.{escaped}: unknown key"]
    assert problems(CHAIN + f'[sweep]\n"{toml_key}" = [1]\n') == [
        f"sweep: unknown key '{escaped}'"]


def test_a_sweep_key_given_twice():
    # was: the first list silently dropped
    text = CHAIN + '[sweep]\n"chain.k" = [1]\nchain.k = [2, 3]\n'
    assert problems(text) == ["sweep.chain.k: given twice"]


def test_sweep_size_limits():
    # was: 10**8 combinations built one by one (a hang)
    big = ", ".join(str(n) for n in range(1, 1001))
    text = CHAIN + f'[sweep]\n"chain.n" = [{big}]\n"solver.rtol" = ' \
                   f'[{", ".join(f"1e-{e}" for e in range(3, 14))}]\n'
    start = time.perf_counter()
    assert problems(text) == [f"sweep: 11000 runs are too many (at most {MAX_RUNS})"]
    assert time.perf_counter() - start < 2.0
    text = CHAIN + "[output]\ntimes = {start = 0, stop = 999999, step = 1}\n" \
                   '[sweep]\n"chain.n" = [' + ", ".join(map(str, range(3, 14))) + "]\n"
    assert problems(text) == [
        "sweep: 11 runs of 1000000 snapshot times make 11000000 snapshots, "
        f"too many (at most {MAX_SNAPSHOTS} in all)"]


def test_limits_do_not_hide_other_problems():
    big = ", ".join(str(n) for n in range(1, 20001))
    text = CHAIN.replace("alpha = 1.5", "alpha = 0.5") + f'[sweep]\n"chain.n" = [{big}]\n'
    assert problems(text) == ["chain.alpha: must be >= 1, got 0.5",
                              f"sweep: 20000 runs are too many (at most {MAX_RUNS})"]


# --- snapshot times after the stop time -----------------------------------------------------


def test_times_after_t_end():
    base = CHAIN + "[output]\ntimes = [0.0, 10.0, 40.0]\n[solver]\nt_end = 30.0\n"
    assert problems(base) == ["output.times: 40.0 is after solver.t_end (30.0)"]
    ranged = CHAIN + "[output]\ntimes = {start = 0, stop = 40, step = 5}\n[solver]\nt_end = 30\n"
    assert problems(ranged) == ["output.times: 40.0 is after solver.t_end (30.0)"]
    equal = CHAIN + "[output]\ntimes = [0.0, 30.0]\n[solver]\nt_end = 30.0\n"
    assert parse_experiment(equal, "toml").runs()[0].times[-1] == 30.0


def test_times_after_t_end_per_sweep_combination():
    text = CHAIN + "[output]\ntimes = [0.0, 40.0]\n[solver]\nt_end = 30.0\n" \
                   '[sweep]\n"solver.t_end" = [10.0, 50.0, 20.0]\n'
    assert problems(text) == [
        "sweep (t_end=10.0): output.times: 40.0 is after solver.t_end (10.0)",
        "sweep (t_end=20.0): output.times: 40.0 is after solver.t_end (20.0)",
    ]
    # the base t_end is overridden by the sweep, so 30 < 40 is not itself a problem
    ok = text.replace("[10.0, 50.0, 20.0]", "[50.0, 60.0]")
    assert [r.t_end for r in parse_experiment(ok, "toml").runs()] == [50.0, 60.0]
    # a sweep of another key: the problem is the file's, reported once
    other = CHAIN + "[output]\ntimes = [0.0, 40.0]\n[solver]\nt_end = 30.0\n" \
                    '[sweep]\n"chain.k" = [1, 2, 3]\n'
    assert problems(other) == ["output.times: 40.0 is after solver.t_end (30.0)"]


def test_runs_of_an_experiment_built_in_code_check_t_end():
    exp = Experiment(name="x", chain=Chain(n=3, k=1, alpha=1.5), output=Output(times=(0, 40)),
                     solver=SolverSettings(t_end=30.0))
    with pytest.raises(ConfigError) as info:
        exp.runs()
    assert info.value.problems == ["output.times: 40.0 is after solver.t_end (30.0)"]


# --- names never leave the output folder ----------------------------------------------------

UNSAFE_NAMES = [
    "../../x", "..", ".", "/abs", "/", "a/b", "a\\b", "..\\x", "a\x00b", "", " ", "~",
    "$HOME", "a b", "x" * 101, ".hidden", "x.", "x..", "résumé", "名前", "a\nb", "a:b",
    "CON", "con", "nul.txt", "Aux.h5", "COM1", "lpt9.tar.gz", "prn",
]


@pytest.mark.parametrize("name", UNSAFE_NAMES)
def test_unsafe_names_are_refused(name):
    text = CHAIN.replace('"x"', '"' + "".join(
        f"\\u{ord(c):04X}" if not c.isprintable() or c in '"\\' else c for c in name) + '"')
    (line,) = problems(text)
    assert line.startswith("name: ")


#: The rule for a name, stated here apart from chainrun.config: 1-100 letters, digits, '.', '_' or '-',
#: neither starting nor ending with '.', and no device name reserved on Windows (CON,
#: PRN, AUX, NUL, COM1-9, LPT1-9, with or without an extension, in any case).
_NAME_RULE = re.compile(r"(?![.])[A-Za-z0-9._-]{1,100}(?<![.])")
_DEVICE = re.compile(r"(con|prn|aux|nul|com[0-9]|lpt[0-9])(\..*)?", re.IGNORECASE)


@settings(max_examples=200, deadline=None)
@given(name=st.text(st.characters(codec="utf-8"), min_size=0, max_size=110)
       | st.from_regex(r"[A-Za-z0-9._-]{1,100}", fullmatch=True)
       | st.sampled_from(UNSAFE_NAMES))
def test_every_accepted_name_is_one_folder_inside_the_output_folder(name):
    follows_rule = bool(_NAME_RULE.fullmatch(name)) and not _DEVICE.fullmatch(name)
    try:
        exp = Experiment.model_validate({"name": name, "chain": {"n": 1, "k": 1, "alpha": 1}})
    except ValidationError as exc:
        # refused: for its name alone (the rest is valid), and only a name the rule refuses
        assert [error["loc"] for error in exc.errors()] == [("name",)], exc.errors()
        assert not follows_rule, f"{name!r} follows the rule but was refused"
        return
    assert follows_rule, f"{name!r} breaks the rule but was accepted"
    results = Path("/results")
    folder = results / exp.name
    assert exp.name == name
    assert Path(exp.name).name == exp.name and len(Path(exp.name).parts) == 1
    assert exp.name not in (".", "..") and not exp.name.startswith(".")
    assert os.path.normpath(folder).startswith("/results/")
    assert "\x00" not in exp.name and "/" not in exp.name and "\\" not in exp.name


# --- run ids from swept values are file names -----------------------------------------------

SWEEP_VALUES = {
    "chain.n": st.integers(1, 2**63 - 1),
    "chain.k": st.integers(1, 2**63 - 1),
    "chain.alpha": st.floats(1, 1.7976931348623157e308) | st.sampled_from([1, 1 + 2**-52, 1e300]),
    **{key: st.floats(-1e308, 1e308) | st.sampled_from([5e-324, 1e300, 0.0])
       for key in SWEEPABLE_KEYS if key.split(".")[-1] in (
           "mass", "stiffness", "gap", "force", "speed", "precompression", "gravity",
           "diameter", "alpha",
           "damping", "damping_exponent", "restitution", "restitution_speed", "amplitude",
           "frequency", "ramp")
       and key != "chain.alpha"},
    "solver.rtol": st.floats(1e-15, 1e-3) | st.sampled_from([1e-15, 1.0000000000000002e-15]),
    "solver.t_end": st.floats(5e-324, 1.7976931348623157e308) | st.sampled_from([5e-324, 1e-300]),
    "solver.max_events": st.integers(1, 2**63 - 1),
}
RUN_ID = re.compile(r"[a-z_]+=[0-9a-z.+-]+(_[a-z_]+=[0-9a-z.+-]+)*")


@st.composite
def sweeps(draw):
    keys = draw(st.lists(st.sampled_from(sorted(SWEEPABLE_KEYS)), min_size=1, unique=True))
    return {key: draw(st.lists(SWEEP_VALUES[key], min_size=1, max_size=3, unique_by=float))
            for key in keys}


@settings(max_examples=150, deadline=None)
@given(sweep=sweeps())
def test_run_ids_are_safe_file_names(tmp_path_factory, sweep):
    data = {"name": "x", "chain": {"n": 2**63 - 1, "k": 1, "alpha": 1.5}, "sweep": sweep}
    try:
        exp = Experiment.model_validate(data)
        specs = exp.runs()
    except ConfigError:  # e.g. k > n in a combination
        return
    ids = [s.run_id for s in specs]
    assert len(set(ids)) == len(ids)
    folder = tmp_path_factory.mktemp("ids")
    for run_id in ids:
        assert RUN_ID.fullmatch(run_id), run_id
        assert len(run_id) <= 200 and "/" not in run_id and run_id not in (".", "..")
        # the longest name written: the run file's temporary name
        path = folder / f".{run_id}.h5.partial-{2**22}"
        path.touch()
        assert path.resolve().parent == folder.resolve()


@pytest.mark.parametrize("key, value", [
    ("chain.n", 0), ("chain.n", -3), ("chain.k", -1), ("chain.alpha", -1.5),
    ("chain.alpha", 0.0), ("solver.rtol", -1e-12), ("solver.t_end", -1.0),
    ("solver.t_end", -0.0), ("solver.max_events", -5), ("chain.alpha", math.nan),
    ("solver.t_end", math.inf),
])
def test_negative_or_non_finite_swept_values_are_refused(key, value):
    data = {"name": "x", "chain": {"n": 3, "k": 1, "alpha": 1.5}, "sweep": {key: [value]}}
    text = "name: x\nchain: {n: 3, k: 1, alpha: 1.5}\nsweep: {" + key + ": [" + {
        math.nan: ".nan", math.inf: ".inf"}.get(value, repr(value)) + "]}\n"
    (line,) = problems(text, "yaml")
    assert line.startswith(f"sweep.{key}: ") or line.startswith("sweep (")
    assert data  # the same data built in code is refused by runs() or the model
    with pytest.raises(Exception):
        Experiment.model_validate(data).runs()


def test_extreme_swept_values_give_short_ids():
    data = {"name": "x", "chain": {"n": 2**63 - 1, "k": 1, "alpha": 1.5}, "sweep": {
        "chain.n": [2**63 - 1], "chain.k": [2**63 - 1], "chain.alpha": [MAX_ALPHA],
        "solver.rtol": [1.0000000000000002e-15], "solver.t_end": [5e-324],
        "solver.max_events": [2**63 - 1]}}
    (spec,) = Experiment.model_validate(data).runs()
    assert spec.run_id == (
        "n=9223372036854775807_k=9223372036854775807_alpha=10.0_"
        f"rtol={1.0000000000000002e-15!r}_t_end=5e-324_max_events=9223372036854775807")
    assert np.asarray(spec.times).size == 0


def test_a_byte_order_mark_is_dropped(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + CHAIN.encode())
    exp = load_experiment(path)
    assert exp.name == "x" and exp.source_text == CHAIN


def test_a_long_run_id_is_cut_with_a_hash_of_the_whole():
    # A sweep over many keys with long values: every id fits MAX_RUN_ID, ends with a
    # hash of the full id, and the ids stay distinct.
    from chainrun.config import MAX_RUN_ID

    text = """
name = "long"
[chain]
n = 4
k = 1
alpha = 1.5
[solver]
t_end = 10.0
[sweep]
"chain.mass" = [1.0000000000000002, 2.0000000000000004]
"chain.stiffness" = [1.5381766297101102e-104, 3.5381766297101102e-104]
"chain.gap" = [9.64066001723686e-124]
"chain.force" = [-3.53603293454901e-67]
"chain.speed" = [1.2919326237966292e+46]
"walls.right.stiffness" = [2.0000000000000004e-100]
"walls.right.gap" = [1.0000000000000002e-100]
"solver.rtol" = [1.0000000000000002e-12]
"""
    specs = parse_experiment(text, "toml").runs()
    ids = [s.run_id for s in specs]
    assert len(set(ids)) == len(ids) == 4
    for run_id in ids:
        assert len(run_id) <= MAX_RUN_ID and RUN_ID.fullmatch(run_id), run_id
        assert re.search(r"_hash=[0-9a-f]{16}$", run_id), run_id
