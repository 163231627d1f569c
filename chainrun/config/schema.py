"""The schema of an experiment file's tables: ``Chain``, ``WallSettings`` and ``Walls``,
``Output`` and ``SolverSettings`` (pydantic models, frozen), with the rules of their
values and the problems of a run's output against its stop time and its chain.

Per-ball and per-contact keys hold a number, a list or a generator table
(``chainrun.generators``); a number is checked as the file is read, the others when
they are expanded (``chainrun.config.line``). The experiment as a whole, with its sweep,
is ``chainrun.config.experiment.Experiment``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Annotated, Any

import numpy as np
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    PlainSerializer,
    ValidationInfo,
    field_validator,
    model_validator,
)
from pydantic_core import PydanticCustomError

from chainrun import generators
from chainrun.check import MIN_RTOL
from chainrun.config.drives import DumpDrive, drive_validator
from chainrun.config.problems import (Issue, Problem, bound, check_bool, check_float,
                                      check_int, check_str, fail, key_text, suggest)
from chainrun.errors import show_value
from chainrun.generators import Values, ValuesError
from chainrun.materials import MATERIALS
from chainrun.solver import DEFAULT_RTOL
from chainrun.solver import restitution as collision
from chainrun.solver.result import last_sample

#: The units an experiment may be written in: the paper's (every coefficient 1), or SI.
UNITS = ("paper", "si")


def canonical_units(value: Any) -> str | None:
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
#: Most force samples a run may take (sample times by sensors): each is a row of the
#: run file and of the solver's memory.
MAX_SENSOR_SAMPLES = 10_000_000
#: Fewer samples than this a sensor is no record of a pulse: a sampling interval given in
#: the wrong unit (0.1 for 0.1 µs) more likely than a wish
MIN_SENSOR_SAMPLES = 3



def _none_or(check):
    return lambda value: None if value is None else check(value)


_Int = Annotated[int, BeforeValidator(check_int)]
_Float = Annotated[float, BeforeValidator(check_float)]
_OptInt = Annotated[int | None, BeforeValidator(_none_or(check_int))]
_Bool = Annotated[bool, BeforeValidator(check_bool)]
_OptFloat = Annotated[float | None, BeforeValidator(_none_or(check_float))]

SCALAR_CHECKS = {int: check_int, float: check_float}


# --- the chain and its walls --------------------------------------------------------------


#: What each per-ball or per-contact key must satisfy: (lowest, strict, highest, what
#: it is per). Checked on scalars as the file is read, and on every value once expanded.
RULES: dict[str, tuple[float | None, bool, float | None, str]] = {
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
SI_KEYS = ("diameter", "material", "young", "poisson", "density")


def rule_reason(key: str, x: float) -> str | None:
    """Why ``x`` breaks the rule of ``key`` (None if it does not)."""
    low, strict, high, _ = RULES[key]
    if low is not None and (x <= low if strict else x < low):
        return f"must be {'>' if strict else '>='} {bound(low)}"
    if high is not None and x > high if key != "poisson" else high is not None and x >= high:
        op = "<" if key == "poisson" else "<="
        why = (" (a steeper law stiffens so abruptly that the solver's steps shrink "
               "without end)" if key == "alpha" else "")
        return f"must be {op} {bound(high)}{why}"
    return None


def _material(value: Any) -> str:
    """A material's name, one of ``chainrun.materials.MATERIALS``."""
    name = check_str(value)
    if name not in MATERIALS:
        raise fail([Issue(f"unknown material {show_value(name)}"
                          f"{suggest(name, list(MATERIALS))} (known: "
                          f"{', '.join(MATERIALS)})")])
    return name


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
                raise fail([Issue(exc.reason, exc.sub)]) from None
        if text:
            return _material(value)
        x = check_float(value)
        reason = rule_reason(key, x)
        if reason:
            raise fail([Issue(f"{reason}, got {show_value(value)}")])
        return x

    return BeforeValidator(check)


def _dump_values(value: Any) -> Any:
    return value.to_json() if isinstance(value, Values) else value


_Dump = PlainSerializer(_dump_values)


def _check_damping_law(value: Any) -> str | None:
    if value is None:
        return None
    name = check_str(value)
    if name not in collision.LAWS:
        raise fail([Issue(f"unknown damping law {show_value(name)}"
                            f"{suggest(name, list(collision.LAWS))} (known: "
                            f"{', '.join(collision.LAWS)})")])
    return name


_OptLaw = Annotated[str | None, BeforeValidator(_check_damping_law)]


def _dissipation_issues(model: BaseModel) -> list[Issue]:
    """Conflicts among a chain's or a wall's dissipation keys.

    A contact's damping is given either as ``damping`` (eta), with its exponent as
    ``damping_exponent`` or from ``damping_law``, or as ``restitution`` with
    ``damping_law`` (and ``restitution_speed`` where e depends on the impact speed,
    which ``chainrun.solver.build`` judges per contact from its exponent).
    """
    def given(key: str) -> bool:
        return getattr(model, key) is not None

    issues: list[Issue] = []
    if given("restitution"):
        issues += [Issue("give restitution or damping, not both", (key,))
                   for key in ("damping", "damping_exponent") if given(key)]
        if not given("damping_law"):
            issues.append(Issue(f"required with restitution (one of "
                                f"{', '.join(collision.LAWS)})", ("damping_law",)))
    else:
        if given("restitution_speed"):
            issues.append(Issue("given without restitution", ("restitution_speed",)))
        if given("damping_law") and given("damping_exponent"):
            issues.append(Issue("set by damping_law; give one or the other",
                                ("damping_exponent",)))
        elif given("damping_law") and not given("damping"):
            issues.append(Issue("needs damping or restitution", ("damping_law",)))
        elif given("damping_exponent") and not given("damping"):
            issues.append(Issue("given without damping", ("damping_exponent",)))
    return issues





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
    gravity: _OptFloat = Field(None, gt=0)
    damping: Annotated[Any, _values("damping"), _Dump] = None
    damping_exponent: Annotated[Any, _values("damping_exponent"), _Dump] = None
    restitution: Annotated[Any, _values("restitution"), _Dump] = None
    damping_law: _OptLaw = None
    restitution_speed: _OptFloat = Field(None, gt=0)
    drive: Annotated[Any, drive_validator("force"), DumpDrive] = None

    @field_validator("k")
    @classmethod
    def _k_at_most_n(cls, k: int | None, info: ValidationInfo) -> int | None:
        if k is None:
            # required unless the velocities are given (absent from data: invalid)
            if info.data.get("velocity", "invalid") is None:
                raise fail([Issue("required")])
            return k
        n = info.data.get("n")  # absent when n itself is invalid
        if n is not None and k > n:
            raise fail([Issue(f"must be <= chain.n ({n}), got {k}", involves=("n",))])
        return k

    @field_validator("alpha")
    @classmethod
    def _alpha_unless_real(cls, alpha: Any, info: ValidationInfo) -> Any:
        # required unless a material's Hertz law sets it (3/2), or there is no contact
        # between balls (one ball: a wall has its own alpha)
        real = ("material", "young", "poisson", "density")
        if alpha is None and all(key in info.data and info.data[key] is None for key in real) \
                and info.data.get("n") != 1:
            raise fail([Issue("required", involves=("n",))])
        return alpha

    @field_validator("speed")
    @classmethod
    def _speed_not_zero(cls, speed: float | None) -> float | None:
        if speed == 0.0:
            raise fail([Issue("must not be 0 (the first k balls strike at this speed)")])
        return speed

    @model_validator(mode="after")
    def _consistent(self) -> "Chain":
        issues: list[Issue] = []
        if self.velocity is not None:
            for key in ("k", "speed"):
                if getattr(self, key) is not None:
                    issues.append(Issue("give chain.velocity or chain.k, not both", (key,)))
        issues += _dissipation_issues(self)
        if issues:
            raise fail(issues)
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
    motion: Annotated[Any, drive_validator("displacement"), DumpDrive] = None

    @field_validator("material", mode="before")
    @classmethod
    def _material(cls, value: Any) -> str | None:
        return None if value is None else _material(value)

    @model_validator(mode="after")
    def _one_law(self) -> "WallSettings":
        issues: list[Issue] = []
        if self.material is not None:
            issues += [Issue("the material's Hertz law sets it; give one or the other", (key,))
                       for key in ("stiffness", "alpha") if getattr(self, key) is not None]
        issues += _dissipation_issues(self)
        if issues:
            raise fail(issues)
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


# --- output and solver --------------------------------------------------------------------


def _expand_range(table: Mapping[str, Any]) -> tuple[tuple[float, ...], list[Issue]]:
    """Snapshot times ``start, start + step, ...`` up to ``stop`` inclusive (to rounding)."""
    issues: list[Issue] = []
    fields = ["start", "stop", "step"]
    for key in table:
        if key not in fields:
            issues.append(Issue(f"unknown key{suggest(str(key), fields)}", (key_text(key),)))
    got: dict[str, float] = {}
    for key in fields:
        if key not in table:
            issues.append(Issue("required", (key,)))
            continue
        try:
            got[key] = check_float(table[key])
        except PydanticCustomError as exc:
            issues.extend(i._replace(sub=(key,)) for i in exc.context["issues"])
    if "start" in got and got["start"] < 0:
        issues.append(Issue(f"must be non-negative, got {got['start']!r}", ("start",)))
    if "step" in got and got["step"] <= 0:
        issues.append(Issue(f"must be > 0, got {got['step']!r}", ("step",)))
    if "start" in got and "stop" in got and got["stop"] < got["start"]:
        issues.append(
            Issue(f"must be >= output.times.start ({got['start']!r}), got {got['stop']!r}", ("stop",))
        )
    if issues:
        return (), issues
    start, stop, step = got["start"], got["stop"], got["step"]
    m = (stop - start) / step  # inf when step is tiny (1e-308)
    if not m < MAX_RANGE_TIMES:
        count = f"{math.floor(m) + 1}" if m < 1e15 else f"{m:.3g}"
        return (), [Issue(f"a range of {count} times is too many (at most {MAX_RANGE_TIMES})")]
    steps = round(m) if abs(m - round(m)) <= 1e-9 * max(1.0, m) else math.floor(m)
    if steps + 1 > MAX_RANGE_TIMES:
        return (), [Issue(f"a range of {steps + 1} times is too many (at most {MAX_RANGE_TIMES})")]
    times = start + step * np.arange(steps + 1, dtype=np.float64)
    times[-1] = min(times[-1], stop)  # stop inclusive: do not let rounding step past it
    return tuple(float(t) for t in times), []


def sensor_balls(value: Any) -> tuple[list[tuple[int, int]], list[Issue]]:
    """The valid ball numbers of ``output.sensors``, each with its position in the
    list, and every problem of the others."""
    if not isinstance(value, (list, tuple)):
        return [], [Issue(f"expected a list of ball numbers, got {show_value(value)}")]
    issues: list[Issue] = []
    balls: list[int] = []
    kept: list[tuple[int, int]] = []
    for position, item in enumerate(value):
        try:
            ball = check_int(item)
        except PydanticCustomError as exc:
            issues.extend(i._replace(reason=f"{i.reason} at position {position}")
                          for i in exc.context["issues"])
            continue
        if ball < 1:
            issues.append(Issue(f"must be a ball number >= 1, got {ball} at position "
                                f"{position}"))
        elif ball in balls:
            issues.append(Issue(f"ball {ball} is listed twice (position {position})"))
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
        kept, issues = sensor_balls(value)
        if issues:
            raise fail(issues)
        return tuple(ball for _, ball in kept)

    @field_validator("sensor_dt", "sensor_end", mode="after")
    @classmethod
    def _sensors_and_interval(cls, value: float | None, info: ValidationInfo) -> float | None:
        # sensors absent from info.data: given, but wrong (reported with them)
        given = info.data.get("sensors", True)
        if given and value is None and info.field_name == "sensor_dt":
            raise fail([Issue("required with output.sensors (the sampling interval)")])
        if value is not None and not given:
            raise fail([Issue("given without output.sensors")])
        return value

    @field_validator("times", mode="before")
    @classmethod
    def _times(cls, value: Any) -> tuple[float, ...]:
        if isinstance(value, Mapping):
            times, issues = _expand_range(value)
            if issues:
                raise fail(issues)
            return times
        if not isinstance(value, (list, tuple)):
            raise fail(
                [Issue("expected a list of times or a table {start, stop, step}, got "
                       f"{show_value(value)}")]
            )
        issues: list[Issue] = []
        times: list[float] = []
        previous: float | None = None
        for position, item in enumerate(value):
            try:
                t = check_float(item)
            except PydanticCustomError as exc:
                issues.extend(
                    i._replace(reason=f"{i.reason} at position {position}") for i in exc.context["issues"]
                )
                continue
            if t < 0:
                issues.append(Issue(f"must be non-negative, got {t!r} at position {position}"))
            if previous is not None and t < previous:
                issues.append(
                    Issue(f"must be non-decreasing, got {t!r} after {previous!r} (position {position})")
                )
            previous = t
            times.append(t)
        if issues:
            raise fail(issues)
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


# --- a run's output against its chain and its stop time -----------------------------------


def sensors_beyond_n(sensors, n: int) -> list[Problem]:
    """The problems of sensor balls that the chain does not have, one per ball
    (``sensors``: (position, ball) pairs)."""
    return [Problem("output.sensors", f"ball {b} (position {i}) is beyond chain.n ({n})",
                    frozenset({"chain.n"})) for i, b in sensors if b > n]


def sensor_count(sensors: tuple[int, ...], dt: float | None, end: float | None) -> int:
    """Force samples of ``sensors`` every ``dt`` from 0 to ``end``: times by balls."""
    if not sensors or dt is None or end is None:
        return 0
    return (last_sample(dt, end)[0] + 1) * len(sensors)


def sensor_end(output: "Output", t_end: float | None) -> float | None:
    """Where a run's sensors stop sampling: ``output.sensor_end``, else ``t_end``, else
    the last snapshot time; None without sensors, or when the run's end is not known
    before it runs (a problem, ``sensor_problems``)."""
    if not output.sensors:
        return None
    if output.sensor_end is not None:
        return output.sensor_end
    if t_end is not None:
        return t_end
    return output.times[-1] if output.times else None


def sensor_problems(output: "Output", t_end: float | None) -> list[Problem]:
    """A run's sensors with no end known before it runs, or with more samples than
    ``MAX_SENSOR_SAMPLES``."""
    if not output.sensors or output.sensor_dt is None:
        return []
    end = sensor_end(output, t_end)
    if end is None:
        return [Problem("output.sensor_end", "required with output.sensors on a run to its "
                        "terminal state without snapshot times (its end is not known "
                        "before it runs): say when sampling stops",
                        frozenset({"solver.t_end"}))]
    samples = sensor_count(output.sensors, output.sensor_dt, end)
    where = "output.sensor_end" if output.sensor_end is not None else (
        "solver.t_end" if t_end is not None else "output.times")
    each = samples // len(output.sensors)
    if each < MIN_SENSOR_SAMPLES:
        return [Problem("output.sensor_dt", f"every {output.sensor_dt:g} up to {end:g} "
                        f"({where}) gives {each} sample{'s' * (each != 1)} a sensor, too "
                        f"few to see a pulse in (at least {MIN_SENSOR_SAMPLES}); sample "
                        "more often (is it in the run's units?)",
                        frozenset({"solver.t_end", "output.sensor_end"}))]
    if samples > MAX_SENSOR_SAMPLES:
        return [Problem("output.sensor_dt", f"{len(output.sensors)} sensor{'s' * (len(output.sensors) != 1)} every "
                        f"{output.sensor_dt:g} up to {end:g} ({where}) take "
                        f"{samples:.3g} samples, too many (at most {MAX_SENSOR_SAMPLES:.0e}); "
                        "sample less often, or stop sooner with output.sensor_end",
                        frozenset({"solver.t_end", "output.sensor_end"}))]
    return []


def times_after_t_end(times: tuple[float, ...], t_end: float | None) -> list[Problem]:
    """The problem of snapshot times after the stop time, which no run could take."""
    if t_end is None or not times or times[-1] <= t_end:
        return []
    reason = f"{times[-1]!r} is after solver.t_end ({t_end!r})"
    return [Problem("output.times", reason, frozenset({"solver.t_end"}))]
