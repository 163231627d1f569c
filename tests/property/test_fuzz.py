"""Fuzzing the experiment loader and ``chainrun simulate`` with Hypothesis.

Random YAML and TOML documents (random values in every field: wrong types, huge and
tiny numbers, NaN and inf, unicode, unknown keys, sweeps), random edits of valid
files, random text and bytes, and deep or cyclic nesting. Every case must end in a
valid ``Experiment`` or a ``ConfigError`` whose problems are one line each; through
the command line, in a non-zero exit without a traceback and with nothing written,
or in a run whose files all lie inside the output folder.

The default is a fast subset for CI. A long run::

    CHAINRUN_FUZZ_EXAMPLES=20000 .venv/bin/python -m pytest tests/property/test_fuzz.py -n 2

gives every test that many examples; the number of cases tried is printed at the end
of the run (``fuzz: N cases tried``).
"""

from __future__ import annotations

import contextlib
import datetime as dt
import json
import math
import os
import re
import tempfile
from pathlib import Path

import pytest
import yaml
from click.testing import CliRunner
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from chainrun.cli import main
from chainrun.config import SWEEPABLE_KEYS, Experiment, load_experiment, parse_experiment
from chainrun.errors import ConfigError

LONG = int(os.environ.get("CHAINRUN_FUZZ_EXAMPLES", "0") or 0)


def fuzz_settings(fast: int):
    """``fast`` examples in CI, ``CHAINRUN_FUZZ_EXAMPLES`` in a long run."""
    return settings(
        max_examples=LONG or fast,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                               HealthCheck.data_too_large],
    )


def report(record_property, count: list[int]) -> None:
    record_property("fuzz_cases", count[0])
    if LONG:
        print(f"fuzz cases tried: {count[0]}")


# --- values ------------------------------------------------------------------------------

_chars = st.characters(blacklist_categories=("Cs",))  # no lone surrogates: not in UTF-8
texts = st.text(_chars, max_size=20)

huge_ints = st.one_of(
    st.integers(min_value=2**63 - 3, max_value=2**200),
    st.integers(min_value=-(2**200), max_value=-(2**63) + 3),
    st.sampled_from([2**63 - 1, 2**63, 2**64, -(2**63), 10**308, 10**309, 16**1100]),
)
odd_floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 5e-324, 1e-308, 2.2250738585072014e-308, 1e-300, 1e308,
                     1.7976931348623157e308, -1e308, math.nan, math.inf, -math.inf,
                     1 + 2**-52, 1 - 2**-53]),
)
dates = st.one_of(st.dates(), st.datetimes(timezones=st.just(dt.timezone.utc)))
scalars = st.one_of(st.none(), st.booleans(), st.integers(-10, 10), huge_ints, odd_floats,
                    texts, dates)
#: Anything at all, nested a few levels.
wild = st.recursive(
    scalars,
    lambda inner: st.one_of(st.lists(inner, max_size=4),
                            st.dictionaries(texts, inner, max_size=4)),
    max_leaves=12,
)


names = st.one_of(
    st.from_regex(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,12}", fullmatch=True),
    st.sampled_from(["../../x", "..", ".", "/abs", "/", "a/b", "a\\b", "a\x00b", "CON",
                     "nul.txt", "x.", "", " ", "..\\..\\x", "~", "$HOME", "résumé", "名前",
                     "a\nb", "x" * 101, "-rf", "--help"]),
    texts,
)
valid_names = st.from_regex(r"[A-Za-z0-9_][A-Za-z0-9._-]{0,12}[A-Za-z0-9_-]", fullmatch=True)


class Fields:
    """Draws the fields of one document.

    A document is *clean* (every field valid, required keys present) or, with a
    drawn error rate, has fields that are wrong, missing or extra.
    """

    def __init__(self, draw):
        self.draw = draw
        self.clean = draw(st.booleans())
        self.rate = 0 if self.clean else draw(st.sampled_from([1, 3, 6]))  # 1 in rate wrong

    def wrong(self) -> bool:
        return not self.clean and self.draw(st.integers(1, self.rate)) == 1

    def value(self, valid, invalid=wild):
        return self.draw(invalid if self.wrong() else valid)

    def table(self, fields: dict, required: bool = True) -> dict:
        """Some of ``fields`` (name -> strategy), and maybe an unknown key."""
        table = {}
        for key, strategy in fields.items():
            if (not required or self.wrong()) and self.draw(st.integers(0, 3)) == 0:
                continue  # left out
            table[key] = self.value(strategy)
        if self.wrong() and self.draw(st.booleans()):
            table[self.draw(texts)] = self.draw(wild)
        return table


@st.composite
def documents(draw, runnable: bool = False):
    """A parsed experiment file, near a valid one: every field is sometimes wrong.

    With ``runnable``, valid values are tiny (N <= 6, times <= 0.9 <= t_end <= 1) so
    that a valid document runs at once; otherwise they span their whole range.
    """
    f = Fields(draw)
    small_n = st.integers(1, 6)
    n_valid = small_n if runnable else small_n | st.integers(1, 2**63 - 1)
    alpha_valid = st.sampled_from([1, 1.0, 1.5, 2.0, 3]) | st.floats(1, 30 if runnable else 1e300)
    t_end_valid = st.floats(0.9, 1.0)
    times = st.floats(0, 0.9)
    if not runnable:
        t_end_valid |= st.floats(min_value=5e-324, max_value=1e308)
        times |= st.floats(0, 1e308)
    times_valid = st.one_of(
        st.lists(times, max_size=5).map(sorted),
        st.fixed_dictionaries({"start": st.floats(0, 0.3), "stop": st.floats(0.3, 0.9),
                               "step": st.floats(0.05, 0.5)}),
    )
    doc = {"name": f.value(valid_names, names)}
    if draw(st.booleans()):
        doc["description"] = f.value(texts)
    chain = f.table({"n": n_valid, "k": small_n, "alpha": alpha_valid})
    doc["chain"] = f.value(st.just(chain))
    if draw(st.booleans()):
        doc["output"] = f.table({"times": times_valid}, required=False)
    solver = f.table({"t_end": t_end_valid, "rtol": st.floats(1e-15, 1e-3),
                      "max_events": st.integers(1, 10**6)}, required=False)
    if runnable and "t_end" not in solver:
        solver["t_end"] = draw(t_end_valid)  # never unbounded
    if solver or draw(st.booleans()):
        doc["solver"] = solver
    if draw(st.integers(0, 2)) == 0:
        values = {
            "chain.n": n_valid, "chain.k": small_n, "chain.alpha": alpha_valid,
            "solver.rtol": st.floats(1e-15, 1e-3), "solver.t_end": t_end_valid,
            "solver.max_events": st.integers(1, 10**6),
        }
        sweep = {}
        for _ in range(draw(st.integers(1, 2 if runnable else 4))):
            key = f.value(st.sampled_from(sorted(SWEEPABLE_KEYS)), texts)
            size = 2 if runnable else 4
            sweep[key] = f.value(st.lists(values.get(key, wild), min_size=1, max_size=size,
                                          unique_by=repr))
        doc["sweep"] = sweep
    if f.wrong() and draw(st.booleans()):
        doc[draw(texts)] = draw(wild)
    return doc


# --- writing documents as text ---------------------------------------------------------


def _toml_string(text: str) -> str:
    out = []
    for ch in text:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04X}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_value(value) -> str | None:
    """TOML for ``value`` (inline tables and arrays), None for what TOML cannot hold."""
    if value is None:
        return None
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value) if abs(value) < 10**4000 else hex(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, (dt.date, dt.datetime)):
        return value.isoformat()
    if isinstance(value, (list, tuple)):
        items = [_toml_value(v) for v in value]
        return "[" + ", ".join(i for i in items if i is not None) + "]"
    if isinstance(value, dict):
        items = [(k, _toml_value(v)) for k, v in value.items()]
        return "{" + ", ".join(f"{_toml_string(str(k))} = {v}" for k, v in items
                               if v is not None) + "}"
    raise TypeError(type(value))


def toml_text(doc: dict) -> str:
    lines = []
    for key, value in doc.items():
        text = _toml_value(value)
        if text is not None:
            lines.append(f"{_toml_string(str(key))} = {text}")
    return "\n".join(lines) + "\n"


def yaml_text(doc: dict) -> str:
    return yaml.safe_dump(doc, allow_unicode=True, sort_keys=False)


def as_text(doc: dict, fmt: str) -> str:
    return toml_text(doc) if fmt == "toml" else yaml_text(doc)


VALID_TOML = """\
name = "cradle"
description = "a valid file to mutate"
[chain]
n = 3
k = 1
alpha = 1.5
[output]
times = {start = 0, stop = 0.5, step = 0.25}
[solver]
t_end = 0.5
rtol = 1e-10
[sweep]
"chain.k" = [1, 2]
"""
VALID_YAML = """\
name: cradle
description: a valid file to mutate
chain: {n: 3, k: 1, alpha: 1.5}
output:
  times: [0, 0.25, 0.5]
solver:
  t_end: 0.5
  rtol: 1.0e-10
sweep:
  chain.k: [1, 2]
"""


@st.composite
def mutated(draw, text: str) -> str:
    """``text`` with a few random insertions, deletions and replacements."""
    chars = list(text)
    pieces = st.sampled_from(list("[]{}\"'=:,.-+#\n\t \\0123456789eE") +
                             ["nan", "inf", "1e999", "!!", "&a", "*a", "<<", "\x00", "\ufeff",
                              "\u2028", "é", "名", "0x", "---", "..."]) | texts
    for _ in range(draw(st.integers(1, 6))):
        at = draw(st.integers(0, len(chars)))
        op = draw(st.sampled_from(["insert", "delete", "replace", "cut"]))
        if op == "insert":
            chars[at:at] = list(draw(pieces))
        elif op == "delete":
            del chars[at:at + draw(st.integers(1, 5))]
        elif op == "replace":
            chars[at:at + 1] = list(draw(pieces))
        elif draw(st.integers(0, 3)) == 0:
            del chars[at:]
    return "".join(chars)


def nasty(fmt: str):
    """Hand-written extreme documents: deep nesting, aliases, huge numbers."""
    depth = st.integers(1, 3000)
    head = 'name = "x"\n' if fmt == "toml" else "name: x\n"
    if fmt == "toml":
        templates = [
            lambda d: head + "chain = " + "[" * d + "]" * d,
            lambda d: head + "chain = " + "{a = " * d + "1" + "}" * d,
            lambda d: head + "[chain]\nn = " + "9" * (2 * d) + "\nk = 1\nalpha = 1",
            lambda d: head + "[chain]\nn = 0x" + "f" * d + "\nk = 1\nalpha = 1",
            lambda d: head + "[chain]\nn = 3\nk = 1\nalpha = " + "9" * d + ".0",
            lambda d: head + "[chain]\nn = 3\nk = 1\nalpha = 1.5\n[sweep]\n" + "a." * d + "b = [1]",
            lambda d: head + "[chain]\nn = 3\nk = 1\nalpha = 1\n[output]\n"
                             f"times = {{start = 0, stop = 1e{d % 309}, step = 1e-{d % 324}}}",
            lambda d: head + "[" + "a." * d + "b]\nc = 1",
        ]
    else:
        templates = [
            lambda d: head + "chain: " + "[" * d + "]" * d,
            lambda d: head + "chain: " + "{a: " * d + "1" + "}" * d,
            lambda d: head + "chain:\n" + "".join("  " * i + f"k{i}:\n" for i in range(min(d, 400))),
            lambda d: head + "chain: {n: " + "9" * (2 * d) + ", k: 1, alpha: 1}",
            lambda d: head + "chain: {n: 0x" + "f" * d + ", k: 1, alpha: 1}",
            lambda d: head + "chain: &a {n: 3, k: 1, alpha: 1.5, x: *a}\nsweep: &b {c: *b}",
            lambda d: "a0: &a0 [x, x, x, x, x, x, x, x, x]\n" + "".join(
                f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 9) + "]\n"
                for i in range(1, 10)) + head + "chain: {n: *a9, k: *a9, alpha: *a9}\n"
                f"output: {{times: *a9}}\nsweep: {{chain.k: *a9, chain.n: [*a9]}}\ndescription: *a9",
            lambda d: "a0: &a0 {k: 1}\n" + "".join(
                f"a{i}: &a{i} {{<<: [" + ", ".join([f"*a{i - 1}"] * (2 + d % 8)) + "]}\n"
                for i in range(1, 2 + d % 9)) + head,
            lambda d: head + f"chain: {{n: 3, k: 1, alpha: {1900 + d % 200}-13-45}}",
            lambda d: head + "chain: {n: !!int abc, k: !!float x, alpha: !!binary '#'}",
            lambda d: head + "chain: {n: 3, k: 1, alpha: 1.5}\n? [1, 2]\n: 3",
            lambda d: head + "chain: !!python/object:os.system {}",
        ]
    return st.builds(lambda template, d: template(d), st.sampled_from(templates), depth)


# --- checks ----------------------------------------------------------------------------


def assert_one_line_problems(exc: ConfigError) -> None:
    assert exc.problems, "a ConfigError without problems"
    for line in exc.problems:
        assert isinstance(line, str) and line.strip()
        assert len(line.splitlines()) == 1 and "\r" not in line and "\n" not in line, repr(line)
    assert len(str(exc).splitlines()) == 1


RUN_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9._=+-]{0,199}")


def assert_usable(exp: Experiment) -> None:
    """What later stages rely on in a valid experiment."""
    specs = exp.runs()
    assert specs and len({s.run_id for s in specs}) == len(specs)
    for spec in specs:
        assert RUN_ID.fullmatch(spec.run_id), spec.run_id
        assert 0 <= spec.k <= spec.n < 2**63  # k = 0: a line at rest
        # alpha: NaN where the contacts' exponents differ, or there is no contact
        assert math.isnan(spec.alpha) or 1 <= spec.alpha < math.inf
        times = spec.times
        assert all(math.isfinite(t) and t >= 0 for t in times)
        assert all(a <= b for a, b in zip(times[:-1], times[1:]))
        if spec.t_end is not None:
            assert 0 < spec.t_end < math.inf
            assert len(times) == 0 or times[-1] <= spec.t_end
        json.dumps(spec.config, allow_nan=False)


def check_text(text: str, fmt: str) -> Experiment | None:
    """``parse_experiment(text)``: an Experiment or a one-line ConfigError, nothing else."""
    try:
        exp = parse_experiment(text, fmt, source="fuzz")
    except ConfigError as exc:
        assert_one_line_problems(exc)
        return None
    assert_usable(exp)
    return exp


# --- the loader --------------------------------------------------------------------------


@pytest.mark.parametrize("fmt", ["toml", "yaml"])
def test_random_documents(fmt, record_property):
    count = [0]

    @fuzz_settings(200)
    @given(doc=documents())
    def run(doc):
        count[0] += 1
        check_text(as_text(doc, fmt), fmt)

    run()
    report(record_property, count)


@pytest.mark.parametrize("fmt", ["toml", "yaml"])
def test_edited_files(fmt, record_property):
    count = [0]
    base = VALID_TOML if fmt == "toml" else VALID_YAML
    assert check_text(base, fmt) is not None

    @fuzz_settings(300)
    @given(text=mutated(base))
    def run(text):
        count[0] += 1
        check_text(text, fmt)

    run()
    report(record_property, count)


@pytest.mark.parametrize("fmt", ["toml", "yaml"])
def test_extreme_documents(fmt, record_property):
    count = [0]

    @fuzz_settings(60)
    @given(text=nasty(fmt))
    def run(text):
        count[0] += 1
        check_text(text, fmt)

    run()
    report(record_property, count)


def test_random_bytes_in_files(record_property):
    count = [0]

    @fuzz_settings(150)
    @given(data=st.binary(max_size=200) | texts.map(lambda t: t.encode("utf-8")),
           suffix=st.sampled_from([".toml", ".yaml", ".yml", ".json", "", ".TOML"]))
    def run(data, suffix):
        count[0] += 1
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / f"exp{suffix}"
            path.write_bytes(data)
            try:
                exp = load_experiment(path)
            except ConfigError as exc:
                assert_one_line_problems(exc)
            else:
                assert_usable(exp)

    run()
    report(record_property, count)


# --- the command -------------------------------------------------------------------------


def files_under(folder: Path) -> set[Path]:
    return {p.relative_to(folder) for p in folder.rglob("*")}


def test_simulate_command(record_property):
    """``chainrun simulate`` on random files: a run, or a clean refusal that writes nothing."""
    count = [0]
    runner = CliRunner()

    @fuzz_settings(100)
    @given(doc=documents(runnable=True), fmt=st.sampled_from(["toml", "yaml"]))
    def run(doc, fmt):
        text = as_text(doc, fmt)
        try:
            exp = parse_experiment(text, fmt)
        except ConfigError:
            exp = None
        if exp is not None:  # a valid file: only tiny runs, so that it is instant
            specs = exp.runs()
            assume(len(specs) <= 4)
            assume(all(s.n <= 10 and s.alpha <= 100 and s.t_end is not None
                       and s.t_end <= 1 and len(s.times) <= 20 for s in specs))
        count[0] += 1
        with tempfile.TemporaryDirectory() as folder, contextlib.chdir(folder):
            folder = Path(folder).resolve()
            config = Path(f"exp.{fmt}")
            config.write_text(text, encoding="utf-8")
            result = runner.invoke(main, ["simulate", str(config)])
            output = result.stdout + result.stderr
            assert result.exception is None or isinstance(result.exception, SystemExit), \
                repr(result.exception)
            assert "Traceback" not in output
            written = files_under(folder) - {config}
            if exp is None:
                assert result.exit_code == 2, output
                assert result.stderr.strip(), "refused without a reason"
                for line in result.stderr.splitlines():
                    assert line.startswith(f"{config}: "), line
                assert written == set(), written
            else:
                assert result.exit_code in (0, 1), output
                outdir = Path("results") / exp.name
                assert all(p == Path("results") or p == outdir or outdir in p.parents
                           for p in written), written
                assert (folder / outdir).resolve().parent == folder / "results"
                assert not [p for p in written if ".partial-" in p.name]
                assert (outdir / "index.h5") in written
                if result.exit_code == 1:
                    assert "failed" in result.stderr

    run()
    report(record_property, count)
