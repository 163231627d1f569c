"""Analysis: run files in, derived quantities out, one analysis file per artefact.

This package owns everything computed from runs (and from the paper's theory) for the
figures, tables and printed numbers of the paper. ``analyze(name)`` looks the artefact up
in ``chainrun.artefacts``, reads the run files of its experiments and the analysis files
it needs (through ``chainrun.store`` only, recording the sha256 of each), calls its
recipe and writes ``results/analysis/<name>.h5``.

Modules:

- ``derived``: measurements on runs (rebound and ejection, fits, solitary-wave trains);
- ``pulse``: force sensors' pulses (peak, width, arrival) and a wave's fitted speed;
- ``similarity``: equation (4.9) by shooting and by Airy functions;
- ``nesterenko``: Nesterenko's long-wave solitary wave;
- ``linear``, ``hertz``: one recipe per artefact, for alpha = 1 and alpha = 3/2;
- ``paper``, ``comparison``: the printed numbers and the comparison table;
- ``spectrum``: the linear spectrum of a line at rest (``chainrun spectrum``), from the
  line itself rather than from runs;
- ``summary``: a run at a glance (``chainrun info``).

Nothing here imports click or matplotlib.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

import numpy as np

from chainrun import artefacts
from chainrun.check import spread
from chainrun.errors import ChainrunError
from chainrun.store import (
    AnalysisData,
    RunData,
    file_sha256,
    read_analysis,
    read_index,
    read_run,
    write_analysis,
)

__all__ = ["Inputs", "Result", "analyze", "check_results"]


class Inputs:
    """What a recipe may read: its experiments' runs and the analyses it needs.

    Every file read is recorded with its sha256, for the analysis file's ``/inputs``.
    """

    def __init__(self, artefact: artefacts.Artefact, results="results"):
        self.artefact = artefact
        self.results = Path(results)
        self.read: list[dict[str, str]] = []
        self._runs: dict[str, list[RunData]] = {}

    def runs(self, experiment: str) -> list[RunData]:
        """The runs of ``experiment`` in its index's order (one, for no sweep)."""
        if experiment not in self.artefact.experiments:
            raise ChainrunError(f"{self.artefact.name}: experiment {experiment!r} is not "
                                "among its declared inputs (chainrun/artefacts.py)")
        if experiment not in self._runs:
            index = artefacts.index_path(experiment, self.results)
            if not index.exists():
                raise ChainrunError(
                    f"{index}: no runs of experiment {experiment!r}; run "
                    f"`chainrun simulate configs/{experiment}.toml -o {index.parent}` first")
            runs = []
            for entry in read_index(index):
                path = index.parent / entry["file"]
                run = read_run(path)
                stopped = run.parameters.get("t_end") is not None and run.outcome == "stop_time"
                if not (run.terminal or stopped):   # a stop at its own t_end is asked for
                    raise ChainrunError(f"{path}: run did not reach its terminal state "
                                        f"({run.message})")
                self.read.append(dict(kind="run", name=f"{experiment}/{entry['run_id']}",
                                      file=str(path), sha256=file_sha256(path)))
                runs.append(run)
            self._runs[experiment] = runs
        return self._runs[experiment]

    def run(self, experiment: str, **params) -> RunData:
        """The one run of ``experiment`` whose parameters match ``params`` (e.g. k=2)."""
        found = [r for r in self.runs(experiment)
                 if all(r.parameters[key] == value for key, value in params.items())]
        if len(found) != 1:
            raise ChainrunError(f"{experiment}: {len(found)} runs with {params}, expected 1")
        return found[0]

    def analysis(self, name: str) -> AnalysisData:
        """The analysis file of artefact ``name`` (declared in ``needs``)."""
        if name not in self.artefact.needs:
            raise ChainrunError(f"{self.artefact.name}: analysis {name!r} is not among its "
                                "declared inputs (chainrun/artefacts.py)")
        path = artefacts.analysis_path(name, self.results)
        if not path.exists():
            raise ChainrunError(f"{path}: missing; run `chainrun analyze {name}` first")
        data = read_analysis(path)
        self.read.append(dict(kind="analysis", name=name, file=str(path),
                              sha256=file_sha256(path)))
        return data


class Result:
    """What a recipe builds: named values, arrays (grouped in series) and settings."""

    def __init__(self):
        self.values: dict[str, float] = {}
        self.descriptions: dict[str, str] = {}
        self.arrays: dict[str, np.ndarray] = {}
        self.attrs: dict[str, dict[str, Any]] = {}
        self.settings: dict[str, Any] = {}

    def value(self, key: str, value, description: str) -> float:
        """Record a named scalar; returns it as a float."""
        self.values[key] = float(value)
        self.descriptions[key] = description
        return self.values[key]

    def array(self, key: str, value) -> None:
        self.arrays[key] = np.asarray(value)

    def series(self, group: str, name: str, x, y, **attrs) -> None:
        """One plotted curve or set of markers: ``group/name/x``, ``.../y`` and attributes
        (``label``, ``role`` in {"data", "guide", "theory"}, ...)."""
        if "/" in name:
            raise ValueError(f"series name {name!r}: '/' would nest HDF5 groups")
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if x.shape != y.shape:
            raise ValueError(f"series {group}/{name}: x {x.shape} and y {y.shape} differ")
        self.arrays[f"{group}/{name}/x"] = x
        self.arrays[f"{group}/{name}/y"] = y
        self.attrs[f"{group}/{name}"] = {"role": "data", **attrs}

    def setting(self, key: str, value) -> None:
        self.settings[key] = value


def recipe(artefact: artefacts.Artefact):
    """The function that computes ``artefact``'s analysis."""
    module, _, function = artefact.analysis.partition(":")
    return getattr(importlib.import_module(f"chainrun.analysis.{module}"), function)


def analyze(name: str, *, results="results", check: bool = False) -> Path:
    """Compute the analysis of artefact ``name`` and write its analysis file.

    Parameters
    ----------
    name : str
        An artefact of ``chainrun.artefacts``.
    results : path-like
        The results folder: runs are read from ``<results>/runs/<experiment>/``, the
        analysis file is written to ``<results>/analysis/<name>.h5``.
    check : bool
        Also compute the same recipe from the check runs, ``<results>/check/runs/``
        (written by ``chainrun simulate --check-outdir``: the same experiments at
        ``chainrun.check.check_rtol``), into ``<results>/check/analysis/<name>.h5``,
        and store each value's spread, ``|value - check value|`` (``AnalysisData.
        spreads``): the part of the number that tolerance and rounding set. A
        comparison artefact has no check of its own: it reads the spreads of the
        analyses it compares.

    Returns
    -------
    Path
        The analysis file written.

    Raises
    ------
    ChainrunError
        If the artefact is unknown or an input is missing or unusable.
    """
    try:
        artefact = artefacts.get(name)
    except KeyError as exc:
        raise ChainrunError(exc.args[0]) from None
    inputs = Inputs(artefact, results)
    spreads: dict[str, float] = {}
    if check and artefact.kind != "comparison":
        check_inputs = Inputs(artefact, check_results(results))
        for experiment in artefact.experiments:
            index = artefacts.index_path(experiment, check_inputs.results)
            if not index.exists():
                raise ChainrunError(
                    f"{index}: no check runs of experiment {experiment!r}; run `chainrun "
                    f"simulate configs/{experiment}.toml -o "
                    f"{artefacts.run_dir(experiment, results)} --check-outdir {index.parent}` "
                    "first")
        checked = _analyze(artefact, check_inputs)
        result = recipe(artefact)(inputs)
        _paired(inputs, check_inputs)
        found = read_analysis(checked)
        spreads = {key: _spread(value, found.values.get(key, np.nan))
                   for key, value in result.values.items()}
        inputs.read.append(dict(kind="analysis", name=f"check/{name}", file=str(checked),
                                sha256=file_sha256(checked)))
    else:
        result = recipe(artefact)(inputs)
    return _write(artefact, inputs, result, spreads)


def check_results(results) -> Path:
    """The results folder of the check runs and their analyses, inside ``results``."""
    return Path(results) / "check"


def _paired(inputs: Inputs, check_inputs: Inputs) -> None:
    """Refuse check runs that are not the checks of the runs (a config changed and
    the runs were simulated again without ``--check-outdir``)."""
    from chainrun.config import checked_config, config_hash  # pydantic: only when checking

    for experiment, runs in inputs._runs.items():
        checks = check_inputs._runs.get(experiment, [])
        if len(checks) != len(runs):
            raise ChainrunError(
                f"{artefacts.index_path(experiment, check_inputs.results)}: {len(checks)} "
                f"check runs for {len(runs)} runs of {experiment!r}; simulate it again "
                "with --check-outdir")
        for run, other in zip(runs, checks):
            expected = config_hash(checked_config(run.parameters["config_resolved"]))
            if other.parameters.get("config_hash") != expected:
                raise ChainrunError(f"{other.path}: not the check run of {run.path} (another "
                                    f"config); simulate {experiment!r} again with "
                                    "--check-outdir")


def _spread(value: float, other: float) -> float:
    """``chainrun.check.spread`` of two scalars."""
    return float(spread([value], [other])[0])


def _analyze(artefact: artefacts.Artefact, inputs: Inputs) -> Path:
    return _write(artefact, inputs, recipe(artefact)(inputs), {})


def _write(artefact: artefacts.Artefact, inputs: Inputs, result: Result,
           spreads: dict[str, float]) -> Path:
    path = artefacts.analysis_path(artefact.name, inputs.results)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_analysis(path, AnalysisData(
        name=artefact.name, title=artefact.title, values=result.values,
        descriptions=result.descriptions, arrays=result.arrays, attrs=result.attrs,
        settings=result.settings, inputs=inputs.read, spreads=spreads,
    ))
    return path
