"""``Experiment``: one experiment file as a whole (its tables, its sweep), checked one
combination of its sweep at a time (``validate``), and the ``RunSpec`` of each
combination (``Experiment.runs``).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import os
import re
from collections.abc import Mapping
from typing import Any

import numpy as np
from pydantic import (BaseModel, ConfigDict, Field, PrivateAttr, ValidationError,
                      field_validator)

from chainrun.config.line import k_and_alpha, line_problems
from chainrun.config.problems import Issue, Problem, check_str, fail, suggest, translate
from chainrun.config.run import RunSpec
from chainrun.config.schema import (UNITS, Chain, Output, SolverSettings, WallSettings, Walls,
                                    canonical_units, sensor_balls, sensor_end,
                                    sensor_problems, sensors_beyond_n, times_after_t_end)
from chainrun.config.sweeps import (MAX_RUNS, MAX_SNAPSHOTS, REPLICAS, canonical_json,
                                    check_sweep, generator_sweep_issues, make_run_id,
                                    run_label, set_key)
from chainrun.errors import ConfigError, one_line, show_value

_NAME_RE = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,99}")
#: Device names Windows reserves in every folder, with or without an extension.
_RESERVED_RE = re.compile(r"(CON|PRN|AUX|NUL|COM[0-9]|LPT[0-9])(\..*)?", re.IGNORECASE)

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
    # (to_run, [(overrides, chain, walls, solver, line or None)]): each combination as
    # validated when the file was read
    _checked: Any = PrivateAttr(default=None)

    @field_validator("name", mode="before")
    @classmethod
    def _name(cls, value: Any) -> str:
        value = check_str(value)
        if not _NAME_RE.fullmatch(value):
            raise fail(
                [
                    Issue(
                        "must be a folder name of 1-100 letters, digits, '.', '_' or '-', "
                        f"not starting with '.', got {show_value(value)}"
                    )
                ]
            )
        if value.endswith("."):  # Windows drops it: "x." and "x" are one folder there
            raise fail([Issue(f"must not end with '.', got {show_value(value)}")])
        if _RESERVED_RE.fullmatch(value):
            raise fail([Issue(f"is a device name reserved on Windows, got {show_value(value)}")])
        return value

    @field_validator("description", mode="before")
    @classmethod
    def _description(cls, value: Any) -> str:
        return "" if value is None else check_str(value)

    @field_validator("units", mode="before")
    @classmethod
    def _units(cls, value: Any) -> str:
        value = check_str(value)
        if canonical_units(value) is None:
            raise fail([Issue(f"expected one of {', '.join(map(repr, UNITS))} (in any "
                                f"case), got {show_value(value)}"
                                f"{suggest(value.lower(), list(UNITS))}")])
        return canonical_units(value)

    @field_validator("output", "solver", "walls", mode="before")
    @classmethod
    def _empty_table(cls, value: Any) -> Any:
        return {} if value is None else value  # YAML ``output:`` with nothing under it

    @field_validator("sweep", mode="before")
    @classmethod
    def _sweep(cls, value: Any) -> dict[str, tuple[Any, ...]]:
        valid, _, issues = check_sweep(value)
        if issues:
            raise fail(issues)
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
            "chain": _given_fields(self.chain),
            "output": {"times": list(self.output.times), **(
                {"sensors": list(self.output.sensors), "sensor_dt": self.output.sensor_dt}
                if self.output.sensors else {}), **(
                {"sensor_end": self.output.sensor_end}
                if self.output.sensor_end is not None else {})},
            "solver": self.solver.model_dump(),
        }
        if self.units != "paper":
            data["units"] = self.units
        walls = {side: _given_fields(getattr(self.walls, side)) for side in ("left", "right")
                 if getattr(self.walls, side) is not None}
        if walls:
            data["walls"] = walls
        return data

    def _data(self) -> dict[str, Any]:
        """The experiment as the data of a file (its tables' models' fields, the sweep
        as written), for ``validate``."""
        sweep = {REPLICAS if key == "replica" else key:
                 len(values) if key == "replica" else list(values)
                 for key, values in self.sweep.items()}
        return {**self._base_data(), "output": self.output, "sweep": sweep}

    def runs(self, *, to_run: bool = True) -> list[RunSpec]:
        """Every run of the experiment: the cartesian product of the sweep.

        Keys vary in the order they are written, the last fastest; values in the order
        given. Without a sweep there is one run, ``run_id == "run"``. ``to_run=False``
        for lines only analysed at rest (``chainrun spectrum``): a line without a
        terminal state then needs no ``solver.t_end``.

        Each combination was validated, and its line built, when the file was read
        (``load_experiment`` and ``parse_experiment``, with the same ``to_run``); they
        are not validated again here.

        Returns
        -------
        list of RunSpec

        Raises
        ------
        ConfigError
            If a combination is invalid (only possible for an experiment built in code,
            or read with another ``to_run``: it is checked now).
        """
        checked = self._checked
        if checked is None or checked[0] != to_run:
            checked = validate(self._data(), self._source or self.name, to_run)._checked
        base, source_text = self._base_data(), self.source_text
        # The times are the same in every run: serialise them once for the hashes.
        times_json = json.dumps(list(self.output.times), separators=(",", ":"))
        specs: list[RunSpec] = []
        for overrides, chain, walls, solver, line in checked[1]:
            config = {**base, "chain": chain.model_dump(exclude_none=True),
                      "solver": solver.model_dump(exclude={"check"})}
            if walls.left is not None or walls.right is not None:
                config["walls"] = walls.model_dump(exclude_none=True)
            k, alpha = k_and_alpha(chain, walls, line)
            spec = RunSpec(
                experiment=self.name,
                run_id=make_run_id(overrides),
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
                config_hash=hashlib.sha256(canonical_json(config, times_json).encode()
                                           ).hexdigest(),
                source_text=source_text,
                units=self.units,
                chain=chain,
                walls=walls,
                check=solver.check,
            )
            specs.append(spec if line is None else spec._keep(line))
        return specs


MODEL_AT: dict[tuple[str, ...], type[BaseModel]] = {
    (): Experiment,
    ("chain",): Chain,
    ("walls",): Walls,
    ("walls", "left"): WallSettings,
    ("walls", "right"): WallSettings,
    ("output",): Output,
    ("solver",): SolverSettings,
}


def _given_fields(model: BaseModel) -> dict[str, Any]:
    """A model's fields that were given (not None), as they are (``Values`` kept)."""
    return {key: value for key, value in model if value is not None}


def _combination_lines(found: list[tuple[str, str]], runs: int) -> list[str]:
    """The lines of the problems sweep combinations cause, ``found`` as (the run's
    label, the problem's line) in order: each once, naming its run, and a problem that
    every one of the ``runs`` combinations has once for all of them."""
    labels: dict[str, set[str]] = {}
    for label, line in found:
        labels.setdefault(line, set()).add(label)
    lines: dict[str, None] = {}
    for label, line in found:
        if runs > 1 and len(labels[line]) == runs:
            lines[f"sweep (all {runs} runs): {line}"] = None
        else:
            lines[f"sweep ({label}): {line}"] = None
    return list(lines)


def validate(data: Any, source: str, to_run: bool = True) -> Experiment:
    """The experiment in ``data`` (parsed file contents), every problem reported at once.

    Each sweep combination is validated on its own, once: the whole file with the first
    combination, then the tables each other one changes; its line is built (and kept for
    its run) unless it is the paper's. Problems a combination causes are named by it,
    e.g. ``sweep (n=3, k=4): chain.k: must be <= chain.n (3), got 4``; one that every
    combination has, once for them all: ``sweep (all 3 runs): solver.t_end: required``.
    """
    if not isinstance(data, Mapping):
        got = "an empty file" if data is None else f"{type(data).__name__} {show_value(data)}"
        # TOML read as YAML is one string: "name = ... [chain] ..."
        toml = isinstance(data, str) and "=" in data and not source.endswith(".toml")
        hint = " (this looks like TOML: name the file .toml)" if toml else ""
        raise ConfigError(source, [f"top level: expected a table of keys, got {got}{hint}"])
    # data files named by the experiment are relative to its folder
    context = {"base_dir": os.path.dirname(os.path.abspath(source))}
    valid, named, sweep_issues = check_sweep(data.get("sweep"))
    sweep_issues += generator_sweep_issues(valid, data.get("chain"), data.get("walls"))
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
               sensor_balls(raw_output.get("sensors", ()))[0]
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

    units = canonical_units(base.get("units", "paper"))
    base_lines: dict[str, None] = {}  # ordered sets of lines
    combo_problems: list[tuple[str, str]] = []  # (the run's label, its problem)
    first: Experiment | None = None
    first_models: dict[str, BaseModel] = {}
    first_line = None
    checked = []
    for index, overrides in enumerate(combos):
        merged = dict(base)
        for key, value in overrides.items():
            set_key(merged, key, value)
        problems: list[Problem] = []
        line = first_line
        if index == 0:  # the whole file once ...
            try:
                first = Experiment.model_validate(merged, context=context)
            except ValidationError as exc:
                problems = translate(exc, MODEL_AT)
            else:
                first_models.update(chain=first.chain, walls=first.walls, solver=first.solver)
            models = dict(first_models)
            recheck = not problems
        else:  # ... then only the tables the sweep changes
            models = dict(first_models)
            for table in dict.fromkeys("chain" if key == "replica" else key.split(".")[0]
                                       for key in overrides):
                models.pop(table, None)
                if isinstance(merged[table], Mapping):
                    try:
                        models[table] = MODEL_AT[(table,)].model_validate(merged[table],
                                                                          context=context)
                    except ValidationError as exc:
                        problems += translate(exc, MODEL_AT, (table,))
            recheck = not problems and any(k.startswith(("chain.", "walls.", "solver.t_end"))
                                           or k == "replica" for k in overrides)

        def model(table: str) -> BaseModel | None:
            """This combination's model of ``table``, or None where it is wrong."""
            if table not in models:
                value = merged.get(table)
                if table == "solver":
                    value = value if isinstance(value, Mapping) else {}
                elif table == "walls":
                    value = {} if value is None else value
                models[table] = None
                if isinstance(value, Mapping):
                    try:
                        models[table] = MODEL_AT[(table,)].model_validate(value,
                                                                          context=context)
                    except ValidationError:
                        pass  # reported with its table
            return models[table]

        if recheck:
            line = None
            chain, walls, solver = model("chain"), model("walls"), model("solver")
            if units is not None and chain is not None and walls is not None \
                    and solver is not None:
                found, line = line_problems(chain, walls, units, solver.t_end, to_run)
                involves = frozenset(k for k in overrides if k.startswith(("chain.", "walls."))
                                     or k == "replica")
                problems += [p._replace(involves=p.involves | involves) for p in found]
            if index == 0:
                first_line = line
        solver = merged.get("solver")
        if output is not None and (solver is None or isinstance(solver, Mapping)):
            settings = model("solver")
            if settings is not None:
                problems += times_after_t_end(output.times, settings.t_end)
                problems += sensor_problems(output, settings.t_end)
        if sensors and isinstance(merged.get("chain"), Mapping):
            chain = model("chain")
            if chain is not None:
                problems += sensors_beyond_n(sensors, chain.n)
        if not problems:
            checked.append((overrides, models.get("chain"), models.get("walls"),
                            models.get("solver"), line))
            continue
        label = run_label(overrides)
        for problem in problems:
            touched = {problem.key} | problem.involves
            if touched & (named - set(valid)):
                continue  # a key whose sweep entry is itself broken: reported there
            if touched & named:
                combo_problems.append((label, problem.line()))
            else:
                base_lines[problem.line()] = None
    lines = list(base_lines)
    lines += [
        (f"sweep.{i.sub[0]}: {i.reason}" if i.sub else f"sweep: {i.reason}") for i in sweep_issues
    ]
    lines += size_lines
    lines += _combination_lines(combo_problems, len(combos))
    if lines:
        raise ConfigError(source, [one_line(line) for line in lines])
    assert first is not None
    experiment = first.model_copy(update={"sweep": valid})
    experiment._checked = (to_run, checked)
    return experiment
