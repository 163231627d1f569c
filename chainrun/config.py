"""Experiment files: the one schema for YAML and TOML, validation, and sweep expansion.

This module owns turning config text into frozen, validated objects, and the ``Line``
each run describes (``build_line``). Nothing else in chainrun parses experiment files,
and the module reads nothing but the file it is given and the data files it names
(``chainrun.generators``).

The schema (TOML shown; YAML has the same structure)::

    name = "table1"                  # the output folder: 1-100 of [A-Za-z0-9._-], no leading
                                     # or trailing ".", not a reserved device name (CON, NUL...)
    description = "..."              # optional
    [chain]
    n = 5                            # balls, 1 <= n < 2**63 (memory is checked when run)
    k = 1                            # impacting balls at velocity 1, 0 <= k <= n
    alpha = 1.5                      # contact exponent, >= 1 (1 linear, 1.5 Hertz)
    # any line (docs/guide.md): per ball mass, velocity (instead of k), force, and in SI
    # diameter, material (or young, poisson, density); per contact stiffness, alpha
    # (<= MAX_ALPHA), gap: a number, a list or a generator table (chainrun.generators);
    # speed (with k), precompression; top-level units = "paper" | "si"; dissipation:
    # per contact damping (>= 0) and damping_exponent (>= 0), or restitution (0 < e <= 1)
    # with damping_law ("dashpot" | "kuwabara-kono" | "tsuji") and, where e depends on
    # the impact speed, restitution_speed (> 0)
    # drive = [{ball = 1, amplitude = 0.1, frequency = 0.2, ramp = 5.0}]: forces in time
    [walls.right]                    # optional, likewise [walls.left]
    stiffness = 1.0                  # alpha, gap; or material (SI); the dissipation keys
    # motion = {amplitude = 1e-3, frequency = 0.2, ramp = 5.0}: the wall moves; or a
    # list of such tables (their sum), or {file = "drive.csv"} (times, displacements)
    [output]                         # optional
    times = [0.0, 5.0]               # or {start = 0, stop = 60, step = 5}, stop inclusive;
                                     # none after solver.t_end
    [solver]                         # optional
    t_end = 100.0                    # default: run to the terminal state
    rtol = 1e-12                     # in [1e-15, 1e-3]
    max_events = 1000000             # default: no limit
    check = false                    # true: run again at a tenth of rtol, store the spreads
    [sweep]                          # optional: the cartesian product of the lists
    "chain.k" = [1, 2, 3, 4]         # at most MAX_RUNS runs, MAX_SNAPSHOTS snapshots in all

Every problem in a file is reported at once, one line each naming the dotted key, as a
``chainrun.errors.ConfigError``; ``load_experiment`` and ``parse_experiment`` raise
nothing else, whatever the text (``tests/property/test_fuzz.py`` checks it).
"""

from __future__ import annotations

import difflib
import functools
import hashlib
import itertools
import json
import math
import os
import re
import sys
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Annotated, Any, NamedTuple

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainSerializer,
    PrivateAttr,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from chainrun import generators
from chainrun.check import MIN_RTOL, check_rtol
from chainrun.errors import ConfigError, one_line, show_value
from chainrun.generators import Values, ValuesError
from chainrun.materials import MATERIALS
from chainrun.solver import DEFAULT_RTOL, Drive, Line, Wall
from chainrun.solver import physics
from chainrun.solver import restitution as collision
from chainrun.solver.model import precompress


@dataclass(frozen=True)
class RunSpec:
    """One fully specified run of an experiment (one point of a sweep).

    Attributes
    ----------
    experiment : str
        The experiment's ``name``.
    run_id : str
        File-name-safe id, unique within the experiment: ``"run"`` without a sweep,
        else the swept values, e.g. ``"k=2"`` or ``"n=100_k=3"``.
    n, k : int
    alpha : float
    times : ndarray, shape (T,)
        Snapshot times, non-negative and non-decreasing.
    t_end : float or None
    rtol : float
    max_events : int or None
    sensors : tuple of int
        Balls (numbered from 1) whose contact forces are sampled every ``sensor_dt``.
    sensor_dt : float or None
    sensor_end : float or None
        The last time a sample is taken (``output.sensor_end``, by default ``t_end``
        or else the last snapshot time); None without sensors.
    overrides : dict
        The swept keys and their values for this run, e.g. ``{"chain.k": 2}``.
    config : dict
        The resolved configuration of this single run (no ``sweep`` table), as plain
        JSON-compatible data.
    config_hash : str
        sha256 of the canonical JSON of ``config``: two runs with the same hash are
        the same computation.
    source_text : str
        The full text of the experiment file the run came from.
    units : {"paper", "si"}
        The units of the run's line, times and results.
    chain : Chain or None
        The run's chain (sweep values applied); None for the paper's line, which
        ``n``, ``k`` and ``alpha`` describe whole.
    walls : Walls or None
    check : bool
        Whether to run the line a second time at ``chainrun.check.check_rtol(rtol)``
        and store the spread of each ball's velocities (``solver.check``, or the
        command's ``--check``); not part of ``config`` nor of its hash.

    For a general line, ``k`` is the number of leading balls that move and ``alpha``
    the contacts' exponent, NaN when it varies: what summaries show. The line itself
    is ``line``.
    """

    experiment: str
    run_id: str
    n: int
    k: int
    alpha: float
    times: np.ndarray
    t_end: float | None
    rtol: float
    max_events: int | None
    overrides: dict[str, Any] = field(default_factory=dict)
    config: dict[str, Any] = field(default_factory=dict)
    config_hash: str = ""
    source_text: str = ""
    sensors: tuple[int, ...] = ()
    sensor_dt: float | None = None
    sensor_end: float | None = None
    units: str = "paper"
    chain: Any = None
    walls: Any = None
    check: bool = False

    def for_check(self) -> "RunSpec":
        """The check's run of this one: the same line at ``check_rtol(rtol)``, with
        its own resolved configuration and hash (and no check of its own)."""
        config = checked_config(self.config)
        return replace(self, rtol=config["solver"]["rtol"], config=config,
                       config_hash=config_hash(config), check=False)

    @property
    def line(self) -> Line:
        """The ``Line`` of this run, in its ``units``: built on first use (its arrays
        are as long as the line), then kept.

        Raises
        ------
        ConfigError
            Values that the file's checks could not see (a generated array of a line
            longer than ``CHECK_MAX_N``, a data file changed since it was read).
        """
        line = self.__dict__.get("_line")
        if line is None:
            if self.chain is None:
                line = Line.paper(self.n, self.k, self.alpha)
            else:
                try:
                    line = build_line(self.chain, self.walls or Walls(), self.units)
                except LineError as exc:
                    raise ConfigError(self.experiment, [
                        one_line(f"run {self.run_id}: {p.line()}") for p in exc.problems]) from None
            object.__setattr__(self, "_line", line)  # a cache, not a field
        return line

    @property
    def sensor_samples(self) -> int:
        """Force samples the run's sensors take: sample times by sensor balls."""
        return _samples(self.sensors, self.sensor_dt, self.sensor_end)

    @property
    def damped(self) -> bool:
        """Whether the run's line may dissipate: a contact's or a wall's damping or
        restitution is given (other than a damping of 0 or a restitution of 1). Read
        from the settings, before the line is built: a damped line's state takes more
        memory (``chainrun.limits``)."""
        def given(settings):
            if settings is None:
                return False
            return any(value is not None and not (isinstance(value, (int, float))
                                                  and value == neutral)
                       for value, neutral in ((settings.damping, 0.0),
                                              (settings.restitution, 1.0)))
        walls = self.walls
        return given(self.chain) or (walls is not None
                                     and (given(walls.left) or given(walls.right)))


__all__ = [
    "Chain",
    "Experiment",
    "LineError",
    "MAX_ALPHA",
    "MAX_RUNS",
    "MAX_SNAPSHOTS",
    "Output",
    "RunSpec",
    "SWEEPABLE_KEYS",
    "SolverSettings",
    "UNITS",
    "WallSettings",
    "Walls",
    "build_line",
    "load_experiment",
    "parse_experiment",
]

#: File extensions and the format each one is read as.
FORMATS = {".toml": "toml", ".yaml": "yaml", ".yml": "yaml"}

#: The keys of a sine of a drive (amplitude, frequency in cycles per unit of time, ramp).
SINE_KEYS = ("amplitude", "frequency", "ramp")

#: Keys a ``[sweep]`` table may vary, and the type of their values.
SWEEPABLE_KEYS: dict[str, type] = {
    "chain.n": int,
    "chain.k": int,
    "chain.alpha": float,
    "chain.mass": float,
    "chain.stiffness": float,
    "chain.gap": float,
    "chain.force": float,
    "chain.speed": float,
    "chain.precompression": float,
    "chain.diameter": float,
    "chain.damping": float,
    "chain.damping_exponent": float,
    "chain.restitution": float,
    "chain.restitution_speed": float,
    "walls.left.stiffness": float,
    "walls.left.alpha": float,
    "walls.left.gap": float,
    "walls.left.damping": float,
    "walls.left.damping_exponent": float,
    "walls.left.restitution": float,
    "walls.left.restitution_speed": float,
    "walls.right.stiffness": float,
    "walls.right.alpha": float,
    "walls.right.gap": float,
    "walls.right.damping": float,
    "walls.right.damping_exponent": float,
    "walls.right.restitution": float,
    "walls.right.restitution_speed": float,
    **{f"walls.{side}.motion.{key}": float for side in ("left", "right") for key in SINE_KEYS},
    "solver.rtol": float,
    "solver.t_end": float,
    "solver.max_events": int,
}

#: The units an experiment may be written in: the paper's (every coefficient 1), or SI.
UNITS = ("paper", "si")


def _canonical_units(value: Any) -> str | None:
    """The units a file's ``units`` names, in lower case ("SI" is "si"); None if none."""
    return value.lower() if isinstance(value, str) and value.lower() in UNITS else None
#: Largest contact exponent: beyond it a contact stiffens so abruptly that the steps
#: the solver needs to resolve it shrink without end.
MAX_ALPHA = 10.0
#: Longest line whose generated values (tables) are expanded and checked when the file
#: is read; a longer one is checked when its run starts.
CHECK_MAX_N = 10_000_000

#: Most snapshot times a ``{start, stop, step}`` range may expand to.
MAX_RANGE_TIMES = 10_000_000
#: Most runs a sweep may have.
MAX_RUNS = 10_000
#: Most snapshots (runs times snapshot times) an experiment may ask for in all.
MAX_SNAPSHOTS = 10_000_000
#: Most force samples a run may take (sample times by sensors): each is a row of the
#: run file and of the solver's memory.
MAX_SENSOR_SAMPLES = 10_000_000
#: Largest integer a config may hold: run files store integers as int64.
MAX_INT = 2**63 - 1

_NAME_RE = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,99}")
#: Device names Windows reserves in every folder, with or without an extension.
_RESERVED_RE = re.compile(r"(CON|PRN|AUX|NUL|COM[0-9]|LPT[0-9])(\..*)?", re.IGNORECASE)
_ERROR_TYPE = "chainrun"  # pydantic error type of the problems raised in this module


# --- problems: one line each, naming a dotted key ----------------------------------------


class _Issue(NamedTuple):
    """One problem found inside a validator, relative to the field it validates.

    ``sub`` extends the field's location (e.g. ``("step",)`` for ``output.times.step``);
    ``involves`` names sibling keys the problem also depends on (e.g. ``("n",)`` for
    ``chain.k <= chain.n``), which decides whether a sweep combination caused it.
    """

    reason: str
    sub: tuple[str, ...] = ()
    involves: tuple[str, ...] = ()


class _Problem(NamedTuple):
    """A problem with its full dotted key, ready to print as ``key: reason``."""

    key: str
    reason: str
    involves: frozenset[str] = frozenset()

    def line(self) -> str:
        return f"{self.key}: {self.reason}" if self.key else self.reason


def _fail(issues: list[_Issue]) -> PydanticCustomError:
    """The pydantic error carrying ``issues``; ``_translate`` unpacks it again."""
    return PydanticCustomError(
        _ERROR_TYPE, "{reason}", {"reason": "; ".join(i.reason for i in issues), "issues": issues}
    )


def _key_path(parts: tuple[str, ...]) -> str:
    """A place in the file from its keys: ``chain.alpha[3]``, an index kept on its key."""
    return "".join(p if p.startswith("[") or i == 0 else "." + p for i, p in enumerate(parts))


def _key_text(key: Any) -> str:
    """A user's key for a message: one line, at most 60 characters."""
    if not isinstance(key, str):
        return show_value(key)
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in key[:200])
    return text if len(text) <= 60 else text[:57] + "..."


def _bound(value: Any) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def _suggest(word: str, choices: list[str]) -> str:
    close = difflib.get_close_matches(word, choices, n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


# --- scalar checks shared by the models and the sweep table ------------------------------


def _check_int(value: Any) -> int:
    """``value`` if it is a true integer (not a bool, not 2.0 or "3") that fits in an
    int64, else an error."""
    if isinstance(value, int) and not isinstance(value, bool):
        if -MAX_INT - 1 <= value <= MAX_INT:
            return value
        raise _fail([_Issue("must be a 64-bit integer (at most 2**63 - 1), got "
                            f"{show_value(value)}")])
    raise _fail([_Issue(f"expected an integer, got {show_value(value)}")])


def _check_float(value: Any) -> float:
    """``value`` as a float if it is a finite int or float (not a bool), else an error."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            x = float(value)
        except OverflowError:  # an integer beyond 1.8e308
            raise _fail([_Issue(f"must be finite, got {show_value(value)}")]) from None
        if math.isfinite(x):
            return x
        raise _fail([_Issue(f"must be finite, got {show_value(value)}")])
    hint = ""
    if isinstance(value, str):
        try:
            float(value)
            hint = " (text, not a number; YAML reads 1e-12 as text: write 1.0e-12)"
        except ValueError:
            pass
    raise _fail([_Issue(f"expected a number, got {show_value(value)}{hint}")])


def _check_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    raise _fail([_Issue(f"expected true or false, got {show_value(value)}")])


def _check_str(value: Any) -> str:
    if isinstance(value, str):
        return value
    raise _fail([_Issue(f"expected a string, got {show_value(value)}")])


def _none_or(check):
    return lambda value: None if value is None else check(value)


_Int = Annotated[int, BeforeValidator(_check_int)]
_Float = Annotated[float, BeforeValidator(_check_float)]
_OptInt = Annotated[int | None, BeforeValidator(_none_or(_check_int))]
_Bool = Annotated[bool, BeforeValidator(_check_bool)]
_OptFloat = Annotated[float | None, BeforeValidator(_none_or(_check_float))]

_SCALAR_CHECKS = {int: _check_int, float: _check_float}


# --- the models ---------------------------------------------------------------------------


#: What each per-ball or per-contact key must satisfy: (lowest, strict, highest, what
#: it is per). Checked on scalars as the file is read, and on every value once expanded.
_RULES: dict[str, tuple[float | None, bool, float | None, str]] = {
    "mass": (0.0, True, None, "ball"),
    "stiffness": (0.0, True, None, "contact"),
    "alpha": (1.0, False, MAX_ALPHA, "contact"),
    "gap": (None, False, None, "contact"),
    "velocity": (None, False, None, "ball"),
    "force": (None, False, None, "ball"),
    "diameter": (0.0, True, None, "ball"),
    "young": (0.0, True, None, "ball"),
    "poisson": (-1.0, True, 0.5, "ball"),
    "density": (0.0, True, None, "ball"),
    "damping": (0.0, False, None, "contact"),
    "damping_exponent": (0.0, False, None, "contact"),
    "restitution": (0.0, True, 1.0, "contact"),
}
#: Keys of the chain that only SI experiments have (real spheres).
_SI_KEYS = ("diameter", "material", "young", "poisson", "density")


def _rule_reason(key: str, x: float) -> str | None:
    """Why ``x`` breaks the rule of ``key`` (None if it does not)."""
    low, strict, high, _ = _RULES[key]
    if low is not None and (x <= low if strict else x < low):
        return f"must be {'>' if strict else '>='} {_bound(low)}"
    if high is not None and x > high if key != "poisson" else high is not None and x >= high:
        op = "<" if key == "poisson" else "<="
        why = (" (a steeper law stiffens so abruptly that the solver's steps shrink "
               "without end)" if key == "alpha" else "")
        return f"must be {op} {_bound(high)}{why}"
    return None


def _values(key: str, text: bool = False):
    """The validator of a per-ball or per-contact key: a scalar (checked now, kept a
    float or str), or a list or generator table (a ``generators.Values``)."""

    def check(value: Any, info: ValidationInfo) -> Any:
        if value is None or isinstance(value, Values):
            return value
        if isinstance(value, (Mapping, list, tuple)):
            base = (info.context or {}).get("base_dir", ".")
            try:
                return generators.check(value, text=text, base_dir=base)
            except ValuesError as exc:
                raise _fail([_Issue(exc.reason, exc.sub)]) from None
        if text:
            name = _check_str(value)
            if name not in MATERIALS:
                raise _fail([_Issue(f"unknown material {show_value(name)}"
                                    f"{_suggest(name, list(MATERIALS))} (known: "
                                    f"{', '.join(MATERIALS)})")])
            return name
        x = _check_float(value)
        reason = _rule_reason(key, x)
        if reason:
            raise _fail([_Issue(f"{reason}, got {show_value(value)}")])
        return x

    return BeforeValidator(check)


def _dump_values(value: Any) -> Any:
    return value.to_json() if isinstance(value, Values) else value


_Dump = PlainSerializer(_dump_values)
_PerItem = Annotated[Any, _Dump]


def _check_damping_law(value: Any) -> str | None:
    if value is None:
        return None
    name = _check_str(value)
    if name not in collision.LAWS:
        raise _fail([_Issue(f"unknown damping law {show_value(name)}"
                            f"{_suggest(name, list(collision.LAWS))} (known: "
                            f"{', '.join(collision.LAWS)})")])
    return name


_OptLaw = Annotated[str | None, BeforeValidator(_check_damping_law)]


def _dissipation_issues(model: BaseModel) -> list[_Issue]:
    """Conflicts among a chain's or a wall's dissipation keys.

    A contact's damping is given either as ``damping`` (eta), with its exponent as
    ``damping_exponent`` or from ``damping_law``, or as ``restitution`` with
    ``damping_law`` (and ``restitution_speed`` where e depends on the impact speed,
    which ``build_line`` judges per contact from its exponent).
    """
    def given(key: str) -> bool:
        return getattr(model, key) is not None

    issues: list[_Issue] = []
    if given("restitution"):
        issues += [_Issue("give restitution or damping, not both", (key,))
                   for key in ("damping", "damping_exponent") if given(key)]
        if not given("damping_law"):
            issues.append(_Issue(f"required with restitution (one of "
                                 f"{', '.join(collision.LAWS)})", ("damping_law",)))
    else:
        if given("restitution_speed"):
            issues.append(_Issue("given without restitution", ("restitution_speed",)))
        if given("damping_law") and given("damping_exponent"):
            issues.append(_Issue("set by damping_law; give one or the other",
                                 ("damping_exponent",)))
        elif given("damping_law") and not given("damping"):
            issues.append(_Issue("needs damping or restitution", ("damping_law",)))
        elif given("damping_exponent") and not given("damping"):
            issues.append(_Issue("given without damping", ("damping_exponent",)))
    return issues


# --- drives: a wall's motion, forces in time on chosen balls ------------------------------

@dataclass(frozen=True, eq=False)
class DriveSpec:
    """A checked drive of an experiment file: ``walls.<side>.motion`` (a displacement)
    or one entry of ``chain.drive`` (a force on ``ball``, numbered from 1).

    ``table`` is what the file holds, as canonical JSON (a file's table gains the
    sha256 of its data, as a generator's does); ``drive`` the function of time
    (``chainrun.solver.Drive``)."""

    table: str
    drive: Drive
    ball: int | None = None
    index: int | None = None  # its place in a list of them (chain.drive)

    def to_json(self) -> Any:
        return json.loads(self.table)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, DriveSpec) and (self.table, self.ball) == (other.table,
                                                                           other.ball)

    def __hash__(self) -> int:
        return hash((self.table, self.ball))

    @property
    def sine(self) -> bool:
        """Whether it is one sine table (whose keys a sweep may vary)."""
        table = self.to_json()
        return isinstance(table, Mapping) and "file" not in table


def _number_issue(table: Mapping, key: str, sub: tuple[str, ...], low: float | None = None,
                  strict: bool = True) -> tuple[float | None, list[_Issue]]:
    """``table[key]`` as a finite number (above ``low``), or the issue."""
    try:
        x = _check_float(table[key])
    except PydanticCustomError as exc:
        return None, [i._replace(sub=sub + (key,)) for i in exc.context["issues"]]
    if low is not None and (x <= low if strict else x < low):
        op = ">" if strict else ">="
        return None, [_Issue(f"must be {op} {_bound(low)}, got {show_value(table[key])}",
                             sub + (key,))]
    return x, []


def _drive_table(table: Any, sub: tuple[str, ...], base_dir: str, what: str,
                 ball: bool) -> tuple[dict | None, Any, list[_Issue]]:
    """One table of a drive: a sine ``{amplitude, frequency, ramp}`` or ``{file}`` (with
    ``ball`` in ``chain.drive``). Returns its JSON form, a ``Sine`` or the samples
    ``(times, values)``, and its issues."""
    shape = "{ball, amplitude, frequency, ramp}" if ball else "{amplitude, frequency, ramp}"
    if not isinstance(table, Mapping):
        return None, None, [_Issue(f"expected a table {shape} or {{file}}, got "
                                   f"{show_value(table)}", sub)]
    keys = [str(k) for k in table]
    allowed = (("file",) if "file" in keys else SINE_KEYS) + (("ball",) if ball else ())
    alone = " (a drive from a file takes no other key)" if "file" in keys else ""
    issues = [_Issue(f"unknown key{_suggest(k, list(allowed)) or alone}",
                     sub + (_key_text(k),)) for k in keys if k not in allowed]
    out: dict[str, Any] = {}
    if ball:
        if "ball" not in table:
            issues.append(_Issue("required (the driven ball, from 1)", sub + ("ball",)))
        else:
            try:
                number = _check_int(table["ball"])
            except PydanticCustomError as exc:
                issues += [i._replace(sub=sub + ("ball",)) for i in exc.context["issues"]]
            else:
                if number < 1:
                    issues.append(_Issue(f"must be a ball number >= 1, got {number}",
                                         sub + ("ball",)))
                out["ball"] = number
    if "file" in keys:
        try:
            name = _check_str(table["file"])
        except PydanticCustomError as exc:
            return None, None, issues + [i._replace(sub=sub + ("file",))
                                         for i in exc.context["issues"]]
        path = os.path.join(base_dir, name)
        try:
            rows = generators.read_rows(path, 2)
            digest = generators.digest(path)
        except FileNotFoundError:
            return None, None, issues + [_Issue(f"no such file {path}", sub + ("file",))]
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            return None, None, issues + [_Issue(f"cannot read {path}: {reason}",
                                                sub + ("file",))]
        t, u = rows[:, 0], rows[:, 1]
        problem = None
        if t.size < 2:
            problem = f"{path} holds {t.size} rows: a drive needs at least two (time, {what})"
        elif not (np.all(np.isfinite(t)) and np.all(np.isfinite(u))):
            problem = f"{path} holds a value that is not finite"
        elif t[0] != 0.0:
            problem = f"{path}: the first time must be 0, got {float(t[0])!r}"
        elif np.any(np.diff(t) <= 0.0):
            i = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
            problem = (f"{path}: times must increase, got {float(t[i])!r} after "
                       f"{float(t[i - 1])!r} (row {i + 1})")
        elif what == "displacement" and u[0] != 0.0:
            problem = (f"{path}: the wall starts at its place, so its displacement at t = 0 "
                       f"must be 0, got {float(u[0])!r}")
        if problem:
            return None, None, issues + [_Issue(problem, sub + ("file",))]
        out.update(file=name, sha256=digest)
        return (out, (t, u), issues) if not issues else (None, None, issues)
    got: dict[str, float] = {}
    for key, low, strict in (("amplitude", None, True), ("frequency", 0.0, True),
                             ("ramp", 0.0, False)):
        if key not in table:
            if key != "ramp":
                issues.append(_Issue("required", sub + (key,)))
            continue
        x, found = _number_issue(table, key, sub, low, strict)
        issues += found
        if x is not None:
            got[key] = x
    if issues:
        return None, None, issues
    out.update(got)
    from chainrun.solver import Sine

    return out, Sine(got["amplitude"], got["frequency"], got.get("ramp", 0.0)), []


def _check_drive(value: Any, base_dir: str, what: str) -> DriveSpec:
    """``walls.<side>.motion``: a sine table, a list of them (their sum), or ``{file}``."""
    if isinstance(value, DriveSpec):
        return value
    tables = value if isinstance(value, (list, tuple)) else [value]
    if isinstance(value, (list, tuple)) and not value:
        raise _fail([_Issue("expected a table or a non-empty list of tables")])
    listed = isinstance(value, (list, tuple))
    issues: list[_Issue] = []
    parts = []
    for i, table in enumerate(tables):
        sub = (f"[{i}]",) if listed else ()
        out, part, found = _drive_table(table, sub, base_dir, what, False)
        issues += found
        if listed and isinstance(part, tuple):
            issues.append(_Issue("a file drives alone: give {file} without a list", sub))
        parts.append((out, part))
    if issues:
        raise _fail(issues)
    if isinstance(parts[0][1], tuple):
        drive = Drive.from_samples(*parts[0][1])
    else:
        drive = Drive.of_sines([p for _, p in parts])
    table = [o for o, _ in parts] if listed else parts[0][0]
    return DriveSpec(json.dumps(table, sort_keys=True), drive)


def _check_ball_drives(value: Any, base_dir: str) -> tuple[DriveSpec, ...]:
    """``chain.drive``: a table ``{ball, amplitude, frequency, ramp}`` or ``{ball, file}``,
    or a list of them (several on one ball add up)."""
    if isinstance(value, tuple) and all(isinstance(v, DriveSpec) for v in value):
        return value
    listed = isinstance(value, (list, tuple))
    tables = value if listed else [value]
    if listed and not value:
        raise _fail([_Issue("expected a table or a non-empty list of tables")])
    issues: list[_Issue] = []
    specs = []
    for i, table in enumerate(tables):
        sub = (f"[{i}]",) if listed else ()
        out, part, found = _drive_table(table, sub, base_dir, "force", True)
        issues += found
        if found:
            continue
        drive = Drive.from_samples(*part) if isinstance(part, tuple) else Drive.of_sines([part])
        specs.append(DriveSpec(json.dumps({k: v for k, v in out.items() if k != "ball"},
                                          sort_keys=True), drive, out["ball"],
                               i if listed else None))
    if issues:
        raise _fail(issues)
    return tuple(specs)


def _drive_validator(what: str):
    def check(value: Any, info: ValidationInfo) -> Any:
        if value is None:
            return None
        base = (info.context or {}).get("base_dir", ".")
        if what == "force":
            return _check_ball_drives(value, base)
        return _check_drive(value, base, what)

    return BeforeValidator(check)


def _dump_drive(value: Any) -> Any:
    if isinstance(value, DriveSpec):
        return value.to_json()
    if isinstance(value, tuple):
        return [{"ball": v.ball, **v.to_json()} for v in value]
    return value


_DumpDrive = PlainSerializer(_dump_drive)


class Chain(BaseModel):
    """The line of balls: ``n`` balls; their masses, contacts (stiffness, exponent
    ``alpha``, gap), initial velocities (the first ``k`` at ``speed``, or ``velocity``
    for each) and external forces; or, in SI, their diameters and materials.

    Per-ball and per-contact keys hold a number, a list or a generator table
    (``chainrun.generators``); a number is kept a float (a material a str), the others
    a ``generators.Values``. Keys left out are None.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    n: _Int = Field(ge=1)
    velocity: Annotated[Any, _values("velocity"), _Dump] = None
    k: _OptInt = Field(None, ge=0, validate_default=True)
    speed: _OptFloat = None
    material: Annotated[Any, _values("material", text=True), _Dump] = None
    young: Annotated[Any, _values("young"), _Dump] = None
    poisson: Annotated[Any, _values("poisson"), _Dump] = None
    density: Annotated[Any, _values("density"), _Dump] = None
    diameter: Annotated[Any, _values("diameter"), _Dump] = None
    alpha: Annotated[Any, _values("alpha"), _Dump] = Field(None, validate_default=True)
    mass: Annotated[Any, _values("mass"), _Dump] = None
    stiffness: Annotated[Any, _values("stiffness"), _Dump] = None
    gap: Annotated[Any, _values("gap"), _Dump] = None
    force: Annotated[Any, _values("force"), _Dump] = None
    precompression: _OptFloat = Field(None, ge=0)
    damping: Annotated[Any, _values("damping"), _Dump] = None
    damping_exponent: Annotated[Any, _values("damping_exponent"), _Dump] = None
    restitution: Annotated[Any, _values("restitution"), _Dump] = None
    damping_law: _OptLaw = None
    restitution_speed: _OptFloat = Field(None, gt=0)
    drive: Annotated[Any, _drive_validator("force"), _DumpDrive] = None

    @field_validator("k")
    @classmethod
    def _k_at_most_n(cls, k: int | None, info: ValidationInfo) -> int | None:
        if k is None:
            # required unless the velocities are given (absent from data: invalid)
            if info.data.get("velocity", "invalid") is None:
                raise _fail([_Issue("required")])
            return k
        n = info.data.get("n")  # absent when n itself is invalid
        if n is not None and k > n:
            raise _fail([_Issue(f"must be <= chain.n ({n}), got {k}", involves=("n",))])
        return k

    @field_validator("alpha")
    @classmethod
    def _alpha_unless_real(cls, alpha: Any, info: ValidationInfo) -> Any:
        # required unless a material's Hertz law sets it (3/2), or there is no contact
        # between balls (one ball: a wall has its own alpha)
        real = ("material", "young", "poisson", "density")
        if alpha is None and all(key in info.data and info.data[key] is None for key in real) \
                and info.data.get("n") != 1:
            raise _fail([_Issue("required", involves=("n",))])
        return alpha

    @field_validator("speed")
    @classmethod
    def _speed_not_zero(cls, speed: float | None) -> float | None:
        if speed == 0.0:
            raise _fail([_Issue("must not be 0 (the first k balls strike at this speed)")])
        return speed

    @model_validator(mode="after")
    def _consistent(self) -> "Chain":
        issues: list[_Issue] = []
        if self.velocity is not None:
            for key in ("k", "speed"):
                if getattr(self, key) is not None:
                    issues.append(_Issue("give chain.velocity or chain.k, not both", (key,)))
        issues += _dissipation_issues(self)
        if issues:
            raise _fail(issues)
        return self

    @property
    def is_paper(self) -> bool:
        """Only n, k and a scalar alpha: the paper's line (built without arrays)."""
        return (self.velocity is None and isinstance(self.alpha, float)
                and all(getattr(self, key) is None for key in type(self).model_fields
                        if key not in ("n", "k", "alpha")))


class WallSettings(BaseModel):
    """A flat wall at one end of the line: its contact with the end ball has a
    stiffness, an exponent and a gap; or, in SI, the wall is of a ``material``. Its
    damping is given as a chain's is (``damping`` and ``damping_exponent``, or
    ``restitution`` with ``damping_law``), one value for its one contact. A ``motion``
    (a ``DriveSpec``) moves it about its place."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    stiffness: _OptFloat = Field(None, gt=0)
    alpha: _OptFloat = Field(None, ge=1, le=MAX_ALPHA)
    gap: _Float = 0.0
    material: str | None = None
    damping: _OptFloat = Field(None, ge=0)
    damping_exponent: _OptFloat = Field(None, ge=0)
    restitution: _OptFloat = Field(None, gt=0, le=1)
    damping_law: _OptLaw = None
    restitution_speed: _OptFloat = Field(None, gt=0)
    motion: Annotated[Any, _drive_validator("displacement"), _DumpDrive] = None

    @field_validator("material", mode="before")
    @classmethod
    def _material(cls, value: Any) -> str | None:
        if value is None:
            return None
        name = _check_str(value)
        if name not in MATERIALS:
            raise _fail([_Issue(f"unknown material {show_value(name)}"
                                f"{_suggest(name, list(MATERIALS))}"
                                f" (known: {', '.join(MATERIALS)})")])
        return name

    @model_validator(mode="after")
    def _one_law(self) -> "WallSettings":
        issues: list[_Issue] = []
        if self.material is not None:
            issues += [_Issue("the material's Hertz law sets it; give one or the other", (key,))
                       for key in ("stiffness", "alpha") if getattr(self, key) is not None]
        issues += _dissipation_issues(self)
        if issues:
            raise _fail(issues)
        return self


class Walls(BaseModel):
    """Optional walls at the left (before ball 1) and right (after ball N) ends."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    left: WallSettings | None = None
    right: WallSettings | None = None

    @field_validator("left", "right", mode="before")
    @classmethod
    def _empty_wall(cls, value: Any) -> Any:
        return {} if value is None else value  # YAML ``right:`` with nothing under it


# --- the line an experiment describes -----------------------------------------------------


class LineError(Exception):
    """Problems building a line, as ``key: reason`` problems."""

    def __init__(self, problems: list["_Problem"]):
        super().__init__("; ".join(p.line() for p in problems))
        self.problems = problems


def _expanded(chain: Chain, key: str, size: int, problems: list["_Problem"],
              prefix: str = "chain") -> np.ndarray | None:
    """The values of ``chain.<key>`` expanded to ``size`` and checked (None if absent
    or wrong; the problem is added to ``problems``)."""
    value = getattr(chain, key)
    if value is None:
        return None
    values = value if isinstance(value, Values) else Values(scalar=value)
    try:
        a = generators.expand(values, size)
    except ValuesError as exc:
        problems.append(_Problem(_key_path((prefix, key) + exc.sub), exc.reason))
        return None
    if key == "material":
        unknown = [i for i, name in enumerate(a) if name not in MATERIALS]
        if unknown:
            i = unknown[0]
            problems.append(_Problem(f"{prefix}.{key}[{i}]", f"unknown material "
                                     f"{show_value(a[i])} (known: {', '.join(MATERIALS)})"))
            return None
        return a
    bad = ~np.isfinite(a)
    low, strict, high, _ = _RULES[key]
    with np.errstate(invalid="ignore"):
        if low is not None:
            bad |= (a <= low) if strict else (a < low)
        if high is not None:
            bad |= (a >= high) if key == "poisson" else (a > high)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        x = float(a[i])
        reason = "must be finite" if not math.isfinite(x) else _rule_reason(key, x)
        problems.append(_Problem(f"{prefix}.{key}[{i}]", f"{reason}, got {show_value(x)}"))
        return None
    return a


def _velocities(chain: Chain, problems: list["_Problem"]) -> np.ndarray | None:
    if chain.velocity is not None:
        return _expanded(chain, "velocity", chain.n, problems)
    v = np.zeros(chain.n)
    v[:chain.k] = 1.0 if chain.speed is None else chain.speed
    return v


def build_line(chain: Chain, walls: "Walls", units: str) -> Line:
    """The ``Line`` an experiment's chain and walls describe, in its ``units``.

    In SI, balls given by ``diameter`` and a ``material`` (a preset of
    ``chainrun.materials`` or ``young``, ``poisson`` and ``density``) get the mass
    ``rho pi d^3 / 6`` and Hertz contacts (``physics.hertz_stiffness``, alpha = 3/2); a
    wall of a ``material`` is a flat body of it (R* = R of the end ball), and a wall
    with neither stiffness nor material is of the end ball's material. With
    ``precompression`` the resting balls start at equilibrium under that load
    (``chainrun.solver.model.precompress``): pushed by a constant force against the
    right wall, or, between two walls, held by them, the left wall placed where every
    contact carries the load.

    Raises
    ------
    LineError
        Every problem found, each naming its key (and index).
    """
    problems: list[_Problem] = []
    n = chain.n
    real = [key for key in _SI_KEYS if getattr(chain, key) is not None]
    wall_real = [side for side in ("left", "right")
                 if getattr(walls, side) is not None and getattr(walls, side).material]
    if units != "si":
        problems += [_Problem(f"chain.{key}", 'needs units = "si" (real spheres)')
                     for key in real]
        problems += [_Problem(f"walls.{side}.material", 'needs units = "si" (real spheres)')
                     for side in wall_real]
        if problems:
            raise LineError(problems)
    young = poisson = diameter = names = None
    line_kw: dict[str, Any] = {}
    if real:
        explicit = [key for key in ("young", "poisson", "density") if getattr(chain, key) is not None]
        if chain.material is not None and explicit:
            problems += [_Problem(f"chain.{key}", "give chain.material or explicit constants, "
                                  "not both") for key in explicit]
        elif chain.material is None and len(explicit) < 3:
            problems += [_Problem(f"chain.{key}", "required with explicit constants "
                                  "(or give chain.material)")
                         for key in ("young", "poisson", "density") if key not in explicit]
        if chain.diameter is None:
            problems.append(_Problem("chain.diameter", "required with a material (m)"))
        for key in ("mass", "stiffness", "alpha"):
            if getattr(chain, key) is not None:
                problems.append(_Problem(f"chain.{key}", "set by the material and diameter "
                                         "(Hertz, alpha = 3/2); give one or the other"))
        if problems:
            raise LineError(problems)
        diameter = _expanded(chain, "diameter", n, problems)
        if chain.material is not None:
            names = _expanded(chain, "material", n, problems)
            if names is not None:
                young = np.array([MATERIALS[m].young for m in names])
                poisson = np.array([MATERIALS[m].poisson for m in names])
                density = np.array([MATERIALS[m].density for m in names])
        else:
            young = _expanded(chain, "young", n, problems)
            poisson = _expanded(chain, "poisson", n, problems)
            density = _expanded(chain, "density", n, problems)
        if problems:
            raise LineError(problems)
        radius = diameter / 2.0
        line_kw["diameter"] = diameter
        line_kw["material"] = names if chain.material is not None else ""
        line_kw["mass"] = physics.sphere_mass(density, diameter)
        line_kw["stiffness"] = physics.hertz_stiffness(young[:-1], poisson[:-1], radius[:-1],
                                                       young[1:], poisson[1:], radius[1:])
        line_kw["alpha"] = 1.5
    else:
        for key in ("mass", "stiffness", "alpha"):
            size = n if _RULES[key][3] == "ball" else n - 1
            a = _expanded(chain, key, size, problems)
            if a is not None:
                line_kw[key] = a
    for key in ("gap",):
        a = _expanded(chain, key, n - 1, problems)
        if a is not None:
            line_kw[key] = a
    force = _expanded(chain, "force", n, problems)
    if force is not None:
        line_kw["force"] = force
    velocity = _velocities(chain, problems)

    built: dict[str, Wall] = {}
    for side in ("left", "right"):
        spec = getattr(walls, side)
        if spec is None:
            continue
        end = 0 if side == "left" else n - 1
        if spec.material is not None and young is None:
            problems.append(_Problem(f"walls.{side}.material", "needs the balls' materials "
                                     "(chain.material and chain.diameter)"))
            continue
        if spec.material is not None or (spec.stiffness is None and young is not None):
            if spec.stiffness is None and spec.alpha is not None and spec.material is None:
                problems.append(_Problem(f"walls.{side}.alpha", "a wall of the end ball's "
                                         "material is Hertz (3/2); give its stiffness too"))
                continue
            wall = MATERIALS[spec.material] if spec.material else None
            stiffness = float(physics.hertz_stiffness(
                young[end], poisson[end], diameter[end] / 2.0,
                wall.young if wall else young[end], wall.poisson if wall else poisson[end]))
            built[side] = Wall(stiffness, 1.5, spec.gap)
            continue
        if spec.stiffness is None and units == "si":
            problems.append(_Problem(f"walls.{side}.stiffness", "required in SI (N/m^alpha), "
                                     "or give the wall a material"))
            continue
        alpha = spec.alpha
        if alpha is None and (n > 1 or real):  # the law of the contact next to it
            alpha = float(np.asarray(line_kw["alpha"]).reshape(-1)[0 if side == "left" else -1])
        elif alpha is None:  # one ball: no contact next to it, but the chain's alpha
            if not isinstance(chain.alpha, float):
                problems.append(_Problem(f"walls.{side}.alpha", "required: a line of one "
                                         "ball has no contact whose exponent the wall could "
                                         "take (or give chain.alpha)"))
                continue
            alpha = chain.alpha
        built[side] = Wall(1.0 if spec.stiffness is None else spec.stiffness, alpha, spec.gap)
    for side, wall in built.items():
        spec = getattr(walls, side)
        if spec.motion is not None:
            built[side] = replace(wall, motion=spec.motion.drive)
    if chain.drive is not None and n == 1 and walls.left is None and walls.right is None:
        problems.append(_Problem("chain.drive", "a lone ball without walls touches nothing: "
                                 "its drive alone moves it, with nothing to solve"))
    if chain.drive is not None:
        drives = []
        for i, spec in enumerate(chain.drive):
            if spec.ball > n:
                where = ("chain.drive.ball" if spec.index is None
                         else f"chain.drive[{spec.index}].ball")
                problems.append(_Problem(where, f"ball {spec.ball} is beyond chain.n ({n})"))
            drives.append((spec.ball - 1, spec.drive))
        line_kw["drives"] = drives
    if problems:
        raise LineError(problems)
    try:
        line = Line.make(n, velocity=velocity, left=built.get("left"),
                         right=built.get("right"), **line_kw)
    except ValueError as exc:  # not expected: every value was checked above
        raise LineError([_Problem("chain", str(exc))]) from None
    line = _with_dissipation(line, chain, walls)
    if chain.precompression:
        if force is not None and np.any(force != 0.0):
            raise LineError([_Problem("chain.precompression", "sets the external force "
                                      "itself; leave chain.force out")])
        if walls.left is not None and walls.right is not None and walls.left.gap != 0.0:
            raise LineError([_Problem("walls.left.gap", "set by chain.precompression "
                                      "between two walls (the left wall is placed where "
                                      "every contact carries the load); leave it out")])
        try:
            line = precompress(line, chain.precompression)
        except ValueError as exc:
            raise LineError([_Problem("chain.precompression", str(exc))]) from None
    return line


def _damping_of(prefix: str, spec: Any, damping, restitution, kappa: np.ndarray,
                alpha: np.ndarray, mu: np.ndarray, problems: list["_Problem"]):
    """(eta, beta) of contacts of stiffness ``kappa``, exponent ``alpha`` and reduced
    mass ``mu`` (arrays alike) from the dissipation keys of ``spec`` (a chain or a
    wall; ``damping`` and ``restitution`` already expanded to arrays, or None), or None
    for elastic contacts (the keys absent) or a problem (added to ``problems``)."""
    law = spec.damping_law
    if restitution is not None:
        beta = np.array([collision.law_exponent(law, a) for a in alpha.reshape(-1)])
        needs = (restitution < 1.0) & (beta != (alpha - 1.0) / 2.0)
        if spec.restitution_speed is None and np.any(needs):
            i = int(np.flatnonzero(needs)[0])
            where = f"contact {i}, " if prefix == "chain" else ""
            problems.append(_Problem(f"{prefix}.restitution_speed", f"required: the "
                                     f"restitution of the {law} law depends on the impact "
                                     f"speed ({where}alpha = {_bound(float(alpha[i]))}); give "
                                     "the speed it holds at"))
            return None
        try:
            eta = collision.damping_for_restitution(restitution, law, kappa, alpha, mu,
                                                    spec.restitution_speed)
        except (ValueError, RuntimeError) as exc:  # not expected: inputs were checked
            problems.append(_Problem(f"{prefix}.restitution", str(exc)))
            return None
        return np.asarray(eta, dtype=float), beta
    if damping is None:
        return None
    if spec.damping_exponent is not None:
        return damping, None
    if law is not None:
        return damping, np.array([collision.law_exponent(law, a) for a in alpha.reshape(-1)])
    return damping, np.zeros_like(damping)


def _with_dissipation(line: Line, chain: Chain, walls: "Walls") -> Line:
    """``line`` with the damping its chain's and walls' keys describe (eta from a
    restitution by ``chainrun.solver.restitution``, with the reduced mass of each
    contact, ``m_j m_(j+1) / (m_j + m_(j+1))``, and a wall's the end ball's mass)."""
    problems: list[_Problem] = []
    changes: dict[str, Any] = {}
    m = line.mass
    size = line.n - 1
    damping = _expanded(chain, "damping", size, problems)
    restitution = _expanded(chain, "restitution", size, problems)
    exponent = _expanded(chain, "damping_exponent", size, problems)
    if problems:
        raise LineError(problems)
    mu = m[:-1] * m[1:] / (m[:-1] + m[1:])
    got = _damping_of("chain", chain, damping, restitution, np.asarray(line.stiffness),
                      np.asarray(line.alpha), mu, problems)
    if got is not None:
        changes["damping"] = got[0]
        changes["damping_exponent"] = exponent if got[1] is None else got[1]
    for side, end in (("left", 0), ("right", line.n - 1)):
        spec, wall = getattr(walls, side), getattr(line, side)
        if spec is None or wall is None:
            continue
        got = _damping_of(f"walls.{side}", spec,
                          None if spec.damping is None else np.array([spec.damping]),
                          None if spec.restitution is None else np.array([spec.restitution]),
                          np.array([wall.stiffness]), np.array([wall.alpha]),
                          np.array([m[end]]), problems)
        if got is not None:
            beta = spec.damping_exponent if got[1] is None else float(got[1][0])
            changes[side] = replace(wall, damping=float(got[0][0]), damping_exponent=beta)
    if problems:
        raise LineError(problems)
    return replace(line, **changes) if changes else line


def _needs_t_end(chain: Chain, walls: "Walls", t_end: float | None) -> list["_Problem"]:
    """The problem of a line with no terminal state run without a stop time, judged
    from its keys (a generated force is judged when the line is built)."""
    if t_end is not None:
        return []
    reasons = []
    if chain.precompression and walls.left is None:
        reasons.append("chain.precompression keeps pushing")
    elif isinstance(chain.force, float) and chain.force != 0.0:
        reasons.append("chain.force keeps doing work")
    elif isinstance(chain.force, Values) and chain.force.items is not None and any(
            chain.force.items):
        reasons.append("chain.force keeps doing work")
    if walls.left is not None and walls.right is not None:
        reasons.append("the line is held between two walls")
    for side in ("left", "right"):
        wall = getattr(walls, side)
        if wall is not None and wall.motion is not None:
            reasons.append(f"walls.{side}.motion drives it")
    if chain.drive is not None:
        reasons.append("chain.drive drives it")
    if not reasons:
        return []
    return [_Problem("solver.t_end", f"required: {' and '.join(reasons)}, so the run "
                     "has no terminal state", frozenset({"chain.force",
                                                         "chain.precompression"}))]


def _expand_range(table: Mapping[str, Any]) -> tuple[tuple[float, ...], list[_Issue]]:
    """Snapshot times ``start, start + step, ...`` up to ``stop`` inclusive (to rounding)."""
    issues: list[_Issue] = []
    fields = ["start", "stop", "step"]
    for key in table:
        if key not in fields:
            issues.append(_Issue(f"unknown key{_suggest(str(key), fields)}", (_key_text(key),)))
    got: dict[str, float] = {}
    for key in fields:
        if key not in table:
            issues.append(_Issue("required", (key,)))
            continue
        try:
            got[key] = _check_float(table[key])
        except PydanticCustomError as exc:
            issues.extend(i._replace(sub=(key,)) for i in exc.context["issues"])
    if "start" in got and got["start"] < 0:
        issues.append(_Issue(f"must be non-negative, got {got['start']!r}", ("start",)))
    if "step" in got and got["step"] <= 0:
        issues.append(_Issue(f"must be > 0, got {got['step']!r}", ("step",)))
    if "start" in got and "stop" in got and got["stop"] < got["start"]:
        issues.append(
            _Issue(f"must be >= output.times.start ({got['start']!r}), got {got['stop']!r}", ("stop",))
        )
    if issues:
        return (), issues
    start, stop, step = got["start"], got["stop"], got["step"]
    m = (stop - start) / step  # inf when step is tiny (1e-308)
    if not m < MAX_RANGE_TIMES:
        return (), [_Issue(f"a range of {m + 1:.4g} times is too many (at most {MAX_RANGE_TIMES})")]
    steps = round(m) if abs(m - round(m)) <= 1e-9 * max(1.0, m) else math.floor(m)
    if steps + 1 > MAX_RANGE_TIMES:
        return (), [_Issue(f"a range of {steps + 1} times is too many (at most {MAX_RANGE_TIMES})")]
    times = start + step * np.arange(steps + 1, dtype=np.float64)
    times[-1] = min(times[-1], stop)  # stop inclusive: do not let rounding step past it
    return tuple(float(t) for t in times), []


def _sensor_balls(value: Any) -> tuple[list[tuple[int, int]], list[_Issue]]:
    """The valid ball numbers of ``output.sensors``, each with its position in the
    list, and every problem of the others."""
    if not isinstance(value, (list, tuple)):
        return [], [_Issue(f"expected a list of ball numbers, got {show_value(value)}")]
    issues: list[_Issue] = []
    balls: list[int] = []
    kept: list[tuple[int, int]] = []
    for position, item in enumerate(value):
        try:
            ball = _check_int(item)
        except PydanticCustomError as exc:
            issues.extend(i._replace(reason=f"{i.reason} at position {position}")
                          for i in exc.context["issues"])
            continue
        if ball < 1:
            issues.append(_Issue(f"must be a ball number >= 1, got {ball} at position "
                                 f"{position}"))
        elif ball in balls:
            issues.append(_Issue(f"ball {ball} is listed twice (position {position})"))
        else:
            balls.append(ball)
            kept.append((position, ball))
    return kept, issues


class Output(BaseModel):
    """What to record: snapshot times, a list or a ``{start, stop, step}`` range, and
    force sensors: balls whose contact forces are sampled every ``sensor_dt``."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    times: tuple[float, ...] = ()
    sensors: tuple[int, ...] = ()
    sensor_dt: _OptFloat = Field(None, gt=0, validate_default=True)
    sensor_end: _OptFloat = Field(None, gt=0)

    @field_validator("sensors", mode="before")
    @classmethod
    def _sensors(cls, value: Any) -> tuple[int, ...]:
        kept, issues = _sensor_balls(value)
        if issues:
            raise _fail(issues)
        return tuple(ball for _, ball in kept)

    @field_validator("sensor_dt", "sensor_end", mode="after")
    @classmethod
    def _sensors_and_interval(cls, value: float | None, info: ValidationInfo) -> float | None:
        # sensors absent from info.data: given, but wrong (reported with them)
        given = info.data.get("sensors", True)
        if given and value is None and info.field_name == "sensor_dt":
            raise _fail([_Issue("required with output.sensors (the sampling interval)")])
        if value is not None and not given:
            raise _fail([_Issue("given without output.sensors")])
        return value

    @field_validator("times", mode="before")
    @classmethod
    def _times(cls, value: Any) -> tuple[float, ...]:
        if isinstance(value, Mapping):
            times, issues = _expand_range(value)
            if issues:
                raise _fail(issues)
            return times
        if not isinstance(value, (list, tuple)):
            raise _fail(
                [_Issue("expected a list of times or a table {start, stop, step}, got "
                        f"{show_value(value)}")]
            )
        issues: list[_Issue] = []
        times: list[float] = []
        previous: float | None = None
        for position, item in enumerate(value):
            try:
                t = _check_float(item)
            except PydanticCustomError as exc:
                issues.extend(
                    i._replace(reason=f"{i.reason} at position {position}") for i in exc.context["issues"]
                )
                continue
            if t < 0:
                issues.append(_Issue(f"must be non-negative, got {t!r} at position {position}"))
            if previous is not None and t < previous:
                issues.append(
                    _Issue(f"must be non-decreasing, got {t!r} after {previous!r} (position {position})")
                )
            previous = t
            times.append(t)
        if issues:
            raise _fail(issues)
        return tuple(times)


class SolverSettings(BaseModel):
    """How to run: an optional stop time, step accuracy and event limit, and whether
    to check which digits of the answer hold.

    ``t_end = None`` runs to the terminal state (no contact can ever close again).
    ``check`` runs each line a second time at ``chainrun.check.check_rtol(rtol)`` and
    stores the spread of every ball's velocities; it adds a measurement, not another
    answer, so it is left out of the run's resolved configuration and its hash.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    t_end: _OptFloat = Field(None, gt=0)
    rtol: _Float = Field(DEFAULT_RTOL, ge=MIN_RTOL, le=1e-3)
    max_events: _OptInt = Field(None, gt=0)
    check: _Bool = False


#: A generator table's numeric keys that a sweep may vary, ``"chain.<key>.<field>"``
#: (``"chain.mass.seed" = [1, 2, 3]``), and their type.
GENERATOR_FIELDS: dict[str, type] = {
    "seed": int, "low": float, "high": float, "median": float, "sigma": float,
    "taper": float, "start": float, "value": float,
}
#: The ``[sweep]`` key that asks for that many runs of the line, each drawing its
#: random values with the file's seeds plus the run's replica number (0, 1, ...).
REPLICAS = "replicas"
#: Most replicas a sweep may ask for (each is a run).
MAX_REPLICAS = 10_000


def _generator_key(key: str) -> tuple[str, str] | None:
    """``("mass", "seed")`` for ``"chain.mass.seed"``: a generator's field of a per-ball
    or per-contact key of the chain; None for any other key."""
    parts = key.split(".")
    if (len(parts) == 3 and parts[0] == "chain" and parts[1] in _RULES
            and parts[2] in GENERATOR_FIELDS):
        return parts[1], parts[2]
    return None


def sweep_type(key: str) -> type | None:
    """The type of a sweep key's values, or None for a key that cannot be swept."""
    if key in SWEEPABLE_KEYS:
        return SWEEPABLE_KEYS[key]
    generator = _generator_key(key)
    return None if generator is None else GENERATOR_FIELDS[generator[1]]


def _flatten_sweep(table: Mapping[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``{"chain": {"k": [...]}}`` (TOML's unquoted ``chain.k = [...]``) as ``chain.k``.

    At most three levels are unfolded (sweepable keys have two or three parts, as
    ``walls.right.gap`` or ``chain.mass.seed``), so a deep or cyclic table (YAML
    aliases) is reported as an unknown key rather than recursed into.
    """
    items: list[tuple[str, Any]] = []
    for key, value in table.items():
        dotted = f"{prefix}{_key_text(key)}"
        if (isinstance(value, Mapping) and prefix.count(".") < 2
                and (not prefix or dotted in ("walls.left", "walls.right")
                     or (prefix == "chain." and dotted.removeprefix("chain.") in _RULES))):
            items.extend(_flatten_sweep(value, dotted + "."))
        else:
            items.append((dotted, value))
    return items


def _check_sweep(value: Any) -> tuple[dict[str, tuple[Any, ...]], set[str], list[_Issue]]:
    """The valid entries of a sweep table, every sweepable key it names, and its issues."""
    if value is None:
        return {}, set(), []
    if not isinstance(value, Mapping):
        return {}, set(), [_Issue(f"expected a table, got {show_value(value)}")]
    valid: dict[str, tuple[Any, ...]] = {}
    named: set[str] = set()
    issues: list[_Issue] = []
    for key, values in _flatten_sweep(value):
        if key == REPLICAS:
            try:
                count = _check_int(values)
            except PydanticCustomError:
                count = 0
            if not 1 <= count <= MAX_REPLICAS:
                issues.append(_Issue(f"expected a number of runs from 1 to {MAX_REPLICAS}, "
                                     f"got {show_value(values)}", (key,)))
            else:
                named.add("replica")
                valid["replica"] = tuple(range(count))
            continue
        if sweep_type(key) is None:
            issues.append(_Issue(f"unknown key '{key}'"
                                 f"{_suggest(key, [*SWEEPABLE_KEYS, REPLICAS])}"))
            continue
        sub = (key,)
        if key in named:  # "chain.k" and chain = {k = ...} in one table
            issues.append(_Issue("given twice", sub))
            valid.pop(key, None)
            continue
        named.add(key)
        if not isinstance(values, (list, tuple)):
            issues.append(_Issue(f"expected a list of values, got {show_value(values)}", sub))
            continue
        if not values:
            issues.append(_Issue("must list at least one value", sub))
            continue
        check = _SCALAR_CHECKS[sweep_type(key)]
        clean: list[Any] = []
        ok = True
        for position, item in enumerate(values):
            try:
                x = check(item)
            except PydanticCustomError as exc:
                ok = False
                issues.extend(
                    i._replace(reason=f"{i.reason} at position {position}", sub=sub)
                    for i in exc.context["issues"]
                )
                continue
            if x in clean:
                ok = False
                issues.append(_Issue(f"duplicate value {x!r} at position {position}", sub))
            clean.append(x)
        if ok:
            valid[key] = tuple(clean)
    seeds = [key for key in valid if key.endswith(".seed")]
    if "replica" in valid and seeds:
        issues.append(_Issue(f"give replicas or a sweep of seeds ({seeds[0]}), not both",
                             (REPLICAS,)))
        valid.pop("replica")
    return valid, named, issues


def _short(key: str) -> str:
    """A swept key as a run id names it: ``k`` for ``chain.k``, ``right_gap`` for
    ``walls.right.gap``, ``mass_seed`` for ``chain.mass.seed``."""
    if key.startswith("walls.") or _generator_key(key):
        return "_".join(key.split(".")[1:])
    return key.split(".")[-1]


def _label(overrides: Mapping[str, Any], sep: str = ", ") -> str:
    """``"n=100, k=3"``: the short name of each swept key with its value."""
    return sep.join(f"{_short(key)}={value}" for key, value in overrides.items())


#: Longest run id, well inside a file name's 255 bytes with its suffixes.
MAX_RUN_ID = 200


def _run_id(overrides: Mapping[str, Any]) -> str:
    """The run's name and file name: ``"n=100_k=3"``, or ``"run"`` without a sweep.

    An id longer than MAX_RUN_ID (a sweep over many keys) keeps the pairs that fit and
    ends with ``hash=`` and 16 hex digits of the whole id, which keeps it unique.
    """
    full = _label(overrides, "_") or "run"
    if len(full) <= MAX_RUN_ID:
        return full
    tail = "hash=" + hashlib.sha256(full.encode()).hexdigest()[:16]
    kept = ""
    for key, value in overrides.items():
        pair = f"{_short(key)}={value}"
        if len(kept) + len(pair) + 1 + len(tail) + 1 > MAX_RUN_ID:
            break
        kept += pair + "_"
    return kept + tail


def _table(value: Any) -> Any:
    """A generator table as a plain dict (a checked one, ``Values``, is JSON text), and
    a checked drive as the table or list the file holds."""
    if isinstance(value, Values) and value.table is not None:
        return json.loads(value.table)
    if isinstance(value, DriveSpec):
        return value.to_json()
    return value


def _replica(chain: Any, number: int) -> Any:
    """The chain's tables with each random generator's seed moved on by ``number``: the
    ``number``-th replica's line (the 0th is the file's own)."""
    if not isinstance(chain, Mapping):
        return chain
    out = dict(chain)
    for key, value in chain.items():
        table = _table(value)
        if (isinstance(table, Mapping) and "random" in table
                and isinstance(table.get("seed"), int) and not isinstance(table["seed"], bool)):
            out[key] = {**table, "seed": table["seed"] + number}
    return out


def _random_keys(chain: Any) -> list[str]:
    """The chain's keys whose values are drawn at random (a generator table's)."""
    if not isinstance(chain, Mapping):
        return []
    return [key for key, value in chain.items()
            if isinstance(_table(value), Mapping) and "random" in _table(value)]


def _set_key(data: dict[str, Any], dotted: str, value: Any) -> None:
    """Set ``data["chain"]["k"]`` for ``"chain.k"`` (``data["walls"]["right"]["gap"]``
    for ``"walls.right.gap"``, and the field of a generator table for
    ``"chain.mass.seed"``), creating missing tables; ``"replica"`` moves the seeds of
    the chain's random generators on by ``value``."""
    if dotted == "replica":
        data["chain"] = _replica(data.get("chain"), value)
        return
    head, _, rest = dotted.partition(".")
    if data.get(head) is None:
        data[head] = {}
    current = _table(data[head])
    if not isinstance(current, Mapping):
        return
    inner = dict(current)
    if "." in rest:
        _set_key(inner, rest, value)
    else:
        inner[rest] = value
    data[head] = inner


def checked_config(config: dict[str, Any]) -> dict[str, Any]:
    """A run's resolved ``config`` with ``solver.rtol`` at its check's tolerance
    (``chainrun.check.check_rtol``): the configuration of its check run."""
    solver = config.get("solver") or {}
    rtol = check_rtol(solver.get("rtol", DEFAULT_RTOL))
    return {**config, "solver": {**solver, "rtol": rtol}}


def config_hash(config: dict[str, Any]) -> str:
    """sha256 (hex) of a run's resolved ``config``, as ``RunSpec.config_hash``."""
    return hashlib.sha256(json.dumps(config, sort_keys=True, separators=(",", ":"))
                          .encode()).hexdigest()


def _canonical_json(config: dict[str, Any], times_json: str) -> str:
    """``json.dumps(config, sort_keys=True, separators=(",", ":"))``, with the (long) list
    ``config["output"]["times"]`` given already serialised as ``times_json``.

    A quote inside a JSON string is always escaped, and no other table has a key
    ``times``, so ``"times":[]`` can only occur as the real key.
    """
    stub = {**config, "output": {**config["output"], "times": []}}
    text = json.dumps(stub, sort_keys=True, separators=(",", ":"))
    marker = '"times":[]'
    assert text.count(marker) == 1
    return text.replace(marker, f'"times":{times_json}')


class Experiment(BaseModel):
    """One experiment file: a chain, output times, solver settings and an optional sweep.

    With a sweep, a swept key may be left out of its own table; the experiment then
    holds the sweep's first value there (``runs()`` gives every combination). Two
    experiments are equal when their fields are, whatever text they came from.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str
    description: str = ""
    units: str = "paper"
    chain: Chain
    walls: Walls = Walls()
    output: Output = Output()
    solver: SolverSettings = SolverSettings()
    sweep: dict[str, tuple[int | float, ...]] = Field(default_factory=dict)

    _source_text: str = PrivateAttr(default="")
    _source: str = PrivateAttr(default="")  # where the text came from, for errors

    @field_validator("name", mode="before")
    @classmethod
    def _name(cls, value: Any) -> str:
        value = _check_str(value)
        if not _NAME_RE.fullmatch(value):
            raise _fail(
                [
                    _Issue(
                        "must be a folder name of 1-100 letters, digits, '.', '_' or '-', "
                        f"not starting with '.', got {show_value(value)}"
                    )
                ]
            )
        if value.endswith("."):  # Windows drops it: "x." and "x" are one folder there
            raise _fail([_Issue(f"must not end with '.', got {show_value(value)}")])
        if _RESERVED_RE.fullmatch(value):
            raise _fail([_Issue(f"is a device name reserved on Windows, got {show_value(value)}")])
        return value

    @field_validator("description", mode="before")
    @classmethod
    def _description(cls, value: Any) -> str:
        return "" if value is None else _check_str(value)

    @field_validator("units", mode="before")
    @classmethod
    def _units(cls, value: Any) -> str:
        value = _check_str(value)
        if _canonical_units(value) is None:
            raise _fail([_Issue(f"expected one of {', '.join(map(repr, UNITS))} (in any "
                                f"case), got {show_value(value)}"
                                f"{_suggest(value.lower(), list(UNITS))}")])
        return _canonical_units(value)

    @field_validator("output", "solver", "walls", mode="before")
    @classmethod
    def _empty_table(cls, value: Any) -> Any:
        return {} if value is None else value  # YAML ``output:`` with nothing under it

    @field_validator("sweep", mode="before")
    @classmethod
    def _sweep(cls, value: Any) -> dict[str, tuple[Any, ...]]:
        valid, _, issues = _check_sweep(value)
        if issues:
            raise _fail(issues)
        return valid

    @property
    def source_text(self) -> str:
        """The full text of the file this experiment was read from ("" if built in code)."""
        return self._source_text

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Experiment):
            return NotImplemented
        return self.__dict__ == other.__dict__

    def __hash__(self) -> int:
        sweep = tuple(self.sweep.items())
        return hash((self.name, self.description, self.units, self.chain, self.walls,
                     self.output, self.solver, sweep))

    def _base_data(self) -> dict[str, Any]:
        """The run's settings before the sweep's values: the chain and walls as their
        models' fields (not yet JSON), the rest as plain data. Keys that were left out
        stay out, so that an experiment of the paper's keys hashes as it always did."""
        data = {
            "name": self.name,
            "description": self.description,
            "chain": _fields(self.chain),
            "output": {"times": list(self.output.times), **(
                {"sensors": list(self.output.sensors), "sensor_dt": self.output.sensor_dt}
                if self.output.sensors else {}), **(
                {"sensor_end": self.output.sensor_end}
                if self.output.sensor_end is not None else {})},
            "solver": self.solver.model_dump(),
        }
        if self.units != "paper":
            data["units"] = self.units
        walls = {side: _fields(getattr(self.walls, side)) for side in ("left", "right")
                 if getattr(self.walls, side) is not None}
        if walls:
            data["walls"] = walls
        return data

    def runs(self, *, to_run: bool = True) -> list[RunSpec]:
        """Every run of the experiment: the cartesian product of the sweep.

        Keys vary in the order they are written, the last fastest; values in the order
        given. Without a sweep there is one run, ``run_id == "run"``. ``to_run=False``
        for lines only analysed at rest (``chainrun spectrum``): a line without a
        terminal state then needs no ``solver.t_end``.

        Returns
        -------
        list of RunSpec

        Raises
        ------
        ConfigError
            If a combination is invalid (only possible for an experiment built in code;
            ``load_experiment`` checks every combination).
        """
        keys = list(self.sweep)
        specs: list[RunSpec] = []
        # The times are the same in every run: serialise them once for the hashes.
        times_json = json.dumps(list(self.output.times), separators=(",", ":"))
        for combo in itertools.product(*(self.sweep[k] for k in keys)):
            overrides = dict(zip(keys, combo))
            data = self._base_data()
            for key, value in overrides.items():
                _set_key(data, key, value)
            problems: list[_Problem] = []
            try:
                chain = Chain.model_validate(data["chain"])
            except ValidationError as exc:
                problems += _translate(exc, ("chain",))
                chain = None
            else:
                problems += _sensors_beyond_n(enumerate(self.output.sensors), chain.n)
            try:
                walls = Walls.model_validate(data.get("walls") or {})
            except ValidationError as exc:
                problems += _translate(exc, ("walls",))
                walls = None
            try:
                solver = SolverSettings.model_validate(data["solver"])
            except ValidationError as exc:
                problems += _translate(exc, ("solver",))
            else:
                problems += _times_after_t_end(self.output.times, solver.t_end)
                problems += _sensor_problems(self.output, solver.t_end)
                if chain is not None and walls is not None and to_run:
                    problems += _needs_t_end(chain, walls, solver.t_end)
            if problems:
                label = f"sweep ({_label(overrides)}): " if overrides else ""
                lines = [one_line(f"{label}{p.line()}") for p in problems]
                raise ConfigError(self._source or self.name, lines)
            config = {**data, "chain": chain.model_dump(exclude_none=True),
                      "solver": solver.model_dump(exclude={"check"})}
            if walls.left is not None or walls.right is not None:
                config["walls"] = walls.model_dump(exclude_none=True)
            canonical = _canonical_json(config, times_json)
            k, alpha = _k_and_alpha(chain, walls)
            specs.append(
                RunSpec(
                    experiment=self.name,
                    run_id=_run_id(overrides),
                    n=chain.n,
                    k=k,
                    alpha=alpha,
                    times=np.array(self.output.times, dtype=np.float64),
                    t_end=solver.t_end,
                    rtol=solver.rtol,
                    max_events=solver.max_events,
                    sensors=self.output.sensors,
                    sensor_dt=self.output.sensor_dt,
                    sensor_end=sensor_end(self.output, solver.t_end),
                    overrides=overrides,
                    config=config,
                    config_hash=hashlib.sha256(canonical.encode()).hexdigest(),
                    source_text=self.source_text,
                    units=self.units,
                    chain=None if chain.is_paper and walls == Walls() and self.units == "paper"
                    else chain,
                    walls=walls,
                    check=solver.check,
                )
            )
        return specs


_MODEL_AT: dict[tuple[str, ...], type[BaseModel]] = {
    (): Experiment,
    ("chain",): Chain,
    ("walls",): Walls,
    ("walls", "left"): WallSettings,
    ("walls", "right"): WallSettings,
    ("output",): Output,
    ("solver",): SolverSettings,
}


def _fields(model: BaseModel) -> dict[str, Any]:
    """A model's fields that were given (not None), as they are (``Values`` kept)."""
    return {key: value for key, value in model if value is not None}


def _k_and_alpha(chain: Chain, walls: Walls) -> tuple[int, float]:
    """K, the leading balls that move, and the contacts' exponent if it is one number
    (NaN if it varies, or if there is no contact): what summaries and the index show
    of a run."""
    if chain.velocity is None:
        k = chain.k
    else:
        v = chain.velocity
        if isinstance(v, float):
            k = chain.n if v != 0.0 else 0
        else:
            try:
                a = (np.asarray(v.items, dtype=float) if v.items is not None
                     else generators.expand(v, chain.n) if chain.n <= CHECK_MAX_N
                     else np.zeros(1))
            except ValuesError:
                a = np.zeros(1)
            moving = a != 0.0
            k = len(a) if moving.all() else int(np.argmin(moving))
    a = chain.alpha
    if a is None and chain.n == 1 and all(getattr(chain, key) is None for key in _SI_KEYS):
        # one ball: its walls' exponents alone (each given, see build_line)
        given = {w.alpha for w in (walls.left, walls.right) if w is not None}
        alpha = given.pop() if len(given) == 1 and None not in given else math.nan
    elif a is None:
        alpha = 1.5  # Hertz, from the material
    elif isinstance(a, float):
        alpha = a
    elif a.items is not None:
        alpha = a.items[0] if len(set(a.items)) == 1 else math.nan
    else:
        table = json.loads(a.table)
        alpha = table["value"] if set(table) == {"value"} else math.nan
    return int(k), float(alpha)


def _sensors_beyond_n(sensors, n: int) -> list[_Problem]:
    """The problems of sensor balls that the chain does not have, one per ball
    (``sensors``: (position, ball) pairs)."""
    return [_Problem("output.sensors", f"ball {b} (position {i}) is beyond chain.n ({n})",
                     frozenset({"chain.n"})) for i, b in sensors if b > n]


def _samples(sensors: tuple[int, ...], dt: float | None, end: float | None) -> int:
    """Force samples of ``sensors`` every ``dt`` from 0 to ``end``: times by balls."""
    if not sensors or dt is None or end is None:
        return 0
    return (math.floor(end / dt) + 1) * len(sensors)


def sensor_end(output: "Output", t_end: float | None) -> float | None:
    """Where a run's sensors stop sampling: ``output.sensor_end``, else ``t_end``, else
    the last snapshot time; None without sensors, or when the run's end is not known
    before it runs (a problem, ``_sensor_problems``)."""
    if not output.sensors:
        return None
    if output.sensor_end is not None:
        return output.sensor_end
    if t_end is not None:
        return t_end
    return output.times[-1] if output.times else None


def _sensor_problems(output: "Output", t_end: float | None) -> list[_Problem]:
    """A run's sensors with no end known before it runs, or with more samples than
    ``MAX_SENSOR_SAMPLES``."""
    if not output.sensors or output.sensor_dt is None:
        return []
    end = sensor_end(output, t_end)
    if end is None:
        return [_Problem("output.sensor_end", "required with output.sensors on a run to its "
                         "terminal state without snapshot times (its end is not known "
                         "before it runs): say when sampling stops",
                         frozenset({"solver.t_end"}))]
    samples = _samples(output.sensors, output.sensor_dt, end)
    if samples > MAX_SENSOR_SAMPLES:
        where = "output.sensor_end" if output.sensor_end is not None else (
            "solver.t_end" if t_end is not None else "output.times")
        return [_Problem("output.sensor_dt", f"{len(output.sensors)} sensor{'s' * (len(output.sensors) != 1)} every "
                         f"{output.sensor_dt:g} up to {end:g} ({where}) take "
                         f"{samples:.3g} samples, too many (at most {MAX_SENSOR_SAMPLES:.0e}); "
                         "sample less often, or stop sooner with output.sensor_end",
                         frozenset({"solver.t_end", "output.sensor_end"}))]
    return []


def _times_after_t_end(times: tuple[float, ...], t_end: float | None) -> list[_Problem]:
    """The problem of snapshot times after the stop time, which no run could take."""
    if t_end is None or not times or times[-1] <= t_end:
        return []
    reason = f"{times[-1]!r} is after solver.t_end ({t_end!r})"
    return [_Problem("output.times", reason, frozenset({"solver.t_end"}))]


# --- pydantic errors -> one-line problems -------------------------------------------------


def _translate(exc: ValidationError, prefix: tuple[str, ...] = ()) -> list[_Problem]:
    """Each pydantic error as a ``key: reason`` problem (never pydantic's own text)."""
    problems: list[_Problem] = []
    for error in exc.errors(include_url=False):
        loc = prefix + tuple(_key_text(part) for part in error["loc"])
        kind, ctx, value = error["type"], error.get("ctx") or {}, error.get("input")
        if kind == _ERROR_TYPE:
            for issue in ctx["issues"]:
                parent = loc + issue.sub
                problems.append(
                    _Problem(
                        _key_path(parent),
                        issue.reason,
                        frozenset(".".join(loc[:-1] + (k,)) for k in issue.involves),
                    )
                )
            continue
        key = ".".join(loc)
        if kind == "missing":
            reason = "required"
        elif kind == "extra_forbidden":
            model = _MODEL_AT.get(loc[:-1])
            choices = list(model.model_fields) if model else []
            reason = f"unknown key{_suggest(loc[-1], choices)}"
        elif kind == "invalid_key":
            key = ".".join(loc[:-1]) or "top level"
            reason = f"unknown key {show_value(error['loc'][-1])} (keys must be text)"
        elif kind in ("model_type", "dict_type", "model_attributes_type"):
            reason = f"expected a table, got {show_value(value)}"
        elif kind == "string_type":
            reason = f"expected a string, got {show_value(value)}"
        elif kind in ("greater_than_equal", "greater_than", "less_than_equal", "less_than"):
            op, bound = {
                "greater_than_equal": (">=", "ge"),
                "greater_than": (">", "gt"),
                "less_than_equal": ("<=", "le"),
                "less_than": ("<", "lt"),
            }[kind]
            reason = f"must be {op} {_bound(ctx[bound])}, got {show_value(value)}"
        else:  # not expected from this schema; pydantic's msg is one line
            reason = f"{error['msg']}, got {show_value(value)}"
        problems.append(_Problem(key, reason))
    return problems


def _line_problems(merged: Mapping[str, Any], overrides: Mapping[str, Any],
                   context: dict[str, Any], to_run: bool = True) -> list[_Problem]:
    """Problems of the line one combination describes: values out of range (by
    index), keys that conflict, a stop time it needs. Nothing when its tables are
    themselves wrong (reported with them)."""
    chain, walls = merged.get("chain"), merged.get("walls")
    units = _canonical_units(merged.get("units", "paper"))
    if not isinstance(chain, Mapping) or not (walls is None or isinstance(walls, Mapping)) \
            or units is None:
        return []
    solver = merged.get("solver")
    try:
        c = Chain.model_validate(chain, context=context)
        w = Walls.model_validate(walls or {}, context=context)
        t_end = SolverSettings.model_validate(solver if isinstance(solver, Mapping)
                                              else {}).t_end
    except (ValidationError, TypeError):
        return []
    if not to_run:
        t_end = math.inf  # analysed at rest, never run: no stop time is needed
    problems = _needs_t_end(c, w, t_end)
    if not (c.is_paper and w == Walls() and units == "paper") and c.n <= CHECK_MAX_N:
        try:
            line = build_line(c, w, units)
        except LineError as exc:
            problems += exc.problems
        else:
            if not problems and t_end is None and not line.has_terminal_state:
                problems.append(_Problem("solver.t_end", "required: chain.force keeps doing "
                                         "work, so the run has no terminal state"))
    involves = frozenset(k for k in overrides if k.startswith(("chain.", "walls."))
                         or k == "replica")
    return [p._replace(involves=p.involves | involves) for p in problems]


def _generator_sweep_issues(valid: dict[str, tuple], chain: Any,
                            walls: Any = None) -> list[_Issue]:
    """Sweeps of a generator's field, or replicas, on a chain without such a table, and
    of a wall motion's key where the motion is not one sine (the entries are dropped
    from ``valid``)."""
    issues = []
    for key in list(valid):
        generator = _generator_key(key)
        if generator is not None and isinstance(chain, Mapping) and not isinstance(
                chain.get(generator[0]), Mapping):
            issues.append(_Issue(f"chain.{generator[0]} is not a generator table "
                                 f"(e.g. {{random = \"uniform\", ..., seed = 1}}): "
                                 f"there is no {generator[1]} to sweep", (key,)))
            valid.pop(key)
    for key in list(valid):
        parts = key.split(".")
        if len(parts) == 4 and parts[2] == "motion" and isinstance(walls, Mapping):
            wall = walls.get(parts[1])
            motion = _table(wall.get("motion")) if isinstance(wall, Mapping) else None
            if not (isinstance(motion, Mapping) and "file" not in motion):
                issues.append(_Issue(f"walls.{parts[1]}.motion is not one sine table "
                                     f"{{amplitude, frequency, ramp}}: there is no "
                                     f"{parts[3]} to sweep", (key,)))
                valid.pop(key)
    if "replica" in valid and isinstance(chain, Mapping) and not _random_keys(chain):
        issues.append(_Issue("the chain draws no random values (a table with random = "
                             "...): its replicas would be one run", (REPLICAS,)))
        valid.pop("replica")
    return issues


def _validate(data: Any, source: str, to_run: bool = True) -> Experiment:
    """The experiment in ``data`` (parsed file contents), every problem reported at once.

    Each sweep combination is validated on its own; problems a combination causes are
    named by it, e.g. ``sweep (n=3, k=4): chain.k: must be <= chain.n (3), got 4``.
    """
    if not isinstance(data, Mapping):
        got = "an empty file" if data is None else f"{type(data).__name__} {show_value(data)}"
        raise ConfigError(source, [f"top level: expected a table of keys, got {got}"])
    # data files named by the experiment are relative to its folder
    context = {"base_dir": os.path.dirname(os.path.abspath(source))}
    valid, named, sweep_issues = _check_sweep(data.get("sweep"))
    sweep_issues += _generator_sweep_issues(valid, data.get("chain"), data.get("walls"))
    base = {key: value for key, value in data.items() if key != "sweep"}
    keys = list(valid)

    # The output table is the same in every run: validate it once, and reuse the model
    # (a range can hold millions of times).
    output: Output | None = Output()
    if base.get("output") is not None:
        try:
            output = Output.model_validate(base["output"])
            base["output"] = output
        except ValidationError:
            output = None  # reported with the whole file below
    # the sensor balls, checked against each run's chain.n even where the output table
    # has other problems (every problem at once)
    raw_output = base.get("output")
    sensors = (list(enumerate(output.sensors)) if output is not None else
               _sensor_balls(raw_output.get("sensors", ()))[0]
               if isinstance(raw_output, Mapping) else [])

    size_lines: list[str] = []
    runs = math.prod(len(v) for v in valid.values())
    snapshots = runs * max(1, len(output.times)) if output is not None else 0
    if runs > MAX_RUNS:
        size_lines.append(f"sweep: {runs} runs are too many (at most {MAX_RUNS})")
    elif snapshots > MAX_SNAPSHOTS:
        if keys:
            size_lines.append(
                f"sweep: {runs} runs of {len(output.times)} snapshot times make {snapshots} "
                f"snapshots, too many (at most {MAX_SNAPSHOTS} in all)"
            )
        else:
            size_lines.append(
                f"output.times: {snapshots} times are too many (at most {MAX_SNAPSHOTS})"
            )
    product = itertools.product(*(valid[k] for k in keys))
    if size_lines:  # check the rest of the file with the first combination only
        product = itertools.islice(product, 1)
    combos = [dict(zip(keys, c)) for c in product]

    base_lines: dict[str, None] = {}  # ordered sets of lines
    combo_lines: dict[str, None] = {}
    first: dict[str, Any] | None = None
    for overrides in combos:
        merged = dict(base)
        for key, value in overrides.items():
            _set_key(merged, key, value)
        problems: list[_Problem] = []
        if first is None:  # the whole file once ...
            first = merged
            try:
                Experiment.model_validate(merged, context=context)
            except ValidationError as exc:
                problems = _translate(exc)
            if not problems:
                problems = _line_problems(merged, overrides, context, to_run)
        else:  # ... then only the tables the sweep changes
            for table in dict.fromkeys("chain" if key == "replica" else key.split(".")[0]
                                       for key in overrides):
                model = _MODEL_AT[(table,)]
                if isinstance(merged[table], Mapping):
                    try:
                        model.model_validate(merged[table], context=context)
                    except ValidationError as exc:
                        problems += _translate(exc, (table,))
            if not problems and any(k.startswith(("chain.", "walls.", "solver.t_end"))
                                    or k == "replica" for k in overrides):
                problems = _line_problems(merged, overrides, context, to_run)
        solver = merged.get("solver")
        if output is not None and (solver is None or isinstance(solver, Mapping)):
            try:
                t_end = SolverSettings.model_validate(solver or {}).t_end
            except ValidationError:
                pass  # reported above
            else:
                problems += _times_after_t_end(output.times, t_end)
                problems += _sensor_problems(output, t_end)
        chain = merged.get("chain")
        if sensors and isinstance(chain, Mapping):
            try:
                n = Chain.model_validate(chain, context=context).n
            except ValidationError:
                pass  # reported above
            else:
                problems += _sensors_beyond_n(sensors, n)
        if not problems:
            continue
        label = _label(overrides)
        for problem in problems:
            touched = {problem.key} | problem.involves
            if touched & (named - set(valid)):
                continue  # a key whose sweep entry is itself broken: reported there
            if touched & named:
                combo_lines[f"sweep ({label}): {problem.line()}"] = None
            else:
                base_lines[problem.line()] = None
    lines = list(base_lines)
    lines += [
        (f"sweep.{i.sub[0]}: {i.reason}" if i.sub else f"sweep: {i.reason}") for i in sweep_issues
    ]
    lines += size_lines
    lines += combo_lines
    if lines:
        raise ConfigError(source, [one_line(line) for line in lines])
    assert first is not None
    return Experiment.model_validate({**first, "sweep": data.get("sweep")}, context=context)


# --- reading files ------------------------------------------------------------------------


def _syntax_line(exc: Exception, text: str, fmt: str) -> str:
    """A parser error as ``line L: message``."""
    if fmt == "toml":
        message = str(exc)
        found = re.search(r"\s*\(at line (\d+), column (\d+)\)", message)
        if found:
            rest = message[: found.start()] + message[found.end() :]
            return f"line {found.group(1)}: {rest.strip()} (column {found.group(2)})"
        found = re.search(r"\s*\(at end of document\)", message)
        if found:
            rest = message[: found.start()] + message[found.end() :]
            return f"line {max(1, len(text.splitlines()))}: {rest.strip()} (at end of document)"
        return " ".join(message.split())
    mark = getattr(exc, "problem_mark", None)
    problem = getattr(exc, "problem", None) or " ".join(str(exc).split())
    context = getattr(exc, "context", None)
    reason = f"{problem} ({context})" if context else problem
    if mark is None:
        return reason
    if text[mark.index:mark.index + 1] == "\t":  # PyYAML's own text names no rule
        indent = text[text.rfind("\n", 0, mark.index) + 1:mark.index].strip(" \t") == ""
        reason = ("a tab: YAML does not allow tabs for indentation; indent with spaces"
                  if indent else "a tab where YAML allows only spaces")
    return f"line {mark.line + 1}: {reason} (column {mark.column + 1})"


#: Most characters an experiment file may have. PyYAML reads about 150 kB a second,
#: tomllib about 1.6 MB: a file at the limit takes a minute and five seconds. Long
#: lists belong in a data file (``{file = "masses.npy"}``).
MAX_TEXT = 8 * 2**20
#: Deepest nesting of YAML flow collections read (PyYAML takes time quadratic in it).
MAX_DEPTH = 100
#: Most values (scalars, lists and tables) a YAML document may hold, counting an
#: alias (``*a``) as the whole value it stands for at every use, merge keys (``<<``)
#: included: ten lines of nested aliases stand for billions of values, which every
#: later stage would walk.
MAX_VALUES = 1_000_000


def _too_deep(text: str) -> int:
    """The line where ``[`` and ``{`` first nest more than ``MAX_DEPTH`` deep, else 0.

    Brackets are counted wherever they are, quoted or not: an overestimate that only
    a file with a hundred unclosed brackets in its strings could trip.
    """
    if text.count("[") + text.count("{") <= MAX_DEPTH:
        return 0
    depth = 0
    line = 1
    for char in text:
        if char in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return line
        elif char in "]}":
            depth = max(0, depth - 1)
        elif char == "\n":
            line += 1
    return 0


def _value_error(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    if "integer string conversion" in text:
        return f"an integer of more than {sys.get_int_max_str_digits()} digits"
    return text or type(exc).__name__


def _expanded_size(root, fail) -> None:
    """Check the size of a composed YAML document with its aliases expanded.

    Walks the node graph once (an alias is the node it names, shared), counting each
    node's values with every use of a shared node; calls ``fail(node, reason)`` at the
    first node that holds more than ``MAX_VALUES``, or that contains itself.
    """
    size: dict[int, int] = {}
    entered: set[int] = set()
    stack = [(root, False)]
    while stack:
        node, leaving = stack.pop()
        value = node.value if isinstance(node.value, list) else []
        children = [c for item in value for c in (item if isinstance(item, tuple) else (item,))]
        if leaving:
            total = 1 + sum(size[id(c)] for c in children)
            if total > MAX_VALUES:
                fail(node, f"more than {MAX_VALUES} values, counting each alias as the "
                           "whole value it stands for")
            size[id(node)] = total
            continue
        if id(node) in size:
            continue
        entered.add(id(node))
        stack.append((node, True))
        for child in children:
            if id(child) in entered and id(child) not in size:
                fail(child, "an alias inside the value it names: a value cannot contain "
                            "itself")
            if id(child) not in size:
                stack.append((child, False))


@functools.cache
def _yaml():
    """PyYAML and ``_YamlLoader``, imported and built on the first YAML file read.

    ``_YamlLoader`` is ``yaml.SafeLoader`` that refuses a document holding more than
    ``MAX_VALUES`` values once its aliases are expanded, or a value that contains
    itself, before it builds anything (``_expanded_size``); and whose failures to
    convert a value name their place. PyYAML converts ``2001-13-45`` (a date),
    ``!!int x`` or an integer of 5000 digits with plain ``int()`` or ``datetime``;
    their ``ValueError`` carries no line.
    """
    import yaml

    class _YamlLoader(yaml.SafeLoader):
        def construct_document(self, node):
            def fail(at, reason):
                raise yaml.constructor.ConstructorError(None, None, reason, at.start_mark)

            _expanded_size(node, fail)
            return super().construct_document(node)

        def construct_object(self, node, deep=False):
            try:
                return super().construct_object(node, deep=deep)
            except (ValueError, TypeError, OverflowError) as exc:
                value = f"{show_value(node.value)}: " if isinstance(node.value, str) else ""
                raise yaml.constructor.ConstructorError(
                    None, None, f"cannot read {value}{_value_error(exc)}", node.start_mark
                ) from None

    return yaml, _YamlLoader


def parse_experiment(text: str, fmt: str, source: str = "<string>", *,
                     to_run: bool = True) -> Experiment:
    """The experiment described by ``text``.

    Parameters
    ----------
    text : str
        The whole experiment file.
    fmt : {"toml", "yaml"}
        Its format (``"yml"`` is taken as ``"yaml"``).
    source : str
        Where the text came from, for error messages.
    to_run : bool
        False for an experiment whose lines are only analysed at rest (``chainrun
        spectrum``): a line without a terminal state then needs no ``solver.t_end``
        (pass the same to ``Experiment.runs``).

    Returns
    -------
    Experiment
        Validated, with ``source_text == text``.

    Raises
    ------
    ConfigError
        With every problem found, one line each.
    """
    fmt = {"yml": "yaml"}.get(fmt, fmt)
    if fmt not in ("toml", "yaml"):
        raise ConfigError(source, [f"unknown format {fmt!r} (expected 'toml' or 'yaml')"])
    if len(text) > MAX_TEXT:
        raise ConfigError(source, [f"more than {MAX_TEXT} characters, too long for an "
                                   "experiment file (give long lists as data files, "
                                   "{file = ...})"])
    if fmt == "toml":
        load, syntax_error = tomllib.loads, tomllib.TOMLDecodeError
    else:
        deep = _too_deep(text)
        if deep:
            raise ConfigError(source, [f"line {deep}: nested more than {MAX_DEPTH} levels deep"])
        yaml, loader = _yaml()
        load, syntax_error = functools.partial(yaml.load, Loader=loader), yaml.YAMLError
    try:
        data = load(text)
    except syntax_error as exc:
        raise ConfigError(source, [one_line(_syntax_line(exc, text, fmt))]) from None
    except RecursionError:
        raise ConfigError(source, ["nested too deeply to read"]) from None
    except ValueError as exc:  # tomllib converting a value, e.g. an integer of 5000 digits
        raise ConfigError(source, [one_line(f"cannot read a value ({_value_error(exc)})")]) from None
    try:
        experiment = _validate(data, source, to_run)
    except RecursionError:  # YAML aliases can nest without end
        raise ConfigError(source, ["nested too deeply to check"]) from None
    experiment._source_text = text  # private attributes are not frozen
    experiment._source = source
    return experiment


def load_experiment(path: str | os.PathLike[str], *, to_run: bool = True) -> Experiment:
    """Read and validate the experiment file at ``path`` (``.toml``, ``.yaml`` or ``.yml``);
    ``to_run`` as for ``parse_experiment``.

    Raises
    ------
    ConfigError
        If the file is missing, unreadable, of an unknown type, or invalid; the error
        lists every problem found.
    """
    source = os.fspath(path)
    suffix = os.path.splitext(source)[1].lower()
    if suffix not in FORMATS:
        raise ConfigError(
            source, [f"unknown file type {suffix or '(none)'!r} (expected .toml, .yaml or .yml)"]
        )
    try:
        with open(source, encoding="utf-8-sig") as handle:  # a BOM (Windows editors) is dropped
            text = handle.read(MAX_TEXT + 1)  # parse_experiment refuses a longer one
    except FileNotFoundError:
        raise ConfigError(source, ["no such file"]) from None
    except IsADirectoryError:
        raise ConfigError(source, ["is a folder, not a file"]) from None
    except UnicodeDecodeError as exc:
        raise ConfigError(source, [f"not UTF-8 text (byte {exc.start})"]) from None
    except OSError as exc:
        raise ConfigError(source, [f"cannot read: {exc.strerror}"]) from None
    return parse_experiment(text, FORMATS[suffix], source, to_run=to_run)
