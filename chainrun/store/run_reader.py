"""Reading run files: ``read_run`` and ``RunData``, snapshots read lazily.

Files of every readable version (``_h5._READABLE``) read into the same ``RunData``:
a version 1 file numbers its event log's contacts from 0 and keeps the walls' impulses
and dissipation as attributes (``docs/schema.md``).
"""

from __future__ import annotations

import dataclasses
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from chainrun.check import Check
from chainrun.errors import StoreError
from chainrun.solver import Diagnostics, Drive, Line, Outcome, Solution, Wall
from chainrun.solver import physics
from chainrun.store import _h5
from chainrun.store._h5 import RUN_FORMAT
from chainrun.store.run_writer import OBSERVABLES


class Snapshots:
    """Positions or velocities of a run file, shape (T, N), read only when indexed.

    ``snaps[i]`` reads one snapshot, ``snaps[:, j]`` one ball's history, and
    ``np.asarray(snaps)`` everything; each access opens the file for reading.
    """

    def __init__(self, path: Path, name: str, shape: tuple[int, int]):
        self.path = path
        self.name = name
        self.shape = shape
        self.dtype = np.dtype(np.float64)

    ndim = 2

    def __len__(self) -> int:
        return self.shape[0]

    def __getitem__(self, key):
        key = key if isinstance(key, tuple) else (key,)
        if len(key) > 2:
            raise IndexError(f"too many indices for an array of shape {self.shape}")
        simple = all(isinstance(k, (int, np.integer)) or
                     (isinstance(k, slice) and (k.step or 1) > 0) for k in key)
        if not simple or any(isinstance(k, (int, np.integer)) and not
                             -size <= k < size for k, size in zip(key, self.shape)):
            return np.asarray(self)[key]
        key = tuple(int(k) % size if isinstance(k, (int, np.integer)) else k
                    for k, size in zip(key, self.shape))
        key = key + (slice(None),) * (2 - len(key)) + (0,)
        return self._read(key)

    def __array__(self, dtype=None, copy=None):
        data = self._read((slice(None), slice(None), 0))
        return data if dtype is None else data.astype(dtype)

    def _read(self, key):
        """Read a selection, reporting a damaged file as a one-line StoreError."""
        try:
            with h5py.File(self.path, "r") as h5:
                return h5[self.name][key]
        except (OSError, KeyError) as exc:
            raise StoreError(f"{self.path}: damaged snapshot data in {self.name} "
                             f"({exc})") from None

    def __repr__(self) -> str:
        return f"Snapshots({str(self.path)!r}, {self.name!r}, shape={self.shape})"



@dataclass(frozen=True, eq=False)
class RunData:
    """The contents of one run file: the ``Solution`` the solver returned, as the file
    holds it, and what only the file has.

    Every field of ``chainrun.solver.Solution`` is an attribute of a ``RunData``
    (``run.final_velocity``, ``run.event_time``, ``run.line``, ``run.drive_energy``,
    ...), read from ``solution``; a field the solver gains needs no declaration here.
    Three read as the file holds them: ``event_contact`` numbers contacts as the file
    does (1..N-1; 0 is the left wall, N the right), ``outcome`` is the outcome's
    value (a str, e.g. ``"terminal"``) and ``diagnostics`` is the dict of what the
    file's diagnostics hold (an older file's fewer, a checked run's ``check_wall_time``
    besides). ``positions`` and ``velocities`` are ``Snapshots``, read when indexed;
    ``line`` is rebuilt from ``model`` (the paper's line of N, K and alpha in a file
    without one).

    Attributes
    ----------
    solution : chainrun.solver.Solution
        What the solver returned (its event contacts numbered from 0, as it numbers
        them; ``diagnostics`` None in a file that lacks one of its fields).
    path : Path
    format_version : int
    created : str
        ISO 8601 time the file was written.
    creator_version : str
        chainrun version that wrote it.
    parameters : dict
        ``n``, ``k``, ``alpha``, ``t_end`` (None when unbounded), ``rtol``,
        ``max_events`` (None when unbounded), ``velocity_floor``, ``experiment``,
        ``run_id``, ``config_hash``, ``config`` (the full config text),
        ``config_resolved`` and ``overrides`` (parsed from JSON).
    steps : ndarray of int64, shape (T,)
        Snapshot indices.
    observables : dict of ndarray, shape (T,)
        ``kinetic_energy``, ``potential_energy``, ``momentum``,
        ``dissipated_energy`` (the energy the damping took by then; 0 on an elastic
        line) and ``drive_work`` (the work the drives did by then; 0 on a line without
        them) at each snapshot.
    diagnostics : dict
        The fields of ``chainrun.solver.Diagnostics`` the file holds.
    model : dict or None
        The line as solved (``/model``): ``units``; per ball ``mass``, ``velocity``,
        ``position``, ``force`` (shape (N,)); per contact ``stiffness``, ``alpha``,
        ``gap``, ``damping``, ``damping_exponent`` (shape (N-1,)); for real spheres
        ``diameter`` and ``material`` (shape (N,); None otherwise); ``walls``
        ({"left"/"right": {"stiffness", "alpha", "gap", "damping",
        "damping_exponent", "motion"}}, the walls present; a moving wall's ``motion`` a
        ``chainrun.solver.Drive``), ``drives`` (``(ball, Drive)`` pairs, balls from 0)
        and ``scales`` (mass, length, time, velocity, force: the paper's units of this
        line, in its units). None for files written before the model was recorded:
        those hold the paper's line.
    check : chainrun.check.Check or None
        The conditioning check (``solver.check``, ``--check``): the check run's
        tolerance, outcome and time, and the spread of each ball's final and separation
        velocity; None for a run without one.
    """

    solution: Solution
    path: Path
    format_version: int
    created: str
    creator_version: str
    parameters: dict[str, Any]
    steps: np.ndarray
    observables: dict[str, np.ndarray]
    diagnostics: dict[str, Any]
    model: dict[str, Any] | None = None
    check: Check | None = None

    def __getattr__(self, name: str) -> Any:
        # only for names not found on the RunData itself: the Solution's fields
        if name.startswith("__") or name == "solution":
            raise AttributeError(name)
        try:
            return getattr(self.solution, name)
        except AttributeError:
            raise AttributeError(f"'RunData' object has no attribute {name!r}") from None

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | {f.name for f in dataclasses.fields(Solution)})

    @property
    def event_contact(self) -> np.ndarray:
        """The contact of each event as the file numbers it: contact j joins balls j
        and j+1 (1..N-1; 0 is the left wall, N the right)."""
        return self.solution.event_contact + 1

    @property
    def outcome(self) -> str:
        """The ``chainrun.solver.Outcome`` value, e.g. ``"terminal"``."""
        return self.solution.outcome.value

    @property
    def impact_energy(self) -> float:
        """The energy the impact put into the line (``physics.impact_energy``)."""
        return physics.impact_energy(self.line)

    @property
    def baseline_energy(self) -> float:
        """The potential energy of the static state the line started in (0 unless it
        started precompressed; ``physics.baseline_energy``): the observables'
        ``potential_energy`` less this is the energy the impact left in the contacts."""
        return physics.baseline_energy(self.line)

    def static_load_work(self, t) -> np.ndarray:
        """The static load's work by the times ``t`` as the walls move, on a driven line
        that starts precompressed (``physics.static_load_work``; 0 otherwise): the part
        of the drives' work, and of the contacts' energy, that the walls' return gives
        back."""
        return physics.static_load_work(self.line, t)

    @property
    def units(self) -> str:
        """"paper" or "si": the units of every quantity in the file."""
        return self.model["units"] if self.model else "paper"

    def contact_forces(self, stride: int = 1) -> np.ndarray:
        """Contact forces ``kappa (c - g)_+^alpha`` at the snapshots, from the stored
        positions and the line's stiffnesses, exponents and gaps (the paper's law for
        its line; on a damped line, its damped law, from the velocities too), of every
        ``stride``-th contact (reading only its two balls); shape (T, C)."""
        n = self.n
        keys = ["alpha", "stiffness", "gap"]
        damped = self.model is not None and bool(np.any(self.model["damping"] != 0.0))
        if self.model is None:
            law = dict(alpha=self.alpha)
        else:
            keys += ["damping", "damping_exponent"] if damped else []
            law = {key: np.asarray(self.model[key])[::stride] for key in keys}
        if stride == 1:
            if damped:
                law["v"] = np.asarray(self.velocities)
            return physics.contact_forces(np.asarray(self.positions), **law)
        law = {k: np.asarray(v)[:, None] if np.ndim(v) else v for k, v in law.items()}
        if damped:
            law["v"] = np.stack([self.velocities[:, 0:n - 1:stride],
                                 self.velocities[:, 1:n:stride]], axis=-1)
        pairs = np.stack([self.positions[:, 0:n - 1:stride],
                          self.positions[:, 1:n:stride]], axis=-1)
        return physics.contact_forces(pairs, **law)[..., 0]


    def wall_forces(self) -> np.ndarray:
        """The walls' contact forces at the snapshots (``physics.wall_forces``: their
        laws, a moving wall's motion, and on a damped wall's its damping from the
        velocities), left and right, 0 where there is no wall; shape (T, 2)."""
        line = self.line
        damped = any(w is not None and w.damping for w in line.walls)
        return physics.wall_forces(np.asarray(self.positions), line, np.asarray(self.times),
                                   np.asarray(self.velocities) if damped else None)


def read_run(path) -> RunData:
    """Read a run file (snapshots lazily), after checking its format and version.

    Raises
    ------
    StoreError
        If the file is missing, not a chainrun run file, of another format version,
        lacks an item of the schema, or holds one it cannot read (a damaged HDF5
        object, text that is not UTF-8 or JSON, a number that is not one).
    """
    name = os.fspath(path)
    with _h5.open_read(name) as h5:
        version = _h5.check_open(h5, name, RUN_FORMAT)
        try:
            _h5.get(h5, "particles/chain/velocity/value")  # read lazily: check it is there
            return _read_run(h5, Path(name), version)
        except KeyError as exc:
            reason = exc.args[0] if exc.args else ""
            if isinstance(reason, str) and reason.startswith("Unable"):  # from h5py
                raise StoreError(f"{name}: damaged run file ({_h5.h5_reason(exc)})") from None
            raise StoreError(f"{name}: damaged run file (missing {reason})") from None
        except (OSError, RuntimeError, ValueError, TypeError, OverflowError) as exc:
            # HDF5 checksum and decoding errors, bad UTF-8 or JSON, "soon" as a time
            raise StoreError(f"{name}: damaged run file ({_h5.h5_reason(exc)})") from None


def _read_run(h5: h5py.File, path: Path, version: int) -> RunData:
    p = _h5.get(h5, "parameters")
    params = {key: _h5.py(value) for key, value in p.attrs.items()}
    for key in ("n", "k", "alpha"):
        _h5.attr(p, key)
    if isinstance(params.get("t_end"), float) and np.isnan(params["t_end"]):
        params["t_end"] = None
    if params.get("max_events") == -1:
        params["max_events"] = None
    for key in ("config_resolved", "overrides"):
        if key in params:
            params[key] = json.loads(params[key])

    pos = _h5.get(h5, "particles/chain/position")
    times = _h5.get(pos, "time")[()]
    shape = _h5.get(pos, "value").shape[:2]
    observables = {name: _h5.get(h5, f"observables/{name}/value")[()] for name in OBSERVABLES}
    # every line's since version 2; a damped line's only before
    observables["dissipated_energy"] = (
        _h5.get(h5, "observables/dissipated_energy/value")[()]
        if "dissipated_energy" in h5["observables"] else np.zeros(times.shape))
    # written since drives exist: none before
    observables["drive_work"] = (
        _h5.get(h5, "observables/drive_work/value")[()]
        if "drive_work" in h5["observables"] else np.zeros(times.shape))
    res = _h5.get(h5, "results")
    ev = _h5.get(h5, "events")
    diag = _h5.get(h5, "diagnostics")
    diagnostics = {key: _h5.py(value) for key, value in diag.attrs.items()}
    model = _read_model(h5)
    n, k, alpha = int(params["n"]), int(params["k"]), float(params["alpha"])
    solution = Solution(
        n=n, k=k, alpha=alpha,
        outcome=Outcome(_h5.as_str(_h5.attr(res, "outcome"))),
        message=_h5.as_str(_h5.attr(res, "message")),
        end_time=float(_h5.attr(res, "end_time")),
        terminal=bool(_h5.attr(res, "terminal")),
        final_position=_h5.get(res, "final_position")[()],
        final_velocity=_h5.get(res, "final_velocity")[()],
        separation_time=_h5.get(res, "separation_time")[()],
        separation_velocity=_h5.get(res, "separation_velocity")[()],
        event_time=_h5.get(ev, "time")[()],
        # the solver numbers contacts from 0 (the left wall -1), as version 1 files do
        event_contact=_h5.get(ev, "contact")[()] - (0 if version == 1 else 1),
        event_kind=_h5.get(ev, "kind")[()],
        times=times,
        positions=Snapshots(path, "particles/chain/position/value", shape),
        velocities=Snapshots(path, "particles/chain/velocity/value", shape),
        diagnostics=_diagnostics(diagnostics),
        line=_line(model, n, k, alpha),
        dissipated=observables["dissipated_energy"],
        drive_work=observables["drive_work"],
        drive_energy=float(res.attrs.get("drive_work", 0.0)),
        **_read_sensors(h5),
        **_read_walls(res, n, version),
    )
    return RunData(
        solution=solution,
        path=path,
        format_version=version,
        created=_h5.as_str(h5.attrs.get("created", "")),
        creator_version=_h5.as_str(_h5.attr(_h5.get(h5, "h5md/creator"), "version")),
        parameters=params,
        steps=_h5.get(pos, "step")[()],
        observables=observables,
        diagnostics=diagnostics,
        model=model,
        check=_read_check(res, diag),
    )


def _diagnostics(stored: dict[str, Any]) -> Diagnostics | None:
    """The solver's ``Diagnostics`` from the file's (None if one of its fields is not
    there)."""
    names = {f.name for f in dataclasses.fields(Diagnostics)}
    try:
        return Diagnostics(**{key: value for key, value in stored.items() if key in names})
    except TypeError:
        return None


def _line(model: dict[str, Any] | None, n: int, k: int, alpha: float) -> Line:
    """The line as solved, rebuilt from the file's ``model``: the paper's line of N, K
    and alpha in a file without one."""
    if model is None:
        return Line.paper(n, k, alpha)
    walls = {side: Wall(**wall) for side, wall in model["walls"].items()}
    return Line(**{key: model[key] for key in (
        "mass", "stiffness", "alpha", "gap", "velocity", "force", "position",
        "damping", "damping_exponent", "diameter", "material", "drives")}, **walls)


def _read_walls(res: h5py.Group, n: int, version: int) -> dict:
    """What the damping dissipated, by contact and wall, and the walls' impulses (in a
    version 1 file, attributes present only where there was a wall or damping)."""
    if version >= 2:
        return dict(dissipated_energy=float(_h5.attr(res, "dissipated_energy")),
                    contact_dissipation=_h5.get(res, "contact_dissipation")[()],
                    wall_dissipation=_h5.get(res, "wall_dissipation")[()],
                    wall_impulse=_h5.get(res, "wall_impulse")[()])
    sides = ("left", "right")
    return dict(
        dissipated_energy=float(res.attrs.get("dissipated_energy", 0.0)),
        contact_dissipation=(_h5.get(res, "contact_dissipation")[()]
                             if "contact_dissipation" in res else np.zeros(max(n - 1, 0))),
        wall_dissipation=np.array([float(res.attrs.get(f"{s}_wall_dissipation", 0.0))
                                   for s in sides]),
        wall_impulse=np.array([float(res.attrs.get(f"{s}_wall_impulse", 0.0)) for s in sides]))


def _read_model(h5: h5py.File) -> dict[str, Any] | None:
    """The ``/model`` group as a dict (None in files written before it existed)."""
    if "model" not in h5:
        return None
    group = h5["model"]
    model: dict[str, Any] = {"units": _h5.as_str(_h5.attr(group, "units"))}
    for name in ("mass", "velocity", "position", "force", "stiffness", "alpha", "gap"):
        model[name] = _h5.get(group, name)[()]
    walls = _h5.get(group, "walls")
    for name in ("damping", "damping_exponent"):  # a damped line's
        n_contacts = model["stiffness"].shape[0]
        model[name] = _h5.get(group, name)[()] if name in group else np.zeros(n_contacts)
    model["diameter"] = _h5.get(group, "diameter")[()] if "diameter" in group else None
    model["material"] = (np.char.decode(_h5.get(group, "material")[()], "ascii")
                         if "material" in group else None)
    model["walls"] = {side: {key: float(walls[side].attrs.get(key, 0.0))
                             for key in ("stiffness", "alpha", "gap", "damping",
                                         "damping_exponent")}
                      for side in ("left", "right") if side in walls}
    for side, wall in model["walls"].items():
        g = walls[side]
        wall["motion"] = _read_drive(g["motion"]) if "motion" in g else None
    drives = group["drives"] if "drives" in group else {}
    model["drives"] = tuple((int(_h5.attr(drives[key], "ball")) - 1, _read_drive(drives[key]))
                            for key in sorted(drives, key=int))
    model["scales"] = {key: float(value) for key, value in _h5.get(group, "scales").attrs.items()
                       if not key.endswith("_unit")}
    return model


def _read_check(res: h5py.Group, diag: h5py.Group) -> Check | None:
    """The conditioning check, if the run had one (optional datasets of ``results``)."""
    if "final_velocity_spread" not in res:
        return None
    return Check(rtol=float(_h5.attr(res, "check_rtol")),
                 outcome=_h5.as_str(_h5.attr(res, "check_outcome")),
                 message=_h5.as_str(res.attrs.get("check_message", "")),
                 wall_time=float(diag.attrs.get("check_wall_time", np.nan)),
                 final_velocity_spread=_h5.get(res, "final_velocity_spread")[()],
                 separation_velocity_spread=_h5.get(res, "separation_velocity_spread")[()])


def _read_drive(group: h5py.Group) -> Drive:
    if _h5.as_str(_h5.attr(group, "kind")) == "samples":
        return Drive.from_samples(_h5.get(group, "time")[()], _h5.get(group, "value")[()])
    return Drive.of_sines([dict(amplitude=float(a), frequency=float(f), ramp=float(r))
                           for a, f, r in zip(_h5.get(group, "amplitude")[()],
                                              _h5.get(group, "frequency")[()],
                                              _h5.get(group, "ramp")[()])])


def _read_sensors(h5: h5py.File) -> dict:
    """The force sensors' samples, if the run had sensors (an optional group)."""
    if "sensors" not in h5:
        return {}
    group = h5["sensors"]
    return dict(sensor_balls=_h5.get(group, "ball")[()], sensor_time=_h5.get(group, "time")[()],
                sensor_force=_h5.get(group, "force")[()])


# --------------------------------------------------------------------- index files


def run_config_hash(path) -> str | None:
    """The ``config_hash`` of a complete run file, or None if there is none to trust.

    A sweep skips a run whose file returns the run's own hash. None means the file
    is missing, unreadable, truncated or not HDF5, not a chainrun run file of this
    format version, or lacks ``/parameters@config_hash``, ``/results`` or
    ``/diagnostics``. Never raises for a bad file.

    Parameters
    ----------
    path : str or path

    Returns
    -------
    str or None
    """
    name = os.fspath(path)
    try:
        with h5py.File(name, "r") as h5:
            _h5.check_open(h5, name, RUN_FORMAT)
            if "results" not in h5 or "diagnostics" not in h5:
                return None
            value = h5["parameters"].attrs["config_hash"]
        return _h5.as_str(value) or None
    except Exception:  # any reason the file cannot be read means: no trusted hash
        return None


# -------------------------------------------------------------------- analysis files
#
# An *analysis file* holds what ``chainrun analyze`` derives for one artefact of the
# paper (a figure, a table or a set of printed numbers): named scalar values, the arrays
