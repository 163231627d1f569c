"""chainrun from Python: run an experiment, or open a run file or a sweep, as xarray.

``simulate`` takes what an experiment file holds (a path, a dict of its tables, or the
tables as keyword arguments), runs it through the same pipeline as ``chainrun
simulate`` (validation, solver, run file) and returns what ``open_run`` reads back from
that file, so a Dataset made here and one read from the command's file are the same.
``open_sweep`` reads every run of an output folder (a sweep, or an ensemble over random
seeds) as one Dataset along a dimension ``run``.

Dimensions: ``time`` (snapshots), ``ball`` (1..N), ``contact`` (1..N-1), ``wall`` and
``event`` (the contact event log). Quantities are in the run's units: SI for an
experiment in SI, else the paper's (mass, stiffness and striker speed 1).

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
import math
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from chainrun.paths import index_file
from chainrun.units import SWEPT_QUANTITY, UNITS

__all__ = ["open_run", "open_sweep", "pulses", "simulate", "spectrum", "transmission"]

_UNITS = "paper units (mass, stiffness and striker speed 1)"
#: A quantity's ``units`` in the paper's units, short as an axis label takes it
#: (``velocity [paper units]``); the Dataset's ``units`` attribute says what they are.
_PAPER_UNIT = "paper units"

#: Variables along ``ball``: (long name, quantity; None for numbers and names).
_BALL_VARS = {
    "mass": ("mass of each ball", "mass"),
    "initial_velocity": ("velocity at t = 0", "velocity"),
    "initial_position": ("displacement at t = 0 (non-zero when precompressed)", "position"),
    "force": ("constant external force (+ towards ball N)", "force"),
    "final_position": ("displacement at the end of the run", "position"),
    "final_velocity": ("velocity at the end of the run", "velocity"),
    "separation_time": ("time the ball last lost contact (NaN: never touched or never "
                        "left)", "time"),
    "separation_velocity": ("velocity when the ball last lost contact", "velocity"),
}
#: Variables along ``contact`` (contact j joins balls j and j+1).
_CONTACT_VARS = {
    "stiffness": ("kappa of the force law F = kappa delta_+^alpha", "stiffness"),
    "alpha": ("exponent of the force law", None),
    "gap": ("gap: delta_j = x_j - x_(j+1) - gap_j (< 0: an initial overlap)", "gap"),
    "damping": ("eta of F = max(0, kappa delta^alpha + eta delta^beta d(delta)/dt)",
                "damping"),
    "damping_exponent": ("beta, the damping's exponent", None),
    "contact_dissipation": ("energy each contact dissipated by the end", "energy"),
}
#: Variables along ``wall`` (left: before ball 1, right: after ball N); NaN (or 0 for
#: impulse and dissipation) where there is no wall.
_WALL_VARS = {
    "wall_stiffness": ("kappa of the wall's contact (NaN: no wall)", "stiffness"),
    "wall_alpha": ("exponent of the wall's contact (NaN: no wall)", None),
    "wall_gap": ("the wall's gap: delta = x_N - gap (right), -x_1 - gap (left)", "gap"),
    "wall_damping": ("eta of the wall's contact", "damping"),
    "wall_damping_exponent": ("beta of the wall's contact", None),
    "wall_impulse": ("impulse the wall gave the line by the end (+ towards ball N)",
                     "momentum"),
    "wall_dissipation": ("energy the wall's contact dissipated by the end", "energy"),
}
#: A moving wall's motion, one sine of ``walls.<side>.motion`` each (dims wall, sine):
#: NaN where the wall does not move, or moves by a file's samples.
_MOTION_VARS = {
    "wall_motion_amplitude": ("amplitude A of the sine A r(t/T) sin(2 pi f t) the wall "
                              "moves by (+ towards ball N)", "position"),
    "wall_motion_frequency": ("frequency f of the wall's sine", "frequency"),
    "wall_motion_ramp": ("duration T of the sine's smooth start (0: none)", "time"),
}
_EVENT_VARS = {
    "event_time": ("time of the contact event", "time"),
    "event_contact": ("contact j joins balls j and j+1 (0: the left wall, N: the right "
                      "wall)", None),
    "event_kind": ("chainrun.solver.EventKind: -3 unload, -2 release, -1 open, 1 close, "
                   "2 engage, 3 reload", None),
}
_OBSERVABLES = {
    "kinetic_energy": ("kinetic energy of the line, sum m v^2/2", "energy"),
    "potential_energy": ("energy stored in the contacts and walls, less the work of the "
                         "external forces", "energy"),
    "momentum": ("momentum of the line, sum m v", "momentum"),
    "dissipated_energy": ("energy the damping dissipated since t = 0", "energy"),
    "drive_work": ("work the drives (moving walls, forces in time) did since t = 0: "
                   "kinetic + potential + dissipated = initial + drive_work", "energy"),
}

#: The short ``long_name`` of each variable, which xarray's plots take for their axis
#: labels; the longer text of the tables above (what it is, how it is measured, what
#: NaN means) is its ``description``.
_LABELS = {
    "position": "displacement", "mass": "mass", "initial_velocity": "initial velocity",
    "initial_position": "initial displacement", "force": "external force",
    "final_position": "final displacement", "final_velocity": "final velocity",
    "separation_time": "separation time", "separation_velocity": "separation velocity",
    "stiffness": "contact stiffness", "alpha": "force-law exponent", "gap": "gap",
    "damping": "damping coefficient", "damping_exponent": "damping exponent",
    "contact_dissipation": "dissipated energy", "wall_stiffness": "wall stiffness",
    "wall_alpha": "wall force-law exponent", "wall_gap": "wall gap",
    "wall_damping": "wall damping coefficient",
    "wall_damping_exponent": "wall damping exponent", "wall_impulse": "wall impulse",
    "wall_dissipation": "wall dissipated energy",
    "wall_motion_amplitude": "wall motion amplitude",
    "wall_motion_frequency": "wall motion frequency", "wall_motion_ramp": "wall motion ramp",
    "event_time": "event time", "event_contact": "event contact", "event_kind": "event kind",
    "kinetic_energy": "kinetic energy", "potential_energy": "potential energy",
    "momentum": "momentum", "dissipated_energy": "dissipated energy",
    "drive_work": "drive work", "diameter": "diameter", "material": "material",
    "final_velocity_spread": "final velocity spread",
    "separation_velocity_spread": "separation velocity spread",
    "sensor_force": "contact force", "sensor_mean_force": "sensor force",
}
#: The coordinates' labels and, where the name alone does not say it, descriptions.
_COORD_LABELS = {
    "time": ("time", "time of the snapshot"), "ball": ("ball", "ball number (from 1)"),
    "contact": ("contact", "contact j joins balls j and j+1"),
    "wall": ("wall", "left: before ball 1, right: after ball N"),
    "event": ("event", "number of the contact event in the log"),
    "sine": ("sine", "number of the sine in the wall's motion"),
    "sample": ("sample time", "time of the force sensors' sample"),
    "sensor": ("sensor ball", "the ball that carries the force sensor"),
    "side": ("side", "the sensor ball's contact"),
}


def _labelled(name: str, meta: dict) -> dict:
    """``meta`` with the variable's short ``long_name``; its text as ``description``."""
    label = _LABELS.get(name)
    if label is None or meta.get("long_name") == label:
        return meta
    return {**meta, "long_name": label, "description": meta["long_name"]}


def _unit(quantity: str | None, units: str) -> str | None:
    """The ``units`` attribute of a quantity: SI's, or the paper's units."""
    from chainrun.units import UNITS

    if quantity is None:
        return None
    if quantity == "damping":
        return "N s m-(1+beta)" if units == "si" else _PAPER_UNIT
    return UNITS["si"][quantity] if units == "si" else _PAPER_UNIT


def _variables(run) -> tuple[dict, dict]:
    """The run's data variables and coordinates, each variable with its long name and
    units: every number the file holds about the line, its run and its results."""
    import numpy as np

    from chainrun.units import law_unit

    line, n, units = run.line, run.n, run.units
    walls = (line.left, line.right)
    coords = {"time": ("time", run.times), "ball": ("ball", np.arange(1, n + 1)),
              "contact": ("contact", np.arange(1, n)),
              "wall": ("wall", ["left", "right"]),
              "event": ("event", np.arange(run.event_time.size))}
    values = {
        "mass": line.mass, "initial_velocity": line.velocity,
        "initial_position": line.position, "force": line.force,
        **{name: getattr(run, name) for name in ("final_position", "final_velocity",
                                                 "separation_time", "separation_velocity")},
        **{name: getattr(line, name) for name in ("stiffness", "alpha", "gap", "damping",
                                                  "damping_exponent")},
        "contact_dissipation": run.contact_dissipation,
        **{f"wall_{key}": np.array([np.nan if w is None else getattr(w, key) for w in walls])
           for key in ("stiffness", "alpha", "gap", "damping", "damping_exponent")},
        "wall_impulse": run.wall_impulse, "wall_dissipation": run.wall_dissipation,
        "event_time": run.event_time, "event_contact": run.event_contact,
        "event_kind": run.event_kind,
        **{name: run.observables[name] for name in _OBSERVABLES},
    }
    data = {
        "position": (("time", "ball"), np.asarray(run.positions).reshape(-1, n),
                     {"long_name": "displacement from the initial (touching) position"},
                     "position"),
        "velocity": (("time", "ball"), np.asarray(run.velocities).reshape(-1, n),
                     {"long_name": "velocity"}, "velocity"),
    }
    for dim, table in (("ball", _BALL_VARS), ("contact", _CONTACT_VARS), ("wall", _WALL_VARS),
                       ("event", _EVENT_VARS), ("time", _OBSERVABLES)):
        for name, (text, quantity) in table.items():
            data[name] = (dim, np.asarray(values[name]), {"long_name": text}, quantity)
    if line.diameter is not None:
        data["diameter"] = ("ball", np.asarray(line.diameter),
                            {"long_name": "diameter of each sphere"}, "diameter")
        data["material"] = ("ball", np.asarray(line.material, dtype=str),
                            {"long_name": "material of each sphere ('': constants given "
                                          "explicitly)"}, None)
    if run.check is not None:
        for name, what in (("final", "final velocity"), ("separation", "separation velocity")):
            data[f"{name}_velocity_spread"] = (
                "ball", np.asarray(getattr(run.check, f"{name}_velocity_spread")),
                {"long_name": f"|difference| of the {what} between the run and its check "
                              f"at rtol {run.check.rtol:g} (chainrun.check)"}, "velocity")
    motions = [None if w is None or w.motion is None else w.motion for w in walls]
    if any(m is not None for m in motions):
        sines = max(len(m.sines) for m in motions if m is not None) or 1
        table = np.full((3, 2, sines), np.nan)
        for side, motion in enumerate(motions):
            for i, sine in enumerate(motion.sines if motion is not None else ()):
                table[:, side, i] = sine.amplitude, sine.frequency, sine.ramp
        coords["sine"] = ("sine", np.arange(1, sines + 1))
        for row, (name, (text, quantity)) in enumerate(_MOTION_VARS.items()):
            data[name] = (("wall", "sine"), table[row], {"long_name": text}, quantity)
    if run.sensor_balls.size:
        coords |= {"sample": ("sample", run.sensor_time), "sensor": ("sensor", run.sensor_balls),
                   "side": ("side", ["towards ball 1", "away from ball 1"])}
        data["sensor_force"] = (("sample", "sensor", "side"), run.sensor_force,
                                {"long_name": "contact force on each side of a sensor ball"},
                                "force")
        data["sensor_mean_force"] = (("sample", "sensor"), run.sensor_force.mean(axis=2),
                                     {"long_name": "mean of the two: what a sensor measures"},
                                     "force")
    out = {}
    for name, (dims, array, meta, quantity) in data.items():
        unit = _unit(quantity, units)
        out[name] = (dims, array, _labelled(name, meta) | ({"units": unit} if unit else {}))
    # a missing wall's coefficient is NaN: its unit is the contacts' law's
    has_wall = np.isfinite(np.asarray(values["wall_alpha"], dtype=float)).any()
    for name, exponents in (("stiffness", line.alpha), ("damping", line.damping_exponent),
                            ("wall_stiffness", values["wall_alpha"] if has_wall else line.alpha),
                            ("wall_damping", values["wall_damping_exponent"]
                             if has_wall else line.damping_exponent)):
        if name in out and "units" in out[name][2] and units == "si":
            quantity = "damping" if name.endswith("damping") else "stiffness"
            out[name][2]["units"] = law_unit(quantity, exponents, units)
    for name, (dim, values) in coords.items():
        label, text = _COORD_LABELS[name]
        unit = _unit("time", units) if name in ("time", "sample") else None
        coords[name] = (dim, values, {"long_name": label, "description": text,
                                      **({"units": unit} if unit else {})})
    return out, coords


#: What a run's parameter left unset reads as in its Dataset's attributes, as in its file.
_UNSET = {"t_end": math.nan, "max_events": -1}


def open_run(path) -> "xarray.Dataset":  # noqa: F821
    """The run file at ``path`` as an ``xarray.Dataset``, loaded into memory.

    Dimensions: ``time`` (snapshots), ``ball`` (1..N), ``contact`` (1..N-1: contact j
    joins balls j and j+1), ``wall`` (``"left"``, ``"right"``), ``event`` (the contact
    event log); with force sensors ``sample``, ``sensor`` (their ball numbers) and
    ``side``. Balls and contacts are numbered alike in every variable.

    Data variables: ``position`` and ``velocity`` (time, ball); the observables
    ``kinetic_energy``, ``potential_energy``, ``momentum``, ``dissipated_energy`` and
    ``drive_work`` (time; on a driven line ``kinetic_energy + potential_energy +
    dissipated_energy - drive_work`` stays at its initial value); the line: ``mass``,
    ``initial_velocity``, ``initial_position``, ``force`` (ball), and for real
    spheres ``diameter`` and ``material``; ``stiffness``, ``alpha``, ``gap``,
    ``damping``, ``damping_exponent`` (contact); the walls'
    ``wall_stiffness``, ``wall_alpha``, ``wall_gap``, ``wall_damping``,
    ``wall_damping_exponent`` (NaN where there is no wall) and what they did,
    ``wall_impulse`` and ``wall_dissipation`` (wall); where a wall moves by sines
    (``walls.<side>.motion``), ``wall_motion_amplitude``, ``wall_motion_frequency``
    and ``wall_motion_ramp`` (wall, sine: one entry per sine, NaN where there is none);
    the results: ``final_position``,
    ``final_velocity``, ``separation_time``, ``separation_velocity`` (ball),
    ``contact_dissipation`` (contact); for a checked run (``--check``),
    ``final_velocity_spread`` and ``separation_velocity_spread`` (ball), the attribute
    ``check_rtol`` and the check's outcome; the event log ``event_time``, ``event_contact``
    (the contact's number, 0 and N for the walls) and ``event_kind`` (event); with
    sensors, ``sensor_force`` (sample, sensor, side) and ``sensor_mean_force``.
    Every quantity has its ``units``: SI (s, m, m/s, kg, N, J, ...) for a run in SI,
    else the paper's; every variable and coordinate a short ``long_name``, the label
    xarray's plots give an axis, and where the name does not say it all a
    ``description``. Attributes: the run's parameters (``n``, ``k``, ``alpha``,
    ``rtol``, ``t_end``, ...), its outcome (``outcome``, ``terminal``, ``end_time``,
    ``message``, ``final_drive_work``: the drives' work by ``end_time``), its
    diagnostics (``diagnostics_*``), the line's scales (``scales_*``), the config text
    and hash, and the writing software's version.

    Raises ``chainrun.errors.StoreError`` (one line) for a file that is not a readable
    chainrun run file, or a ``path`` that is not a path.
    """
    import xarray as xr

    from chainrun.errors import StoreError
    from chainrun.store import read_run

    if not isinstance(path, (str, os.PathLike)):
        raise StoreError(f"open_run: expected a run file's path, got {type(path).__name__}"
                         + (" (a Dataset is a run already open)"
                            if isinstance(path, xr.Dataset) else ""))
    run = read_run(path)
    data, coords = _variables(run)
    si = run.units == "si"
    params = {k: v for k, v in run.parameters.items()
              if k not in ("config_resolved", "overrides")}
    scales = run.model["scales"] if run.model else {}
    attrs = {
        # as the run file has them: an unset t_end NaN, no event limit -1 (docs/schema.md)
        **{k: (_UNSET.get(k, "none") if v is None else v) for k, v in params.items()},
        "overrides": json.dumps(run.parameters.get("overrides", {})),
        "outcome": run.outcome, "terminal": int(run.terminal), "end_time": run.end_time,
        "message": run.message, "units": "SI" if si else _UNITS,
        "dissipated_energy": run.dissipated_energy, "final_drive_work": run.drive_energy,
        "creator_version": run.creator_version, "created": run.created,
        **{f"diagnostics_{k}": v for k, v in run.diagnostics.items()},
        **{f"scales_{k}": v for k, v in scales.items()},
        **{f"scales_{k}_unit": UNITS[run.units]["position" if k == "length" else k]
           for k in scales},
        **({"check_rtol": run.check.rtol, "check_outcome": run.check.outcome}
           if run.check is not None else {}),
    }
    return xr.Dataset(data, coords=coords, attrs=attrs)


#: What differs from run to run of a sweep, kept as variables along ``run``: the
#: outcome of each, and every diagnostic.
_PER_RUN = ("outcome", "terminal", "end_time", "message", "dissipated_energy",
            "final_drive_work", "config_hash", "n", "k", "alpha")
#: What each of those is along run, and its quantity (for its units; "wall": seconds
#: of the computer's clock, None: a number without a unit)
_PER_RUN_ATTRS = {
    "outcome": ("how the run ended", None), "terminal": ("whether it reached its "
                                                          "terminal state", None),
    "end_time": ("time the run ended", "time"), "message": ("the run's summary line", None),
    "final_drive_work": ("work of the drives over the run", "energy"),
    "config_hash": ("sha256 of the run's resolved configuration", None),
    "n": ("balls in the line", None), "k": ("balls that strike (K)", None),
    "diagnostics_steps": ("accepted integration steps", None),
    "diagnostics_rejected_steps": ("rejected integration steps", None),
    "diagnostics_events": ("contact events", None),
    "diagnostics_momentum_error": ("momentum error, relative to the line's scale", None),
    "diagnostics_energy_error": ("energy balance error, relative to the impact energy",
                                 None),
    "diagnostics_energy_correction": ("energy restored by the projection, relative", None),
    "diagnostics_wall_time": ("the solver's wall-clock time", "wall"),
    "diagnostics_max_window": ("most balls integrated at once", None),
    "diagnostics_rtol": ("relative tolerance of a step", None),
    "diagnostics_velocity_floor": ("velocity floor of the contact rules, in the line's "
                                   "velocity scale", None),
    "diagnostics_closed_form_collisions": ("isolated binary collisions taken whole", None),
    "diagnostics_energy_floor": ("what rounding alone can leave in the energy balance, "
                                 "relative to the impact energy", None),
}
#: The short labels of those whose text is longer (the text is their description).
_PER_RUN_LABELS = {
    "config_hash": "config hash", "diagnostics_momentum_error": "momentum error",
    "diagnostics_energy_error": "energy error",
    "diagnostics_energy_correction": "energy correction",
    "diagnostics_energy_floor": "energy rounding floor",
    "diagnostics_velocity_floor": "velocity floor",
    "diagnostics_closed_form_collisions": "closed-form collisions",
}
#: Values that fill a run's shorter event log (its events are numbered 0..E-1).
_EVENT_FILL = {"event_contact": -1, "event_kind": 0}


def open_sweep(folder) -> "xarray.Dataset":  # noqa: F821
    """Every run of the output folder ``folder`` (its ``index.h5``) as one Dataset; or
    of a sweep ``chainrun.simulate`` returned (its DataTree), the same.

    The runs' Datasets (``open_run``) are put side by side along a new dimension
    ``run``, whose coordinate is the run ids; the swept keys are coordinates along it
    (``chain.mass.seed``, ``replica``, ``chain.k``: NaN for a run without the key). A
    variable of every run has the dimension ``run`` first: ``final_velocity`` has shape
    (runs, balls), so an ensemble's mean final velocity is
    ``ds.final_velocity.mean("run")``. Runs whose lines or snapshot times differ are
    aligned on the union of balls and times (NaN where a run has none). The event
    logs, of different lengths, are kept whole: run r's events are
    ``ds.event_time.isel(run=r)[: ds.event_count.isel(run=r)]``, the rest filled with
    NaN (times), -1 (contacts) and 0 (kinds). Each run's outcome, ``end_time``,
    ``terminal``, ``message``, ``config_hash``, ``n``, ``k`` and diagnostics
    (``diagnostics_*``) are variables along ``run`` (``alpha`` and
    ``dissipated_energy`` stay the runs' variables of those names, per contact and
    over time); the attributes are those every run shares.

    Raises
    ------
    chainrun.errors.StoreError
        For a folder without an index file, a run file that cannot be read, or
        something neither a folder's path nor a sweep's DataTree.
    """
    import xarray as xr

    from chainrun.errors import StoreError
    from chainrun.store import read_index

    if isinstance(folder, xr.DataTree):     # simulate's sweep: a child per run
        runs = [child.to_dataset() for child in folder.children.values()]
        if not runs:
            raise StoreError("open_sweep: the DataTree holds no runs")
        for name, ds in zip(folder.children, runs):
            if "final_velocity" not in ds or "overrides" not in ds.attrs:
                raise StoreError(f"open_sweep: {name} is not a run's Dataset (a sweep of "
                                 "chainrun.simulate's, or an output folder, has runs)")
        return _along_run(runs, list(folder.children))
    if not isinstance(folder, (str, os.PathLike)):
        raise StoreError(f"open_sweep: expected an output folder's path or the DataTree "
                         f"chainrun.simulate returns for a sweep, got "
                         f"{type(folder).__name__}")
    folder = Path(folder)
    index = index_file(folder)
    if not index.is_file():
        raise StoreError(f"{folder}: no index.h5 (not a chainrun output folder)")
    rows = read_index(index)
    if not rows:
        raise StoreError(f"{folder}: the index lists no runs")
    return _along_run([open_run(folder / str(row["file"])) for row in rows],
                      [str(row["run_id"]) for row in rows])


def _along_run(runs: list, ids: list[str]) -> "xarray.Dataset":  # noqa: F821
    """The runs' Datasets (``open_run``) side by side along ``run``, named by ``ids``,
    with the swept keys as coordinates (``open_sweep``)."""
    import numpy as np
    import xarray as xr

    keys = list(dict.fromkeys(key for ds in runs for key in json.loads(ds.attrs["overrides"])))
    swept = {key: ("run", [json.loads(ds.attrs["overrides"]).get(key, np.nan) for ds in runs])
             for key in keys}
    per_run = [key for key in runs[0].attrs
               if key in _PER_RUN or key.startswith("diagnostics_")]
    counts = [ds.sizes["event"] for ds in runs]
    # a variable of the same name (alpha per contact, dissipated_energy over time)
    # already holds that number along run, in more detail: it is kept
    runs = [ds.assign({key: ds.attrs[key] for key in per_run if key not in ds.data_vars})
            for ds in runs]
    out = xr.concat(runs, dim="run", join="outer", fill_value={**_EVENT_FILL},
                    combine_attrs="drop_conflicts", coords="minimal", compat="override")
    for key in per_run:
        out.attrs.pop(key, None)
    out.attrs.pop("overrides", None)
    out = out.assign_coords(run=("run", list(ids), {"long_name": "run",
                                                    "description": "the run's id"}),
                            **swept)
    units = out.attrs.get("units")
    for key in keys:
        quantity = SWEPT_QUANTITY.get(key.rpartition(".")[2])
        unit = _unit(quantity, "si" if units == "SI" else "paper")
        last = key.rpartition(".")[2]
        label = _LABELS.get(last, last.replace("_", " "))
        out[key].attrs = {"long_name": label if label == key else f"{label} ({key})",
                          "description": f"the swept key {key}",
                          **({"units": unit} if unit else {})}
    for key in per_run:
        if key in _PER_RUN_ATTRS and key in out.data_vars and not out[key].attrs:
            text, quantity = _PER_RUN_ATTRS[key]
            unit = "s" if quantity == "wall" else _unit(quantity, "si" if units == "SI"
                                                        else "paper")
            label = _PER_RUN_LABELS.get(key)
            meta = {"long_name": label, "description": text} if label else {"long_name": text}
            out[key].attrs = meta | ({"units": unit} if unit else {})
    return out.assign(event_count=("run", np.array(counts),
                                   {"long_name": "events in each run's log"}))


def _experiment(config, tables: dict[str, Any], source: str = "<simulate>",
                to_run: bool = True):
    from chainrun.config import load_experiment, parse_experiment
    from chainrun.errors import ConfigError

    if config is not None and not isinstance(config, (str, os.PathLike, Mapping)):
        raise ConfigError(source, [
            f"config: expected a path or a dict of the experiment's tables, got "
            f"{type(config).__name__}"])
    if type(config).__module__.partition(".")[0] == "xarray":   # a Mapping, not tables
        raise ConfigError(source, [
            f"config: expected a path or a dict of the experiment's tables, got an xarray "
            f"{type(config).__name__} (a result, not an experiment)"])
    if isinstance(config, (str, os.PathLike)):
        if tables:
            raise ConfigError(os.fspath(config), [
                "keyword tables are for a config given as a dict, not a file: "
                + ", ".join(sorted(tables))])
        return load_experiment(config, to_run=to_run)
    import yaml

    data = {"name": "api", **(dict(config) if config is not None else {}), **tables}
    # written as YAML (numpy values as plain numbers and lists), then parsed, checked and
    # stored as an experiment file is; PyYAML writes 1e-06 as 1.0e-06, which YAML 1.1
    # reads back as a number (JSON's 1e-06 it would read as text)
    problems: list[str] = []
    plain = _plain(data, "", problems)
    if problems:
        raise ConfigError(source, problems)
    text = yaml.safe_dump(plain, sort_keys=False, default_flow_style=None, width=88)
    return parse_experiment(text, "yaml", source, to_run=to_run)


def _plain(value, key: str, problems: list[str]):
    """``value`` as plain numbers, text, lists and dicts (numpy's values, ranges and
    tuples as lists, paths as text); what has no such form is a problem naming its key."""
    import numpy as np

    if isinstance(value, Mapping):
        return {str(k): _plain(v, f"{key}.{k}" if key else str(k), problems)
                for k, v in value.items()}
    if isinstance(value, (list, tuple, range)):
        return [_plain(v, f"{key}[{i}]", problems) for i, v in enumerate(value)]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist(), key, problems) if value.dtype == object else value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, os.PathLike):
        return os.fspath(value)
    if value is None or isinstance(value, (str, int, float)):
        return value
    problems.append(f"{key}: cannot use a {type(value).__name__} in an experiment "
                    "(a number, text, a list or a table)")
    return None


def simulate(config=None, /, *, check: bool = False,
             **tables) -> "xarray.Dataset | xarray.DataTree":  # noqa: F821
    """Run an experiment and return its run as an ``xarray.Dataset`` (see ``open_run``).

    Parameters
    ----------
    config : path or dict, optional
        An experiment file (``.toml``, ``.yaml``), or its tables as a dict.
    check : bool
        Check every run, as ``chainrun simulate --check`` (or ``solver={"check":
        True}``): run it again at a tenth of its tolerance; the Dataset then has
        ``final_velocity_spread`` and ``separation_velocity_spread``.
    **tables
        Tables of the experiment file as keyword arguments (``chain=``, ``output=``,
        ``solver=``, ``sweep=``, ``name=``), added to a dict ``config``. Numpy arrays
        and numbers, tuples and ranges are taken as lists and numbers, paths as text;
        any other value is a ``ConfigError`` naming its key.

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
    import warnings

    import numpy as np
    import xarray as xr

    from chainrun.check import energy_doubt
    from chainrun.config.doubts import doubts
    from chainrun.errors import ChainrunError, ChainrunWarning, ConfigError, show_value
    from chainrun.runner import run_file, simulate_run, sweep_specs

    if not isinstance(check, (bool, np.bool_)):
        raise ConfigError("<simulate>", [f"check: expected True or False, got "
                                         f"{show_value(check)}"])
    experiment = _experiment(config, tables)
    specs = sweep_specs(experiment, check=bool(check))
    for doubt in doubts(specs):
        warnings.warn(doubt, ChainrunWarning, stacklevel=2)
    with tempfile.TemporaryDirectory(prefix="chainrun-") as tmp:
        out = {}
        for spec in specs:
            summary = simulate_run(spec, Path(tmp))
            if not summary.ok:
                raise ChainrunError(f"{spec.run_id}: {summary.message}")
            doubt = energy_doubt(summary.energy_error, summary.energy_floor)
            if doubt:
                warnings.warn(f"{spec.run_id}: {doubt}", ChainrunWarning, stacklevel=2)
            out[spec.run_id] = open_run(run_file(Path(tmp), spec))
    if not experiment.sweep:
        return out[specs[0].run_id]
    return xr.DataTree.from_dict(out, name=experiment.name)
