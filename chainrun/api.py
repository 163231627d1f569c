"""chainrun from Python: run an experiment, or open a run file, as an xarray Dataset.

``simulate`` takes what an experiment file holds (a path, a dict of its tables, or the
tables as keyword arguments), runs it through the same pipeline as ``chainrun
simulate`` (validation, solver, run file) and returns what ``open_run`` reads back from
that file, so a Dataset made here and one read from the command's file are the same.

Dimensions: ``time`` (snapshots), ``ball`` (1..N), ``event`` (the contact event log).
Quantities are in the paper's units (mass, stiffness and striker speed 1).

Examples
--------
>>> import chainrun
>>> ds = chainrun.simulate(chain={"n": 5, "k": 1, "alpha": 1.5},
...                        output={"times": {"start": 0, "stop": 10, "step": 0.5}})
>>> ds.final_velocity.sel(ball=5).item()       # doctest: +SKIP
0.98877...
>>> ds.velocity.sel(time=5.0)                  # a snapshot, by time  # doctest: +SKIP
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

__all__ = ["open_run", "simulate"]

_UNITS = "paper units (mass, stiffness and striker speed 1)"

_BALL_VARS = {
    "final_position": "displacement at the end of the run",
    "final_velocity": "velocity at the end of the run",
    "separation_time": "time the ball last lost contact (NaN: never touched or never left)",
    "separation_velocity": "velocity when the ball last lost contact",
}
_EVENT_VARS = {
    "event_time": "time of the contact event",
    "event_contact": "contact j (0-based) joins balls j+1 and j+2",
    "event_kind": "chainrun.solver.EventKind: -3 unload, -2 release, -1 open, 1 close, "
                  "2 engage, 3 reload",
}
#: the quantity of each variable, for its unit in a run in SI
_QUANTITY = {"position": "position", "velocity": "velocity", "final_position": "position",
             "final_velocity": "velocity", "separation_time": "time",
             "separation_velocity": "velocity", "event_time": "time",
             "kinetic_energy": "energy", "potential_energy": "energy", "momentum": "momentum",
             "dissipated_energy": "energy", "contact_dissipation": "energy",
             "sensor_force": "force", "sensor_mean_force": "force"}
_OBSERVABLES = {
    "kinetic_energy": "kinetic energy of the line",
    "potential_energy": "energy stored in the contacts",
    "momentum": "momentum of the line",
}


def open_run(path) -> "xarray.Dataset":  # noqa: F821
    """The run file at ``path`` as an ``xarray.Dataset``, loaded into memory.

    Data variables: ``position`` and ``velocity`` (time, ball); with force sensors,
    ``sensor_force`` (sample, sensor, side) and ``sensor_mean_force``; the observables
    ``kinetic_energy``, ``potential_energy``, ``momentum`` (time), and for a damped line
    ``dissipated_energy`` (time) and ``contact_dissipation`` (contact); the final and
    separation positions, velocities and times (ball); the event log ``event_time``,
    ``event_contact``, ``event_kind`` (event). Attributes: the run's parameters
    (``n``, ``k``, ``alpha``, ``rtol``, ``t_end``, ...), its outcome (``outcome``,
    ``terminal``, ``end_time``, ``message``), its diagnostics (``diagnostics_*``), the
    config text and hash, and the writing software's version. Every quantity has its
    ``units``: the paper's, or SI (m, s, m/s, J, N, ...) for a run in SI.

    Raises ``chainrun.errors.StoreError`` (one line) for a file that is not a readable
    chainrun run file.
    """
    import numpy as np
    import xarray as xr

    from chainrun.store import read_run

    run = read_run(path)
    n = run.n
    coords = {"time": ("time", run.times), "ball": ("ball", np.arange(1, n + 1)),
              "event": ("event", np.arange(run.event_time.size))}
    data = {
        "position": (("time", "ball"), np.asarray(run.positions).reshape(-1, n),
                     {"long_name": "displacement from the initial position"}),
        "velocity": (("time", "ball"), np.asarray(run.velocities).reshape(-1, n),
                     {"long_name": "velocity"}),
    }
    data |= {name: ("time", run.observables[name], {"long_name": text})
             for name, text in _OBSERVABLES.items()}
    data |= {name: ("ball", getattr(run, name), {"long_name": text})
             for name, text in _BALL_VARS.items()}
    data |= {name: ("event", getattr(run, name), {"long_name": text})
             for name, text in _EVENT_VARS.items()}
    if "dissipated_energy" in run.observables:
        data["dissipated_energy"] = ("time", run.observables["dissipated_energy"],
                                     {"long_name": "energy the damping dissipated since t = 0"})
        coords["contact"] = ("contact", np.arange(1, n))
        data["contact_dissipation"] = ("contact", run.contact_dissipation,
                                       {"long_name": "energy each contact dissipated"})
    if run.sensor_balls.size:
        coords |= {"sample": ("sample", run.sensor_time), "sensor": ("sensor", run.sensor_balls),
                   "side": ("side", ["towards ball 1", "away from ball 1"])}
        data["sensor_force"] = (("sample", "sensor", "side"), run.sensor_force,
                                {"long_name": "contact force on each side of a sensor ball"})
        data["sensor_mean_force"] = (("sample", "sensor"), run.sensor_force.mean(axis=2),
                                     {"long_name": "mean of the two: what a sensor measures"})
    from chainrun.units import UNITS

    si = run.units == "si"
    for name, (_dims, _values, meta) in data.items():
        if name not in ("event_contact", "event_kind"):  # numbers, not quantities
            meta["units"] = UNITS["si"][_QUANTITY[name]] if si else _UNITS
    params = {k: v for k, v in run.parameters.items()
              if k not in ("config_resolved", "overrides")}
    attrs = {
        **{k: ("none" if v is None else v) for k, v in params.items()},
        "overrides": json.dumps(run.parameters.get("overrides", {})),
        "outcome": run.outcome, "terminal": int(run.terminal), "end_time": run.end_time,
        "message": run.message, "units": "SI" if si else _UNITS,
        "dissipated_energy": run.dissipated_energy,
        "creator_version": run.creator_version, "created": run.created,
        **{f"diagnostics_{k}": v for k, v in run.diagnostics.items()},
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


def _experiment(config, tables: dict[str, Any]):
    from chainrun.config import load_experiment, parse_experiment
    from chainrun.errors import ConfigError

    if config is not None and not isinstance(config, (str, os.PathLike, Mapping)):
        raise ConfigError("<simulate>", [
            f"config: expected a path or a dict of the experiment's tables, got "
            f"{type(config).__name__}"])
    if isinstance(config, (str, os.PathLike)):
        if tables:
            raise ConfigError(os.fspath(config), [
                "keyword tables are for a config given as a dict, not a file: "
                + ", ".join(sorted(tables))])
        return load_experiment(config)
    data = {"name": "api", **(dict(config) if config is not None else {}), **tables}
    # JSON is YAML: the experiment is parsed, checked and stored as an experiment file is
    return parse_experiment(json.dumps(data, indent=1, default=_plain), "yaml", "<simulate>")


def _plain(value):
    import numpy as np

    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot use a {type(value).__name__} in an experiment")


def simulate(config=None, /, **tables) -> "xarray.Dataset | xarray.DataTree":  # noqa: F821
    """Run an experiment and return its run as an ``xarray.Dataset`` (see ``open_run``).

    Parameters
    ----------
    config : path or dict, optional
        An experiment file (``.toml``, ``.yaml``), or its tables as a dict.
    **tables
        Tables of the experiment file as keyword arguments (``chain=``, ``output=``,
        ``solver=``, ``sweep=``, ``name=``), added to a dict ``config``.

    Returns
    -------
    xarray.Dataset, or xarray.DataTree for an experiment with a sweep (a child
    Dataset per run, named by its run id, e.g. ``"k=2"``).

    Raises
    ------
    chainrun.errors.ConfigError
        For an invalid experiment, naming every wrong key.
    chainrun.errors.ChainrunError
        If a run fails (its message says where and why).
    """
    import xarray as xr

    from chainrun.errors import ChainrunError
    from chainrun.runner import run_file, simulate_run

    experiment = _experiment(config, tables)
    specs = experiment.runs()
    with tempfile.TemporaryDirectory(prefix="chainrun-") as tmp:
        out = {}
        for spec in specs:
            summary = simulate_run(spec, Path(tmp))
            if not summary.ok:
                raise ChainrunError(f"{spec.run_id}: {summary.message}")
            out[spec.run_id] = open_run(run_file(Path(tmp), spec))
    if not experiment.sweep:
        return out[specs[0].run_id]
    return xr.DataTree.from_dict(out, name=experiment.name)
