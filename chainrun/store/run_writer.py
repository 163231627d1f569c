"""Writing run files: one run, snapshot by snapshot, in H5MD.

A *run file* holds one run (one point of a sweep): its parameters and full config text,
the line as solved, the snapshots of positions and velocities, the energies and momentum
at each snapshot, the contact event log, the final and separation velocities of every
ball and the solver's diagnostics. The tree is drawn in ``docs/schema.md``; change it
together with ``RUN_FORMAT_VERSION``.

Run files follow H5MD 1.1 [1]_ with spatial dimension 1 (``/h5md``, ``/particles``,
``/observables``, ``/parameters``); ``/model``, ``/results``, ``/events``,
``/diagnostics`` and ``/sensors`` are chainrun's own groups, which H5MD allows. Every
dataset carries netCDF-4 dimension scales (``time``, ``ball``, ``spatial``, ``event``),
so ``xarray.open_datatree(path, engine="h5netcdf")`` opens a run file with named
dimensions.

The writer computes nothing about the line: the energies and momentum of each snapshot,
like everything of ``finish``'s ``Solution``, come from its caller.

References
----------
.. [1] P. de Buyl, P. H. Colberg and F. Höfling, "H5MD: A structured, efficient,
   and portable file format for molecular data", Comput. Phys. Commun. 185, 1546
   (2014); specification 1.1 at https://www.nongnu.org/h5md/
"""

from __future__ import annotations

import dataclasses
import json
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

import h5py
import numpy as np

import chainrun
from chainrun import atomic
from chainrun.check import Check
from chainrun.errors import StoreError
from chainrun.solver import Drive, EventKind, Solution
from chainrun.store import _h5
from chainrun.store._h5 import BALL_CHUNK, GZIP, RUN_FORMAT
from chainrun.limits import free_disk, human_size
from chainrun.units import UNITS, law_unit, run_message

if TYPE_CHECKING:  # the config parser (pydantic, YAML) is not needed to write files
    from chainrun.config import RunSpec

#: H5MD specification version the run files conform to (major, minor).
H5MD_VERSION = (1, 1)
#: Snapshots of positions and velocities are kept in memory up to this many bytes and
#: written together: one by one, a snapshot of a short line costs some twenty HDF5
#: calls, most of a short run's time. A larger snapshot is written when it is taken.
SNAPSHOT_BUFFER = 2**20
#: the free space checked after every this many bytes of snapshots written
DISK_CHECK_BYTES = 2**26
#: a run stops (its file discarded) rather than leave less than this free on its disk
DISK_RESERVE = 10**9

#: The observables written at each snapshot, with their description and unit.
OBSERVABLES = {
    "kinetic_energy": ("sum m v^2/2", "energy"),
    "potential_energy": ("sum kappa delta_+^(alpha+1)/(alpha+1) over contacts and walls, "
                         "less sum f x", "energy"),
    "momentum": ("sum m v", "momentum"),
}


def _author() -> str:
    return os.environ.get("USER") or "chainrun user"



class _Element:
    """An H5MD time-dependent element (``step``, ``time``, ``value``) that grows by rows."""

    def __init__(self, group: h5py.Group, name: str, item_shape: tuple[int, ...],
                 item_scales: list[h5py.Dataset], chunk_hint: int, long_name: str):
        self.group = g = _h5.group(group, name)
        rows = max(1, min(chunk_hint, 4096))
        self.time = g.create_dataset("time", shape=(0,), maxshape=(None,), dtype="f8",
                                     chunks=(rows,))
        self.time.make_scale("time")
        self.time.attrs["long_name"] = "time of the snapshot"
        self.step = g.create_dataset("step", shape=(0,), maxshape=(None,), dtype="i8",
                                     chunks=(rows,))
        self.step.dims[0].attach_scale(self.time)
        self.step.attrs["long_name"] = "snapshot index"
        if item_shape:  # (N, 1): one snapshot per chunk row, compressed
            opts = dict(chunks=(1, min(item_shape[0], BALL_CHUNK)) + item_shape[1:], **GZIP)
        else:
            opts = dict(chunks=(rows,))
        self.value = g.create_dataset("value", shape=(0,) + item_shape,
                                      maxshape=(None,) + item_shape, dtype="f8", **opts)
        self.value.dims[0].attach_scale(self.time)
        for axis, scale in enumerate(item_scales, start=1):
            self.value.dims[axis].attach_scale(scale)
        self.value.attrs["long_name"] = long_name
        self.rows = 0  # rows in the file
        self.pending: list[tuple[int, float, Any]] = []  # rows to write: (step, t, value)

    def append(self, step: int, t: float, value) -> None:
        """Keep a row to write with ``flush`` (``value`` must stay as it is until then)."""
        self.pending.append((step, t, value))

    def flush(self) -> None:
        """Write the rows kept since the last flush."""
        if not self.pending:
            return
        row, m = self.rows, len(self.pending)
        steps, times, values = zip(*self.pending)
        for ds in (self.time, self.step, self.value):
            ds.resize(row + m, axis=0)
        self.time[row:row + m] = times
        self.step[row:row + m] = steps
        if self.value.compression is None:
            self.value[row:row + m] = values
        else:
            for i, value in enumerate(values):
                _h5.write_chunks(self.value, (row + i,), value)
        self.rows = row + m
        self.pending.clear()



class RunWriter:
    """Write one run file, snapshot by snapshot, then atomically put it in place.

    Use as a context manager. ``snapshot`` takes the solver's snapshot (as its
    ``on_snapshot`` hook does) and the line's energies and momentum at it, which the
    caller computes (``chainrun.runner.recorder`` is that hook); snapshots are written
    in blocks of up to
    ``SNAPSHOT_BUFFER`` bytes (a larger snapshot at once, without a copy);
    ``finish`` writes the rest, the results, events and diagnostics, closes the file
    and renames it to ``path``. Leaving the ``with`` block by an exception, or
    without calling ``finish``, deletes the temporary file: nothing appears under
    ``path``. An existing file at ``path`` is replaced.

    Parameters
    ----------
    path : str or path
        The run file to create.
    spec : RunSpec
        The run; its parameters, config text and line (``spec.line``) are written at
        once.
    velocity_floor : float
        The solver's velocity floor (``chainrun.solver.velocity_floor(spec.rtol)``).

    Examples
    --------
    >>> from chainrun.runner import recorder
    >>> with RunWriter("results/runs/k=2.h5", spec, velocity_floor=1e-12) as w:
    ...     sol = simulate(spec.line, spec.times, on_snapshot=recorder(w, spec.line))
    ...     w.finish(sol)
    """

    def __init__(self, path, spec: RunSpec, *, velocity_floor: float):
        self.path = Path(path)
        self.temp_path = atomic.temp_name(self.path)
        self._spec = spec
        self._n = int(spec.n)
        self._units = getattr(spec, "units", "paper")
        self._pending_bytes = 0
        self._unchecked_bytes = 0
        self._done = False
        self._h5: h5py.File | None = _h5.create(self.path, self.temp_path, "run file")
        try:
            self._write_header(float(velocity_floor))
        except BaseException:
            self.abort()
            raise

    # -- layout ------------------------------------------------------------------

    def _write_header(self, velocity_floor: float) -> None:
        h5, spec, n = self._h5, self._spec, self._n
        _h5.stamp(h5, RUN_FORMAT)

        meta = _h5.group(h5, "h5md")
        meta.attrs["version"] = np.array(H5MD_VERSION, dtype=np.int32)
        _h5.group(meta, "author").attrs["name"] = _h5.fixed_str(_author())
        creator = _h5.group(meta, "creator")
        creator.attrs["name"] = _h5.fixed_str("chainrun")
        creator.attrs["version"] = _h5.fixed_str(chainrun.__version__)

        params = _h5.group(h5, "parameters")
        a = params.attrs
        a["n"] = np.int64(n)
        a["k"] = np.int64(spec.k)
        a["alpha"] = np.float64(spec.alpha)
        a["t_end"] = np.float64(np.nan if spec.t_end is None else spec.t_end)
        a["t_end_unit"] = UNITS[self._units]["time"]
        a["rtol"] = np.float64(spec.rtol)
        a["max_events"] = np.int64(-1 if spec.max_events is None else spec.max_events)
        a["velocity_floor"] = np.float64(velocity_floor)
        a["experiment"] = str(spec.experiment)
        a["run_id"] = str(spec.run_id)
        a["config_hash"] = str(spec.config_hash)
        a["config"] = str(spec.source_text)
        a["config_resolved"] = _h5.to_json(spec.config)
        a["overrides"] = _h5.to_json(spec.overrides)

        chain = _h5.group(_h5.group(h5, "particles"), "chain")
        box = _h5.group(chain, "box")
        box.attrs["dimension"] = np.int32(1)
        box.attrs["boundary"] = np.array([b"none"], dtype=h5py.string_dtype("ascii", 4))
        ball = _h5.scale(chain, "ball", np.arange(1, n + 1, dtype=np.int64),
                      "ball number n = 1..N (ball 1 is struck first)")
        spatial = _h5.scale(chain, "spatial", np.array(["x"], dtype=h5py.string_dtype()),
                         "spatial axis")
        hint = len(np.atleast_1d(spec.times))
        self._position = _Element(chain, "position", (n, 1), [ball, spatial], hint,
                                  "displacement x_n from the initial touching position")
        self._velocity = _Element(chain, "velocity", (n, 1), [ball, spatial], hint,
                                  "velocity dx_n/dt")
        obs = _h5.group(h5, "observables")
        self._observables = {name: _Element(obs, name, (), [], hint, long_name)
                             for name, (long_name, _) in OBSERVABLES.items()}
        units = UNITS[self._units]
        for element, unit in ((self._position, "position"), (self._velocity, "velocity")):
            element.value.attrs["unit"] = units[unit]
            element.time.attrs["unit"] = units["time"]
        for name, (_, unit) in OBSERVABLES.items():
            self._observables[name].value.attrs["unit"] = units[unit]
            self._observables[name].time.attrs["unit"] = units["time"]
        self._write_model(h5)

    def _write_model(self, h5: h5py.File) -> None:
        """``/model``: the line as solved, per ball and per contact, its walls, its
        units and the scales it was solved in."""
        line, units = self._spec.line, UNITS[self._units]
        model = _h5.group(h5, "model")
        model.attrs["units"] = self._units
        ball = _h5.scale(model, "ball", np.arange(1, line.n + 1, dtype=np.int64),
                      "ball number n = 1..N")
        contact = _h5.scale(model, "contact", np.arange(1, line.n, dtype=np.int64),
                         "contact j = 1..N-1 joins balls j and j+1")
        for name, scale, unit, long_name in (
            ("mass", ball, "mass", "mass of each ball"),
            ("velocity", ball, "velocity", "initial velocity"),
            ("position", ball, "position", "initial displacement (from touching, no gap)"),
            ("force", ball, "force", "constant external force on each ball (+x: to ball N)"),
            ("stiffness", contact, "stiffness", "kappa of F = kappa delta_+^alpha"),
            ("alpha", contact, "alpha", "exponent of the contact's force law"),
            ("gap", contact, "gap", "gap g_j: delta_j = x_j - x_j+1 - g_j (< 0: overlap)"),
        ):
            ds = _h5.array(model, name, getattr(line, name), [scale], long_name)
            ds.attrs["unit"] = units[unit]
        model["stiffness"].attrs["unit"] = law_unit("stiffness", line.alpha, self._units)
        if line.diameter is not None:
            _h5.array(model, "diameter", line.diameter, [ball],
                   "diameter of each sphere").attrs["unit"] = units["diameter"]
        if line.material is not None:
            _h5.array(model, "material", np.char.encode(line.material, "ascii"), [ball],
                   "material of each sphere (chainrun.materials; empty: constants given "
                   "explicitly)")
        if line.is_damped:
            eta = _h5.array(model, "damping", line.damping, [contact],
                         "eta of F = max(0, kappa delta^alpha + eta delta^beta d(delta)/dt)")
            eta.attrs["unit"] = law_unit("damping", line.damping_exponent, self._units)
            _h5.array(model, "damping_exponent", line.damping_exponent, [contact],
                   "beta, the damping's exponent").attrs["unit"] = "1"
        walls = _h5.group(model, "walls")
        for side, wall in (("left", line.left), ("right", line.right)):
            if wall is not None:
                g = _h5.group(walls, side)
                g.attrs["stiffness"] = np.float64(wall.stiffness)
                g.attrs["alpha"] = np.float64(wall.alpha)
                g.attrs["gap"] = np.float64(wall.gap)
                if wall.damping:
                    g.attrs["damping"] = np.float64(wall.damping)
                    g.attrs["damping_exponent"] = np.float64(wall.damping_exponent)
                if wall.motion is not None:
                    _write_drive(_h5.group(g, "motion"), wall.motion, units["position"],
                                 units["time"])
        if line.drives:
            drives = _h5.group(model, "drives")
            for i, (ball, drive) in enumerate(line.drives):
                g = _h5.group(drives, str(i))
                g.attrs["ball"] = np.int64(ball + 1)
                _write_drive(g, drive, units["force"], units["time"])
        scales = _h5.group(model, "scales")
        sc = line.scales()
        for name in ("mass", "length", "time", "velocity", "force"):
            scales.attrs[name] = np.float64(getattr(sc, name))
            scales.attrs[f"{name}_unit"] = units["position" if name == "length" else name]

    # -- writing -----------------------------------------------------------------

    def _live(self) -> h5py.File:
        if self._h5 is None:
            raise StoreError(f"{self.path}: run writer is closed")
        return self._h5

    def snapshot(self, index: int, t: float, x: np.ndarray, v: np.ndarray,
                 observables: Mapping[str, float]) -> None:
        """Write one snapshot (``x``, ``v`` need only be valid during the call).

        Parameters
        ----------
        index : int
            Snapshot index (stored as H5MD ``step``).
        t : float
        x, v : ndarray, shape (N,)
            Displacements and velocities.
        observables : mapping of str to float
            The line's energies and momentum at ``t``, one per name of
            ``OBSERVABLES``, computed by the caller (``chainrun.solver.physics``).
        """
        self._live()
        x = np.asarray(x, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        if x.shape != (self._n,) or v.shape != (self._n,):
            raise ValueError(
                f"snapshot arrays must have shape ({self._n},); got {x.shape} and {v.shape}"
            )
        missing = [name for name in OBSERVABLES if name not in observables]
        if missing:
            raise ValueError(f"snapshot lacks the observables {', '.join(missing)}")
        for name, element in self._observables.items():
            element.append(index, t, float(observables[name]))
        self._pending_bytes += x.nbytes + v.nbytes
        if self._pending_bytes < SNAPSHOT_BUFFER:  # kept: the caller reuses its arrays
            self._position.append(index, t, x[:, None].copy())
            self._velocity.append(index, t, v[:, None].copy())
        else:
            self._position.append(index, t, x[:, None])
            self._velocity.append(index, t, v[:, None])
            self._flush()

    def _flush(self) -> None:
        for element in (self._position, self._velocity, *self._observables.values()):
            element.flush()
        self._unchecked_bytes += self._pending_bytes
        self._pending_bytes = 0
        if self._unchecked_bytes >= DISK_CHECK_BYTES:
            self._unchecked_bytes = 0
            self._check_disk()

    def _check_disk(self) -> None:
        """Stop the run before its file fills the disk: a ``StoreError`` (the file is
        then discarded) where less than ``DISK_RESERVE`` is left. Before the run, the
        estimate only warns (``chainrun.limits``): it counts every snapshot before
        compression, and balls at rest take no room."""
        free = free_disk(self.temp_path.parent)
        if free is not None and free < DISK_RESERVE:
            raise StoreError(
                f"{self.path}: stopped before the disk fills: {human_size(free)} left "
                f"(chainrun keeps {human_size(DISK_RESERVE)} free) after "
                f"{self._position.rows} snapshots; fewer output.times, or another "
                f"output folder (-o), would fit")

    def finish(self, solution: Solution, check: Check | None = None) -> None:
        """Write results, events and diagnostics (and the ``check``'s spreads, if
        given); close; rename to ``path``."""
        h5 = self._live()
        try:
            self._flush()
            self._write_solution(h5, solution)
            if check is not None:
                self._write_check(h5, check)
            self._h5 = None
            _h5.commit(h5, self.temp_path, self.path)
        except BaseException:
            self._h5 = h5
            self.abort()
            raise
        self._done = True

    def _write_solution(self, h5: h5py.File, sol: Solution) -> None:
        n = self._n
        if int(sol.n) != n:
            raise StoreError(f"{self.path}: solution has n = {sol.n}, run spec n = {n}")
        results = _h5.group(h5, "results")
        ball = _h5.scale(results, "ball", np.arange(1, n + 1, dtype=np.int64),
                      "ball number n = 1..N")
        for name, long_name in (
            ("final_velocity", "velocity at end_time"),
            ("final_position", "displacement at end_time"),
            ("separation_velocity", "velocity when the ball last lost contact (NaN: never)"),
            ("separation_time", "time when the ball last lost contact (NaN: never)"),
        ):
            data = np.asarray(getattr(sol, name), dtype=np.float64)
            if data.shape != (n,):
                raise StoreError(f"{self.path}: {name} has shape {data.shape}, expected ({n},)")
            ds = _h5.array(results, name, data, [ball], long_name)
            ds.attrs["unit"] = UNITS[self._units][name.split("_")[1]]
        wall = _h5.scale(results, "wall", np.array(["left", "right"], dtype=h5py.string_dtype()),
                      "the wall at each end: left (before ball 1), right (after ball N)")
        self._write_dissipation(h5, results, sol, wall)
        ds = _h5.array(results, "wall_impulse", np.asarray(sol.wall_impulse, dtype=np.float64),
                    [wall], "impulse each wall gave the line by end_time (+x towards ball "
                    "N; 0 where there is no wall)")
        ds.attrs["unit"] = UNITS[self._units]["momentum"]
        results.attrs["end_time"] = np.float64(sol.end_time)
        results.attrs["end_time_unit"] = UNITS[self._units]["time"]
        results.attrs["terminal"] = np.bool_(sol.terminal)
        results.attrs["outcome"] = str(getattr(sol.outcome, "value", sol.outcome))
        results.attrs["message"] = run_message(sol, self._units)

        events = _h5.group(h5, "events")
        t = np.asarray(sol.event_time, dtype=np.float64).reshape(-1)
        contact = np.asarray(sol.event_contact, dtype=np.int64).reshape(-1)
        kind = np.asarray(sol.event_kind, dtype=np.int8).reshape(-1)
        if not (len(t) == len(contact) == len(kind)):
            raise StoreError(f"{self.path}: event arrays differ in length "
                             f"({len(t)}, {len(contact)}, {len(kind)})")
        event = _h5.scale(events, "event", np.arange(len(t), dtype=np.int64),
                       "event number, in time order")
        _h5.array(events, "time", t, [event], "time of the event").attrs["unit"] = \
            UNITS[self._units]["time"]
        # the solver's arrays count contacts from 0 (and the left wall as -1); the file
        # numbers them as it numbers balls: contact j joins balls j and j+1
        c = _h5.array(events, "contact", contact + 1, [event],
                   "contact j joins balls j and j+1 (0: the left wall, N: the right wall)")
        c.attrs["base"] = np.int64(1)
        k = _h5.array(events, "kind", kind, [event], "what happened to the contact")
        k.attrs["kinds"] = json.dumps({str(int(e)): e.name.lower() for e in EventKind})
        k.attrs["flag_values"] = np.array([int(e) for e in EventKind], dtype=np.int8)
        k.attrs["flag_meanings"] = " ".join(e.name.lower() for e in EventKind)

        diag = _h5.group(h5, "diagnostics")
        for key, value in dataclasses.asdict(sol.diagnostics).items():
            diag.attrs[key] = value

        balls = np.asarray(sol.sensor_balls, dtype=np.int64).reshape(-1)
        if balls.size:
            sensors = _h5.group(h5, "sensors")
            units = UNITS[self._units]
            sample = _h5.scale(sensors, "time", np.asarray(sol.sensor_time, dtype=np.float64),
                            "sample time: 0, dt, 2 dt, ... up to end_time")
            sample.attrs["unit"] = units["time"]
            sensor = _h5.scale(sensors, "ball", balls, "sensor ball number (1..N)")
            force = np.asarray(sol.sensor_force, dtype=np.float64)
            side = _h5.scale(sensors, "side", np.array([0, 1], dtype=np.int64),
                          "0: the contact towards ball 1; 1: the contact away from it")
            _h5.array(sensors, "force", force, [sample, sensor, side],
                   "contact force on each side of the sensor ball (0 at a line's end)"
                   ).attrs["unit"] = units["force"]
            _h5.array(sensors, "mean_force", force.mean(axis=2), [sample, sensor],
                   "mean of the two contact forces: what a sensor inside the ball measures"
                   ).attrs["unit"] = units["force"]
            sensors.attrs["time_unit"] = units["time"]  # (of dt and end)
            sensors.attrs["dt"] = np.float64(self._spec.sensor_dt)
            sensors.attrs["end"] = np.float64(np.nan if self._spec.sensor_end is None
                                              else self._spec.sensor_end)

    def _write_check(self, h5: h5py.File, check: Check) -> None:
        """The conditioning check (``chainrun.check``): the spread of every ball's final
        and separation velocity between the run and its check at ``check.rtol``."""
        results, n = h5["results"], self._n
        ball = results["ball"]
        for name, what in (("final_velocity", "final velocity"),
                           ("separation_velocity", "separation velocity (0: NaN in "
                                                   "both runs; inf: NaN in one)")):
            data = np.asarray(getattr(check, f"{name}_spread"), dtype=np.float64)
            if data.shape != (n,):
                raise StoreError(f"{self.path}: {name}_spread has shape {data.shape}, "
                                 f"expected ({n},)")
            ds = _h5.array(results, f"{name}_spread", data, [ball],
                        f"|difference| of the {what} between the run and its check "
                        "run at check_rtol")
            ds.attrs["unit"] = UNITS[self._units]["velocity"]
        results.attrs["check_rtol"] = np.float64(check.rtol)
        results.attrs["check_outcome"] = str(check.outcome)
        results.attrs["check_message"] = str(check.message)
        h5["diagnostics"].attrs["check_wall_time"] = np.float64(check.wall_time)

    def _write_dissipation(self, h5: h5py.File, results: h5py.Group, sol: Solution,
                           wall: h5py.Dataset) -> None:
        """What the damping dissipated (0 on an elastic line): by each snapshot (an
        observable beside the energies), in total, and by each contact and wall; and
        likewise the work the drives did (0 on a line without them)."""
        n, energy = self._n, UNITS[self._units]["energy"]
        times = np.asarray(sol.times, dtype=np.float64)

        def observable(name: str, values, description: str) -> None:
            # an energy by each snapshot; a line without it stores zeros
            element = _Element(h5["observables"], name, (), [], len(times), description)
            values = np.asarray(values, dtype=np.float64)
            if values.size != times.size:
                values = np.zeros(times.size)
            for i, (t, v) in enumerate(zip(times, values)):
                element.append(i, float(t), float(v))
            element.flush()
            element.value.attrs["unit"] = energy
            element.time.attrs["unit"] = UNITS[self._units]["time"]

        observable("dissipated_energy", sol.dissipated,
                   "energy dissipated by the damping since t = 0")
        results.attrs["dissipated_energy"] = np.float64(sol.dissipated_energy)
        results.attrs["dissipated_energy_unit"] = energy
        observable("drive_work", sol.drive_work,
                   "work the drives (moving walls, forces in time) did since t = 0")
        results.attrs["drive_work"] = np.float64(sol.drive_energy)
        results.attrs["drive_work_unit"] = energy
        contact = _h5.scale(results, "contact", np.arange(1, n, dtype=np.int64),
                         "contact j = 1..N-1 joins balls j and j+1")
        per = np.asarray(sol.contact_dissipation, dtype=np.float64)
        ds = _h5.array(results, "contact_dissipation", per if per.size else np.zeros(n - 1),
                    [contact], "energy each contact dissipated by end_time")
        ds.attrs["unit"] = energy
        ds = _h5.array(results, "wall_dissipation",
                    np.asarray(sol.wall_dissipation, dtype=np.float64),
                    [wall], "energy each wall dissipated by end_time (0 where there is "
                    "no wall)")
        ds.attrs["unit"] = energy

    def abort(self) -> None:
        """Close and delete the temporary file; nothing is written under ``path``."""
        h5, self._h5 = self._h5, None
        _h5.discard(h5, self.temp_path)

    def __enter__(self) -> "RunWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if not self._done:
            self.abort()
        return False



def _write_drive(group: h5py.Group, drive: Drive, unit: str, time_unit: str) -> None:
    """A drive (``chainrun.solver.Drive``) in ``group``: its sines (``amplitude``,
    ``frequency``, ``ramp``, one entry each) or its samples (``time``, ``value``)."""
    if drive.times is not None:
        group.attrs["kind"] = "samples"
        for name, data, u in (("time", drive.times, time_unit), ("value", drive.values, unit)):
            group.create_dataset(name, data=np.asarray(data, dtype=np.float64)).attrs["unit"] = u
        return
    group.attrs["kind"] = "sines"
    for name, u in (("amplitude", unit), ("frequency", f"1/{time_unit}"),
                    ("ramp", time_unit)):
        data = np.array([getattr(sine, name) for sine in drive.sines], dtype=np.float64)
        group.create_dataset(name, data=data).attrs["unit"] = u
