"""Run files and index files: the one module of chainrun that reads and writes HDF5.

This module owns the on-disk format. A *run file* holds one run (one point of a
sweep): its parameters and full config text, the snapshots of positions and
velocities, the energies and momentum at each snapshot, the contact event log, the
final and separation velocities of every ball and the solver's diagnostics. An
*index file* lists the runs of one experiment as a table and links to each run file.
The tree of both files is drawn in ``docs/schema.md``; change it together with
``RUN_FORMAT_VERSION`` or ``INDEX_FORMAT_VERSION``.

Run files follow H5MD 1.1 [1]_ with spatial dimension 1 (``/h5md``, ``/particles``,
``/observables``, ``/parameters``); ``/results``, ``/events`` and ``/diagnostics``
are chainrun's own groups, which H5MD allows. Every dataset carries netCDF-4
dimension scales (``time``, ``ball``, ``spatial``, ``event``), so
``xarray.open_datatree(path, engine="h5netcdf")`` opens a run file with named
dimensions.

Files are written atomically (``chainrun.atomic``): under a temporary name beside the
target, flushed to disk and renamed over it only when complete, so a reader never sees
a half-written file under the final name.

References
----------
.. [1] P. de Buyl, P. H. Colberg and F. Höfling, "H5MD: A structured, efficient,
   and portable file format for molecular data", Comput. Phys. Commun. 185, 1546
   (2014); specification 1.1 at https://www.nongnu.org/h5md/
"""

from __future__ import annotations

import dataclasses
import datetime as _dt
import functools
import json
import os
import re
import zlib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable

import h5py
import numpy as np

import chainrun
from chainrun import atomic
from chainrun.check import Check
from chainrun.errors import StoreError
from chainrun.solver import Drive, EventKind, Line, Solution, Wall
from chainrun.solver import physics
from chainrun.units import UNITS

if TYPE_CHECKING:  # the config parser (pydantic, YAML) is not needed to read files
    from chainrun.config import RunSpec

__all__ = [
    "INDEX_FORMAT",
    "INDEX_FORMAT_VERSION",
    "RUN_FORMAT",
    "RUN_FORMAT_VERSION",
    "RunData",
    "RunWriter",
    "Snapshots",
    "check_format",
    "read_index",
    "read_run",
    "write_index",
    "write_run",
]

#: Format name and version of a run file (root attributes ``format``, ``format_version``).
RUN_FORMAT = "chainrun-run"
RUN_FORMAT_VERSION = 2
#: Format name and version of an experiment's index file.
INDEX_FORMAT = "chainrun-index"
INDEX_FORMAT_VERSION = 1
_FORMAT_VERSIONS = {RUN_FORMAT: RUN_FORMAT_VERSION, INDEX_FORMAT: INDEX_FORMAT_VERSION}
#: The versions each format is still read in: a run file of version 1 numbers its event
#: log's contacts from 0 and keeps the walls' impulses and dissipation as attributes.
_READABLE = {RUN_FORMAT: (1, 2), INDEX_FORMAT: (1,)}

#: H5MD specification version the run files conform to (major, minor).
H5MD_VERSION = (1, 1)

#: Chunk length along the ball axis of large arrays (2**16 float64 = 512 KiB).
BALL_CHUNK = 2**16
#: Snapshots of positions and velocities are kept in memory up to this many bytes and
#: written together: one by one, a snapshot of a short line costs some twenty HDF5
#: calls, most of a short run's time. A larger snapshot is written when it is taken.
SNAPSHOT_BUFFER = 2**20
#: Arrays with more elements than this are chunked and compressed.
COMPRESS_ABOVE = 4096
_GZIP_LEVEL = 1
_GZIP = dict(compression="gzip", compression_opts=_GZIP_LEVEL, shuffle=True)

# HDF5 1.8 object headers: large attributes (the config text) go to dense storage.
_LIBVER = "v108"

#: The names of the observables written at each snapshot.
OBSERVABLES = ("kinetic_energy", "potential_energy", "momentum")

#: Columns every index entry must have, in table order, with their dtype.
INDEX_COLUMNS: dict[str, str] = {
    "run_id": "str",
    "file": "str",
    "n": "int",
    "k": "int",
    "alpha": "float",
    "outcome": "str",
    "terminal": "bool",
    "end_time": "float",
    "events": "int",
    "wall_time": "float",
    "config_hash": "str",
}


# --------------------------------------------------------------------------- helpers


def _now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def _author() -> str:
    return os.environ.get("USER") or "chainrun user"


def _fixed_str(value: str) -> np.ndarray:
    """A scalar fixed-length UTF-8 string, as H5MD asks for its metadata."""
    raw = value.encode("utf-8") or b" "
    return np.array(raw, dtype=h5py.string_dtype("utf-8", len(raw)))


def _as_str(value: Any) -> str:
    if isinstance(value, np.ndarray) and value.shape == ():
        value = value[()]
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8")
    return str(value)


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"{type(obj).__name__} is not JSON serializable")


def _to_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, default=_json_default)


def _py(value: Any) -> Any:
    """An HDF5 attribute value as a plain Python object."""
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8")
    if isinstance(value, np.ndarray):
        return [_py(v) for v in value.tolist()] if value.ndim else _py(value[()])
    if isinstance(value, np.generic):
        return value.item()
    return value


def _group(parent: h5py.Group, name: str) -> h5py.Group:
    return parent.create_group(name, track_order=True)


def _scale(group: h5py.Group, name: str, data: np.ndarray, long_name: str) -> h5py.Dataset:
    """A 1-d dataset that is also the netCDF dimension ``name`` of its group."""
    ds = _array(group, name, data, [], long_name)
    ds.make_scale(name)
    return ds


_deflate_pool: ThreadPoolExecutor | None = None


def _forget_deflate_pool() -> None:
    # a forked child inherits the pool object but none of its threads
    global _deflate_pool
    _deflate_pool = None


os.register_at_fork(after_in_child=_forget_deflate_pool)


def _deflate_chunk(chunk: np.ndarray) -> bytes:
    """One chunk through HDF5's shuffle and deflate filters, in that order.

    Shuffle stores the elements' first bytes, then their second bytes, and so on
    (H5Zshuffle.c); deflate is a zlib stream at the dataset's level.
    """
    size = chunk.dtype.itemsize
    planes = np.ascontiguousarray(chunk).view(np.uint8).reshape(-1, size).T
    return zlib.compress(np.ascontiguousarray(planes), _GZIP_LEVEL)


def _bits(data: np.ndarray) -> np.ndarray | None:
    """``data``'s elements as unsigned integers of the same size, flattened: equal where
    their bytes are (a NaN equals itself, -0.0 is not 0.0); None for other sizes."""
    size = data.dtype.itemsize
    if size not in (1, 2, 4, 8):
        return None
    return np.ascontiguousarray(data).reshape(-1).view(f"u{size}")


def _write_deflated(ds: h5py.Dataset, lead: tuple[int, ...], data: np.ndarray) -> None:
    """Write ``data`` into ``ds[lead + (...)]`` chunk by chunk, compressing on every core.

    ``ds`` was created with ``_GZIP`` and chunks that span ``data``'s trailing axes and
    cut its first axis. h5py would compress the chunks one after another inside one
    write; zlib releases the GIL, so a pool of threads compresses them side by side and
    each is stored as it is (``write_direct_chunk``). The edge chunk is padded with
    zeros to the full chunk shape, as HDF5 stores it.

    A chunk made of the dataset's fill value alone is not stored at all: HDF5 reads an
    unstored chunk as the fill value. Ahead of a wave the balls are at rest where they
    started, so a snapshot of a long line is mostly chunks of zeros; the masses of a
    uniform line are one value, the fill value ``_array`` gives them. (Only for chunks
    not stored before, which is how the writers here use it.)
    """
    global _deflate_pool
    chunk_shape = ds.chunks[len(lead):]
    step = chunk_shape[0]
    data = np.asarray(data, dtype=ds.dtype)
    fill = _bits(np.asarray([ds.fillvalue], dtype=ds.dtype))

    def pack(start: int) -> bytes | None:
        part = np.ascontiguousarray(data[start:start + step])
        if fill is not None and np.all(_bits(part) == fill):
            return None
        if part.shape != chunk_shape:
            full = np.zeros(chunk_shape, dtype=ds.dtype)
            full[:len(part)] = part
            part = full
        return _deflate_chunk(part.reshape((1,) * len(lead) + chunk_shape))

    starts = range(0, data.shape[0], step)
    rest = (0,) * (len(chunk_shape) - 1)
    if len(starts) == 1:  # one chunk: handing it to a thread costs more than it saves
        blobs = map(pack, starts)
    else:
        if _deflate_pool is None:
            _deflate_pool = ThreadPoolExecutor(max_workers=os.cpu_count() or 1,
                                               thread_name_prefix="chainrun-deflate")
        blobs = _deflate_pool.map(pack, starts)
    for start, blob in zip(starts, blobs):
        if blob is not None:
            ds.id.write_direct_chunk(lead + (start,) + rest, blob)


def _array(group: h5py.Group, name: str, data, scales: list[h5py.Dataset],
           long_name: str, dtype=None) -> h5py.Dataset:
    """A fixed-size dataset, chunked and compressed when large, with dims attached."""
    data = np.asarray(data, dtype=dtype)
    if data.size > COMPRESS_ABOVE and data.dtype.kind in "biufS":
        # one value throughout (a uniform line's masses): the fill value, stored nowhere
        bits = _bits(data)
        fill = data.reshape(-1)[0] if bits is not None and np.all(bits == bits[0]) else None
        ds = group.create_dataset(name, shape=data.shape, dtype=data.dtype,
                                  chunks=(min(data.shape[0], BALL_CHUNK),) + data.shape[1:],
                                  fillvalue=fill, **_GZIP)
        _write_deflated(ds, (), data)
    else:
        ds = group.create_dataset(name, data=data)
    for axis, scale in enumerate(scales):
        ds.dims[axis].attach_scale(scale)
    ds.attrs["long_name"] = long_name
    return ds


def _create(path: Path, temp: Path, what: str) -> h5py.File:
    if not path.parent.is_dir():
        raise StoreError(f"{path}: cannot create {what} (no folder {path.parent})")
    try:
        return h5py.File(temp, "w", libver=_LIBVER, track_order=True)
    except OSError as exc:
        found = re.search(r"error message = '([^']*)'", str(exc))
        reason = found.group(1) if found else str(exc).splitlines()[0]
        raise StoreError(f"{path}: cannot create {what} ({reason})") from exc


def _commit(h5: h5py.File, temp: Path, path: Path) -> None:
    """Flush and close ``h5``, fsync it and rename it over ``path``.

    Raises StoreError (one line) when the file cannot be completed or put in place
    (a full disk, a folder under the final name); the temporary file is removed.
    """
    try:
        h5.flush()
        h5.close()
        atomic.put_in_place(temp, path)
    except OSError as exc:
        try:
            temp.unlink()
        except OSError:
            pass
        reason = exc.strerror or str(exc)
        raise StoreError(f"{path}: cannot write ({reason})") from None


def _discard(h5: h5py.File | None, temp: Path) -> None:
    if h5 is not None:
        try:
            h5.close()
        except Exception:  # already closed or broken: removing the file is what matters
            pass
    try:
        os.unlink(temp)
    except FileNotFoundError:
        pass


def _stamp(h5: h5py.File, fmt: str) -> None:
    h5.attrs["format"] = fmt
    h5.attrs["format_version"] = np.int64(_FORMAT_VERSIONS[fmt])
    h5.attrs["created"] = _now()


# ------------------------------------------------------------------ format checking


def check_format(path_or_h5file, expected: str = RUN_FORMAT) -> int:
    """Check that a file is a chainrun file of the expected format and a known version.

    Parameters
    ----------
    path_or_h5file : str, path or h5py.File
    expected : {"chainrun-run", "chainrun-index"}

    Returns
    -------
    int
        The file's format version.

    Raises
    ------
    StoreError
        With a one-line message naming the file: missing, truncated or not HDF5, of
        another format, or of an unsupported format version.
    """
    if expected not in _FORMAT_VERSIONS:
        raise ValueError(f"unknown chainrun format {expected!r}")
    if isinstance(path_or_h5file, (h5py.File, h5py.Group)):
        return _check_open(path_or_h5file.file, path_or_h5file.file.filename, expected)
    name = os.fspath(path_or_h5file)
    with _open_read(name) as h5:
        return _check_open(h5, name, expected)


def _open_read(name: str) -> h5py.File:
    if not os.path.exists(name):
        raise StoreError(f"{name}: no such file")
    if os.path.isdir(name):
        raise StoreError(f"{name}: is a folder, not a file")
    try:
        return h5py.File(name, "r")
    except OSError as exc:
        if not os.access(name, os.R_OK):
            raise StoreError(f"{name}: cannot read (permission denied)") from exc
        if os.path.splitext(name)[1].lower() in (".toml", ".yaml", ".yml"):
            raise StoreError(f"{name}: an experiment file, not a run file (run `chainrun "
                             f"simulate {name}` to make its runs)") from exc
        raise StoreError(f"{name}: truncated or not HDF5") from exc


def _h5_reason(exc: BaseException) -> str:
    """One line for an h5py error: HDF5's own reason, without its stack."""
    raw = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc  # KeyError quotes
    text = " ".join(str(raw).split()) or type(exc).__name__
    found = re.search(r"\(([^()]*)\)\s*$", text)  # "Unable to ... (the reason)"
    return found.group(1) if found and text.startswith(("Unable", "Can't", "Error")) else text


def _check_open(h5: h5py.File, name: str, expected: str) -> int:
    noun = expected.removeprefix("chainrun-")
    try:
        fmt = h5.attrs.get("format")
        raw_version = h5.attrs.get("format_version")
    except (KeyError, OSError, RuntimeError) as exc:  # a damaged object header
        raise StoreError(f"{name}: damaged HDF5 file ({_h5_reason(exc)})") from None
    if fmt is None:
        raise StoreError(f"{name}: not a chainrun {noun} file (no format attribute)")
    try:
        fmt = _as_str(fmt)
    except UnicodeDecodeError:
        raise StoreError(f"{name}: not a chainrun {noun} file (format is not text)") from None
    if fmt != expected:
        raise StoreError(f"{name}: not a chainrun {noun} file (format {fmt!r})")
    if isinstance(raw_version, np.ndarray) and raw_version.shape == ():
        raw_version = raw_version[()]
    if not isinstance(raw_version, (int, np.integer)) or isinstance(raw_version, (bool, np.bool_)):
        # absent, or not an integer: "1", 1.5 or [1] are not version 1
        raise StoreError(f"{name}: {fmt} file without a valid format_version")
    version = int(raw_version)
    readable = _READABLE[expected]
    if version not in readable:
        known = " or ".join(str(v) for v in readable)
        raise StoreError(
            f"{name}: format version {version} is not supported (expected {known})"
        )
    return version


# ----------------------------------------------------------------------- run files


class _Element:
    """An H5MD time-dependent element (``step``, ``time``, ``value``) that grows by rows."""

    def __init__(self, group: h5py.Group, name: str, item_shape: tuple[int, ...],
                 item_scales: list[h5py.Dataset], chunk_hint: int, long_name: str):
        self.group = g = _group(group, name)
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
            opts = dict(chunks=(1, min(item_shape[0], BALL_CHUNK)) + item_shape[1:], **_GZIP)
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
                _write_deflated(self.value, (row + i,), value)
        self.rows = row + m
        self.pending.clear()


class RunWriter:
    """Write one run file, snapshot by snapshot, then atomically put it in place.

    Use as a context manager. ``snapshot`` has the signature of the solver's
    ``on_snapshot`` hook; snapshots are written in blocks of up to
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
        The run; its parameters and config text are written at once.
    velocity_floor : float
        The solver's velocity floor (``chainrun.solver.velocity_floor(spec.rtol)``).

    Examples
    --------
    >>> with RunWriter("results/runs/k=2.h5", spec, velocity_floor=1e-12) as w:
    ...     sol = simulate(spec.n, spec.k, spec.alpha, spec.times, on_snapshot=w.snapshot)
    ...     w.finish(sol)
    """

    def __init__(self, path, spec: RunSpec, *, velocity_floor: float):
        self.path = Path(path)
        self.temp_path = atomic.temp_name(self.path)
        self._spec = spec
        self._n = int(spec.n)
        self._alpha = float(spec.alpha)
        self._units = getattr(spec, "units", "paper")
        # the paper's line keeps its observables' formulas, bit for bit
        self._line = None if spec.is_paper else spec.line
        self._pending_bytes = 0
        self._done = False
        self._h5: h5py.File | None = _create(self.path, self.temp_path, "run file")
        try:
            self._write_header(float(velocity_floor))
        except BaseException:
            self.abort()
            raise

    # -- layout ------------------------------------------------------------------

    def _write_header(self, velocity_floor: float) -> None:
        h5, spec, n = self._h5, self._spec, self._n
        _stamp(h5, RUN_FORMAT)

        meta = _group(h5, "h5md")
        meta.attrs["version"] = np.array(H5MD_VERSION, dtype=np.int32)
        _group(meta, "author").attrs["name"] = _fixed_str(_author())
        creator = _group(meta, "creator")
        creator.attrs["name"] = _fixed_str("chainrun")
        creator.attrs["version"] = _fixed_str(chainrun.__version__)

        params = _group(h5, "parameters")
        a = params.attrs
        a["n"] = np.int64(n)
        a["k"] = np.int64(spec.k)
        a["alpha"] = np.float64(spec.alpha)
        a["t_end"] = np.float64(np.nan if spec.t_end is None else spec.t_end)
        a["rtol"] = np.float64(spec.rtol)
        a["max_events"] = np.int64(-1 if spec.max_events is None else spec.max_events)
        a["velocity_floor"] = np.float64(velocity_floor)
        a["experiment"] = str(spec.experiment)
        a["run_id"] = str(spec.run_id)
        a["config_hash"] = str(spec.config_hash)
        a["config"] = str(spec.source_text)
        a["config_resolved"] = _to_json(spec.config)
        a["overrides"] = _to_json(spec.overrides)

        chain = _group(_group(h5, "particles"), "chain")
        box = _group(chain, "box")
        box.attrs["dimension"] = np.int32(1)
        box.attrs["boundary"] = np.array([b"none"], dtype=h5py.string_dtype("ascii", 4))
        ball = _scale(chain, "ball", np.arange(1, n + 1, dtype=np.int64),
                      "ball number n = 1..N (ball 1 is struck first)")
        spatial = _scale(chain, "spatial", np.array(["x"], dtype=h5py.string_dtype()),
                         "spatial axis")
        hint = len(np.atleast_1d(spec.times))
        self._position = _Element(chain, "position", (n, 1), [ball, spatial], hint,
                                  "displacement x_n from the initial touching position")
        self._velocity = _Element(chain, "velocity", (n, 1), [ball, spatial], hint,
                                  "velocity dx_n/dt")
        obs = _group(h5, "observables")
        general = self._line is not None
        self._observables = {
            "kinetic_energy": _Element(obs, "kinetic_energy", (), [], hint,
                                       "sum m v^2/2" if general else "sum v^2/2"),
            "potential_energy": _Element(
                obs, "potential_energy", (), [], hint,
                "sum kappa delta_+^(alpha+1)/(alpha+1) over contacts and walls, less sum f x"
                if general else "sum c_+^(alpha+1)/(alpha+1), c_j = x_j - x_j+1"),
            "momentum": _Element(obs, "momentum", (), [], hint,
                                 "sum m v" if general else "sum v"),
        }
        units = UNITS[self._units]
        for element, unit in ((self._position, "position"), (self._velocity, "velocity"),
                              (self._observables["kinetic_energy"], "energy"),
                              (self._observables["potential_energy"], "energy"),
                              (self._observables["momentum"], "momentum")):
            element.value.attrs["unit"] = units[unit]
            element.time.attrs["unit"] = units["time"]
        self._write_model(h5)

    def _write_model(self, h5: h5py.File) -> None:
        """``/model``: the line as solved, per ball and per contact, its walls, its
        units and the scales it was solved in."""
        from chainrun.solver import Line

        spec, units = self._spec, UNITS[self._units]
        line = self._line if self._line is not None else Line.paper(spec.n, spec.k, spec.alpha)
        model = _group(h5, "model")
        model.attrs["units"] = self._units
        ball = _scale(model, "ball", np.arange(1, line.n + 1, dtype=np.int64),
                      "ball number n = 1..N")
        contact = _scale(model, "contact", np.arange(1, line.n, dtype=np.int64),
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
            ds = _array(model, name, getattr(line, name), [scale], long_name)
            ds.attrs["unit"] = units[unit]
        if line.diameter is not None:
            _array(model, "diameter", line.diameter, [ball],
                   "diameter of each sphere").attrs["unit"] = units["diameter"]
        if line.material is not None:
            _array(model, "material", np.char.encode(line.material, "ascii"), [ball],
                   "material of each sphere (chainrun.materials; empty: constants given "
                   "explicitly)")
        if line.is_damped:
            eta = _array(model, "damping", line.damping, [contact],
                         "eta of F = max(0, kappa delta^alpha + eta delta^beta d(delta)/dt)")
            eta.attrs["unit"] = "SI (N s m^-(1+beta))" if self._units == "si" else "1"
            _array(model, "damping_exponent", line.damping_exponent, [contact],
                   "beta, the damping's exponent").attrs["unit"] = "1"
        walls = _group(model, "walls")
        for side, wall in (("left", line.left), ("right", line.right)):
            if wall is not None:
                g = _group(walls, side)
                g.attrs["stiffness"] = np.float64(wall.stiffness)
                g.attrs["alpha"] = np.float64(wall.alpha)
                g.attrs["gap"] = np.float64(wall.gap)
                if wall.damping:
                    g.attrs["damping"] = np.float64(wall.damping)
                    g.attrs["damping_exponent"] = np.float64(wall.damping_exponent)
                if wall.motion is not None:
                    _write_drive(_group(g, "motion"), wall.motion, units["position"],
                                 units["time"])
        if line.drives:
            drives = _group(model, "drives")
            for i, (ball, drive) in enumerate(line.drives):
                g = _group(drives, str(i))
                g.attrs["ball"] = np.int64(ball + 1)
                _write_drive(g, drive, units["force"], units["time"])
        scales = _group(model, "scales")
        sc = line.scales()
        for name in ("mass", "length", "time", "velocity", "force"):
            scales.attrs[name] = np.float64(getattr(sc, name))

    # -- writing -----------------------------------------------------------------

    def _live(self) -> h5py.File:
        if self._h5 is None:
            raise StoreError(f"{self.path}: run writer is closed")
        return self._h5

    def snapshot(self, index: int, t: float, x: np.ndarray, v: np.ndarray) -> None:
        """Write one snapshot now (``x``, ``v`` need only be valid during the call).

        Parameters
        ----------
        index : int
            Snapshot index (stored as H5MD ``step``).
        t : float
        x, v : ndarray, shape (N,)
            Displacements and velocities.
        """
        self._live()
        x = np.asarray(x, dtype=np.float64)
        v = np.asarray(v, dtype=np.float64)
        if x.shape != (self._n,) or v.shape != (self._n,):
            raise ValueError(
                f"snapshot arrays must have shape ({self._n},); got {x.shape} and {v.shape}"
            )
        if self._line is None:
            values = {
                "kinetic_energy": physics.kinetic_energy(v),
                "potential_energy": physics.potential_energy(x, self._alpha),
                "momentum": physics.momentum(v),
            }
        else:
            line = self._line
            values = {
                "kinetic_energy": physics.line_kinetic_energy(v, line.mass),
                "potential_energy": physics.line_potential_energy(x, line, t),
                "momentum": physics.line_momentum(v, line.mass),
            }
        for name, element in self._observables.items():
            element.append(index, t, values[name])
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
        self._pending_bytes = 0

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
            _commit(h5, self.temp_path, self.path)
        except BaseException:
            self._h5 = h5
            self.abort()
            raise
        self._done = True

    def _write_solution(self, h5: h5py.File, sol: Solution) -> None:
        n = self._n
        if int(sol.n) != n:
            raise StoreError(f"{self.path}: solution has n = {sol.n}, run spec n = {n}")
        results = _group(h5, "results")
        ball = _scale(results, "ball", np.arange(1, n + 1, dtype=np.int64),
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
            ds = _array(results, name, data, [ball], long_name)
            ds.attrs["unit"] = UNITS[self._units][name.split("_")[1]]
        wall = _scale(results, "wall", np.array(["left", "right"], dtype=h5py.string_dtype()),
                      "the wall at each end: left (before ball 1), right (after ball N)")
        self._write_dissipation(h5, results, sol, wall)
        ds = _array(results, "wall_impulse", np.asarray(sol.wall_impulse, dtype=np.float64),
                    [wall], "impulse each wall gave the line by end_time (+x towards ball "
                    "N; 0 where there is no wall)")
        ds.attrs["unit"] = UNITS[self._units]["momentum"]
        results.attrs["end_time"] = np.float64(sol.end_time)
        results.attrs["terminal"] = np.bool_(sol.terminal)
        results.attrs["outcome"] = str(getattr(sol.outcome, "value", sol.outcome))
        results.attrs["message"] = str(sol.message)

        events = _group(h5, "events")
        t = np.asarray(sol.event_time, dtype=np.float64).reshape(-1)
        contact = np.asarray(sol.event_contact, dtype=np.int64).reshape(-1)
        kind = np.asarray(sol.event_kind, dtype=np.int8).reshape(-1)
        if not (len(t) == len(contact) == len(kind)):
            raise StoreError(f"{self.path}: event arrays differ in length "
                             f"({len(t)}, {len(contact)}, {len(kind)})")
        event = _scale(events, "event", np.arange(len(t), dtype=np.int64),
                       "event number, in time order")
        _array(events, "time", t, [event], "time of the event").attrs["unit"] = \
            UNITS[self._units]["time"]
        # the solver's arrays count contacts from 0 (and the left wall as -1); the file
        # numbers them as it numbers balls: contact j joins balls j and j+1
        c = _array(events, "contact", contact + 1, [event],
                   "contact j joins balls j and j+1 (0: the left wall, N: the right wall)")
        c.attrs["base"] = np.int64(1)
        k = _array(events, "kind", kind, [event], "what happened to the contact")
        k.attrs["kinds"] = json.dumps({str(int(e)): e.name.lower() for e in EventKind})
        k.attrs["flag_values"] = np.array([int(e) for e in EventKind], dtype=np.int8)
        k.attrs["flag_meanings"] = " ".join(e.name.lower() for e in EventKind)

        diag = _group(h5, "diagnostics")
        for key, value in dataclasses.asdict(sol.diagnostics).items():
            diag.attrs[key] = value

        balls = np.asarray(sol.sensor_balls, dtype=np.int64).reshape(-1)
        if balls.size:
            sensors = _group(h5, "sensors")
            sample = _scale(sensors, "time", np.asarray(sol.sensor_time, dtype=np.float64),
                            "sample time: 0, dt, 2 dt, ... up to end_time")
            sensor = _scale(sensors, "ball", balls, "sensor ball number (1..N)")
            force = np.asarray(sol.sensor_force, dtype=np.float64)
            side = _scale(sensors, "side", np.array([0, 1], dtype=np.int64),
                          "0: the contact towards ball 1; 1: the contact away from it")
            _array(sensors, "force", force, [sample, sensor, side],
                   "contact force on each side of the sensor ball (0 at a line's end)")
            _array(sensors, "mean_force", force.mean(axis=2), [sample, sensor],
                   "mean of the two contact forces: what a sensor inside the ball measures")
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
            ds = _array(results, f"{name}_spread", data, [ball],
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
        contact = _scale(results, "contact", np.arange(1, n, dtype=np.int64),
                         "contact j = 1..N-1 joins balls j and j+1")
        per = np.asarray(sol.contact_dissipation, dtype=np.float64)
        ds = _array(results, "contact_dissipation", per if per.size else np.zeros(n - 1),
                    [contact], "energy each contact dissipated by end_time")
        ds.attrs["unit"] = energy
        ds = _array(results, "wall_dissipation",
                    np.asarray(sol.wall_dissipation, dtype=np.float64),
                    [wall], "energy each wall dissipated by end_time (0 where there is "
                    "no wall)")
        ds.attrs["unit"] = energy

    def abort(self) -> None:
        """Close and delete the temporary file; nothing is written under ``path``."""
        h5, self._h5 = self._h5, None
        _discard(h5, self.temp_path)

    def __enter__(self) -> "RunWriter":
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        if not self._done:
            self.abort()
        return False


def write_run(path, spec: RunSpec, solution: Solution, *, velocity_floor: float) -> None:
    """Write a whole run file from a ``Solution`` that kept its snapshots.

    Parameters
    ----------
    path : str or path
    spec : RunSpec
    solution : Solution
        With ``positions`` and ``velocities`` of shape (T, N), or None when T = 0.
    velocity_floor : float
    """
    times = np.asarray(solution.times, dtype=np.float64).reshape(-1)
    if len(times) and (solution.positions is None or solution.velocities is None):
        raise StoreError(f"{path}: the solution's snapshots were consumed by an observer; "
                         "write them with RunWriter.snapshot")
    with RunWriter(path, spec, velocity_floor=velocity_floor) as writer:
        for i, t in enumerate(times):
            writer.snapshot(i, float(t), solution.positions[i], solution.velocities[i])
        writer.finish(solution)


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
    """The contents of one run file.

    Attributes
    ----------
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
    times : ndarray, shape (T,)
    steps : ndarray of int64, shape (T,)
        Snapshot indices.
    positions, velocities : Snapshots, shape (T, N)
        Read lazily; ``np.asarray`` loads all.
    observables : dict of ndarray, shape (T,)
        ``kinetic_energy``, ``potential_energy``, ``momentum``,
        ``dissipated_energy`` (the energy the damping took by then; 0 on an elastic
        line) and ``drive_work`` (the work the drives did by then; 0 on a line without
        them) at each snapshot.
    final_position, final_velocity, separation_time, separation_velocity : ndarray, shape (N,)
    event_time : ndarray, shape (E,)
    event_contact : ndarray of int64, shape (E,)
        Contact j joins balls j and j+1 (1..N-1; 0 is the left wall, N the right).
    event_kind : ndarray of int8, shape (E,)
        ``chainrun.solver.EventKind`` values.
    outcome : str
        ``chainrun.solver.Outcome`` value, e.g. ``"terminal"``.
    message : str
    end_time : float
    terminal : bool
    diagnostics : dict
        The fields of ``chainrun.solver.Diagnostics``.
    model : dict or None
        The line as solved (``/model``): ``units``; per ball ``mass``, ``velocity``,
        ``position``, ``force`` (shape (N,)); per contact ``stiffness``, ``alpha``,
        ``gap``, ``damping``, ``damping_exponent`` (shape (N-1,)); for real spheres
        ``diameter`` and ``material`` (shape (N,); None otherwise); ``walls``
        ({"left"/"right": {"stiffness", "alpha", "gap", "damping",
        "damping_exponent", "motion"}}, the walls present; a moving wall's ``motion`` a
        ``chainrun.solver.Drive``), ``drives`` (``(ball, Drive)`` pairs, balls from 0)
        and ``scales`` (mass, length, time, velocity,
        force: the paper's units of this line, in its units). None for files written
        before the model was recorded: those hold the paper's line.
    sensor_balls : ndarray of int64, shape (S,)
        Force sensor balls (1..N); empty without sensors.
    sensor_time : ndarray, shape (M,)
    sensor_force : ndarray, shape (M, S, 2)
        Contact forces on each side of each sensor ball at each sample time.
    dissipated_energy : float
        The energy the damping dissipated by ``end_time`` (0 for an elastic line).
    contact_dissipation : ndarray, shape (N-1,)
        The same by each contact.
    wall_dissipation : ndarray, shape (2,)
        The same by the left and right walls.
    wall_impulse : ndarray, shape (2,)
        The impulse the left and right walls gave the line by ``end_time`` (+x towards
        ball N; 0 where there is no wall).
    check : chainrun.check.Check or None
        The conditioning check (``solver.check``, ``--check``): the check run's
        tolerance, outcome and time, and the spread of each ball's final and separation
        velocity; None for a run without one.
    drive_work : float
        The work the drives did by ``end_time`` (0 on a line without them).
    """

    path: Path
    format_version: int
    created: str
    creator_version: str
    parameters: dict[str, Any]
    times: np.ndarray
    steps: np.ndarray
    positions: Snapshots
    velocities: Snapshots
    observables: dict[str, np.ndarray]
    final_position: np.ndarray
    final_velocity: np.ndarray
    separation_time: np.ndarray
    separation_velocity: np.ndarray
    event_time: np.ndarray
    event_contact: np.ndarray
    event_kind: np.ndarray
    outcome: str
    message: str
    end_time: float
    terminal: bool
    diagnostics: dict[str, Any]
    sensor_balls: np.ndarray = dataclasses.field(
        default_factory=lambda: np.zeros(0, np.int64))
    sensor_time: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    sensor_force: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((0, 0, 2)))
    model: dict[str, Any] | None = None
    dissipated_energy: float = 0.0
    contact_dissipation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    wall_dissipation: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    wall_impulse: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    check: Check | None = None
    drive_work: float = 0.0

    @property
    def n(self) -> int:
        return self.parameters["n"]

    @functools.cached_property
    def line(self) -> Line:
        """The line as solved (``chainrun.solver.Line``), rebuilt from ``model``: the
        paper's line of N, K and alpha in a file without one."""
        model = self.model
        if model is None:
            return Line.paper(self.n, self.k, self.alpha)
        walls = {side: Wall(**wall) for side, wall in model["walls"].items()}
        return Line(**{key: model[key] for key in (
            "mass", "stiffness", "alpha", "gap", "velocity", "force", "position",
            "damping", "damping_exponent", "diameter", "material", "drives")}, **walls)

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

    @property
    def k(self) -> int:
        return self.parameters["k"]

    @property
    def alpha(self) -> float:
        return self.parameters["alpha"]


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
    with _open_read(name) as h5:
        version = _check_open(h5, name, RUN_FORMAT)
        try:
            _get(h5, "particles/chain/velocity/value")  # read lazily: check it is there
            return _read_run(h5, Path(name), version)
        except KeyError as exc:
            reason = exc.args[0] if exc.args else ""
            if isinstance(reason, str) and reason.startswith("Unable"):  # from h5py
                raise StoreError(f"{name}: damaged run file ({_h5_reason(exc)})") from None
            raise StoreError(f"{name}: damaged run file (missing {reason})") from None
        except (OSError, RuntimeError, ValueError, TypeError, OverflowError) as exc:
            # HDF5 checksum and decoding errors, bad UTF-8 or JSON, "soon" as a time
            raise StoreError(f"{name}: damaged run file ({_h5_reason(exc)})") from None


def _get(h5: h5py.File, item: str):
    if item not in h5:
        raise KeyError(item)
    return h5[item]


def _attr(obj, key: str):
    if key not in obj.attrs:
        raise KeyError(f"{obj.name}@{key}")
    return obj.attrs[key]


def _read_run(h5: h5py.File, path: Path, version: int) -> RunData:
    p = _get(h5, "parameters")
    params = {key: _py(value) for key, value in p.attrs.items()}
    for key in ("n", "k", "alpha"):
        _attr(p, key)
    if isinstance(params.get("t_end"), float) and np.isnan(params["t_end"]):
        params["t_end"] = None
    if params.get("max_events") == -1:
        params["max_events"] = None
    for key in ("config_resolved", "overrides"):
        if key in params:
            params[key] = json.loads(params[key])

    pos = _get(h5, "particles/chain/position")
    times = _get(pos, "time")[()]
    steps = _get(pos, "step")[()]
    shape = _get(pos, "value").shape[:2]
    observables = {name: _get(h5, f"observables/{name}/value")[()] for name in OBSERVABLES}
    # every line's since version 2; a damped line's only before
    observables["dissipated_energy"] = (
        _get(h5, "observables/dissipated_energy/value")[()]
        if "dissipated_energy" in h5["observables"] else np.zeros(times.shape))
    # written since drives exist: none before
    observables["drive_work"] = (
        _get(h5, "observables/drive_work/value")[()]
        if "drive_work" in h5["observables"] else np.zeros(times.shape))
    res = _get(h5, "results")
    ev = _get(h5, "events")
    diag = _get(h5, "diagnostics")
    return RunData(
        path=path,
        format_version=version,
        created=_as_str(h5.attrs.get("created", "")),
        creator_version=_as_str(_attr(_get(h5, "h5md/creator"), "version")),
        parameters=params,
        times=times,
        steps=steps,
        positions=Snapshots(path, "particles/chain/position/value", shape),
        velocities=Snapshots(path, "particles/chain/velocity/value", shape),
        observables=observables,
        final_position=_get(res, "final_position")[()],
        final_velocity=_get(res, "final_velocity")[()],
        separation_time=_get(res, "separation_time")[()],
        separation_velocity=_get(res, "separation_velocity")[()],
        event_time=_get(ev, "time")[()],
        event_contact=_get(ev, "contact")[()] + (1 if version == 1 else 0),
        event_kind=_get(ev, "kind")[()],
        outcome=_as_str(_attr(res, "outcome")),
        message=_as_str(_attr(res, "message")),
        end_time=float(_attr(res, "end_time")),
        terminal=bool(_attr(res, "terminal")),
        diagnostics={key: _py(value) for key, value in diag.attrs.items()},
        model=_read_model(h5),
        check=_read_check(res, diag),
        drive_work=float(res.attrs.get("drive_work", 0.0)),
        **_read_sensors(h5),
        **_read_walls(res, int(params["n"]), version),
    )


def _read_walls(res: h5py.Group, n: int, version: int) -> dict:
    """What the damping dissipated, by contact and wall, and the walls' impulses (in a
    version 1 file, attributes present only where there was a wall or damping)."""
    if version >= 2:
        return dict(dissipated_energy=float(_attr(res, "dissipated_energy")),
                    contact_dissipation=_get(res, "contact_dissipation")[()],
                    wall_dissipation=_get(res, "wall_dissipation")[()],
                    wall_impulse=_get(res, "wall_impulse")[()])
    sides = ("left", "right")
    return dict(
        dissipated_energy=float(res.attrs.get("dissipated_energy", 0.0)),
        contact_dissipation=(_get(res, "contact_dissipation")[()]
                             if "contact_dissipation" in res else np.zeros(max(n - 1, 0))),
        wall_dissipation=np.array([float(res.attrs.get(f"{s}_wall_dissipation", 0.0))
                                   for s in sides]),
        wall_impulse=np.array([float(res.attrs.get(f"{s}_wall_impulse", 0.0)) for s in sides]))


def _read_model(h5: h5py.File) -> dict[str, Any] | None:
    """The ``/model`` group as a dict (None in files written before it existed)."""
    if "model" not in h5:
        return None
    group = h5["model"]
    model: dict[str, Any] = {"units": _as_str(_attr(group, "units"))}
    for name in ("mass", "velocity", "position", "force", "stiffness", "alpha", "gap"):
        model[name] = _get(group, name)[()]
    walls = _get(group, "walls")
    for name in ("damping", "damping_exponent"):  # a damped line's
        n_contacts = model["stiffness"].shape[0]
        model[name] = _get(group, name)[()] if name in group else np.zeros(n_contacts)
    model["diameter"] = _get(group, "diameter")[()] if "diameter" in group else None
    model["material"] = (np.char.decode(_get(group, "material")[()], "ascii")
                         if "material" in group else None)
    model["walls"] = {side: {key: float(walls[side].attrs.get(key, 0.0))
                             for key in ("stiffness", "alpha", "gap", "damping",
                                         "damping_exponent")}
                      for side in ("left", "right") if side in walls}
    for side, wall in model["walls"].items():
        g = walls[side]
        wall["motion"] = _read_drive(g["motion"]) if "motion" in g else None
    drives = group["drives"] if "drives" in group else {}
    model["drives"] = tuple((int(_attr(drives[key], "ball")) - 1, _read_drive(drives[key]))
                            for key in sorted(drives, key=int))
    model["scales"] = {key: float(value) for key, value in _get(group, "scales").attrs.items()}
    return model


def _read_check(res: h5py.Group, diag: h5py.Group) -> Check | None:
    """The conditioning check, if the run had one (optional datasets of ``results``)."""
    if "final_velocity_spread" not in res:
        return None
    return Check(rtol=float(_attr(res, "check_rtol")),
                 outcome=_as_str(_attr(res, "check_outcome")),
                 message=_as_str(res.attrs.get("check_message", "")),
                 wall_time=float(diag.attrs.get("check_wall_time", np.nan)),
                 final_velocity_spread=_get(res, "final_velocity_spread")[()],
                 separation_velocity_spread=_get(res, "separation_velocity_spread")[()])
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


def _read_drive(group: h5py.Group) -> Drive:
    if _as_str(_attr(group, "kind")) == "samples":
        return Drive.from_samples(_get(group, "time")[()], _get(group, "value")[()])
    return Drive.of_sines([dict(amplitude=float(a), frequency=float(f), ramp=float(r))
                           for a, f, r in zip(_get(group, "amplitude")[()],
                                              _get(group, "frequency")[()],
                                              _get(group, "ramp")[()])])


def _read_sensors(h5: h5py.File) -> dict:
    """The force sensors' samples, if the run had sensors (an optional group)."""
    if "sensors" not in h5:
        return {}
    group = h5["sensors"]
    return dict(sensor_balls=_get(group, "ball")[()], sensor_time=_get(group, "time")[()],
                sensor_force=_get(group, "force")[()])


# --------------------------------------------------------------------- index files


def _column(values: list, kind: str, name: str, path) -> np.ndarray:
    if kind == "str":
        return np.array([str(v) for v in values], dtype=h5py.string_dtype())
    if kind == "bool":
        return np.array([bool(v) for v in values], dtype=np.bool_)
    if kind == "int":
        try:
            return np.array([int(v) for v in values], dtype=np.int64)
        except (TypeError, ValueError):
            raise StoreError(f"{path}: index column {name!r} needs integers") from None
    return np.array([np.nan if v is None else float(v) for v in values], dtype=np.float64)


def _kind_of(values: Iterable) -> str:
    kinds = set()
    for v in values:
        if isinstance(v, (bool, np.bool_)):
            kinds.add("bool")
        elif isinstance(v, (int, np.integer)):
            kinds.add("int")
        elif isinstance(v, (float, np.floating)) or v is None:
            kinds.add("float")
        else:
            kinds.add("str")
    if kinds <= {"int", "float"} and "float" in kinds:
        return "float"
    return kinds.pop() if len(kinds) == 1 else "str"


def write_index(path, experiment: str, entries: list[dict]) -> None:
    """Write an experiment's index file atomically: a table of runs and links to them.

    Parameters
    ----------
    path : str or path
    experiment : str
    entries : list of dict
        One per run, with at least the keys of ``INDEX_COLUMNS`` (``run_id``,
        ``file`` -- the run file's name relative to the index file's folder --, ``n``,
        ``k``, ``alpha``, ``outcome``, ``terminal``, ``end_time``, ``events``,
        ``wall_time``, ``config_hash``). Further keys present in every entry with
        scalar values become further columns.
    """
    path = Path(path)
    entries = list(entries)
    missing = sorted({c for e in entries for c in INDEX_COLUMNS if c not in e})
    if missing:
        raise StoreError(f"{path}: index entries lack {', '.join(missing)}")
    ids = [str(e["run_id"]) for e in entries]
    for run_id in ids:
        if not run_id or "/" in run_id or run_id in (".", ".."):
            raise StoreError(f"{path}: run_id {run_id!r} cannot name an HDF5 link")
    if len(set(ids)) != len(ids):
        raise StoreError(f"{path}: run_id values are not unique")
    kinds = dict(INDEX_COLUMNS)
    for key in entries[0] if entries else ():
        if key not in kinds and all(key in e for e in entries):
            kinds[key] = _kind_of(e[key] for e in entries)

    temp = atomic.temp_name(path)
    h5 = _create(path, temp, "index file")
    try:
        _stamp(h5, INDEX_FORMAT)
        h5.attrs["experiment"] = str(experiment)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        table = _group(h5, "table")
        run = _scale(table, "run", np.arange(len(entries), dtype=np.int64), "row number")
        for name, kind in kinds.items():
            data = _column([e[name] for e in entries], kind, name, path)
            ds = table.create_dataset(name, data=data)
            ds.dims[0].attach_scale(run)
        table.attrs["columns"] = json.dumps(list(kinds))
        runs = _group(h5, "runs")
        for entry in entries:
            runs[str(entry["run_id"])] = h5py.ExternalLink(os.fspath(entry["file"]), "/")
        _commit(h5, temp, path)
    except BaseException:
        _discard(h5, temp)
        raise


def read_index(path) -> list[dict]:
    """Read the table of an index file: one dict per run, in the order written."""
    name = os.fspath(path)
    with _open_read(name) as h5:
        _check_open(h5, name, INDEX_FORMAT)
        try:
            table = _get(h5, "table")
            columns = json.loads(_as_str(_attr(table, "columns")))
            data = {c: _get(table, c)[()] for c in columns}
        except KeyError as exc:
            raise StoreError(f"{name}: damaged index file (missing {exc.args[0]})") from None
        except (OSError, ValueError) as exc:
            raise StoreError(f"{name}: damaged index file ({exc})") from None
    rows = len(data[columns[0]]) if columns else 0
    return [{c: _py(data[c][i]) for c in columns} for i in range(rows)]


# ------------------------------------------------------------ resuming sweeps
# (owned by the runner's resumption; kept apart so it can be edited on its own)

__all__ += ["run_config_hash"]


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
            _check_open(h5, name, RUN_FORMAT)
            if "results" not in h5 or "diagnostics" not in h5:
                return None
            value = h5["parameters"].attrs["config_hash"]
        return _as_str(value) or None
    except Exception:  # any reason the file cannot be read means: no trusted hash
        return None


# -------------------------------------------------------------------- analysis files
#
# An *analysis file* holds what ``chainrun analyze`` derives for one artefact of the
# paper (a figure, a table or a set of printed numbers): named scalar values, the arrays
# a figure draws, the settings that produced them, and the sha256 of every run or
# analysis file read. ``chainrun plot`` reads nothing else. The tree is drawn in
# ``docs/schema.md``.

ANALYSIS_FORMAT = "chainrun-analysis"
ANALYSIS_FORMAT_VERSION = 1
_FORMAT_VERSIONS[ANALYSIS_FORMAT] = ANALYSIS_FORMAT_VERSION
_READABLE[ANALYSIS_FORMAT] = (ANALYSIS_FORMAT_VERSION,)

#: Columns of an analysis file's ``/inputs`` table, in order.
ANALYSIS_INPUT_COLUMNS = ("kind", "name", "file", "sha256")

__all__ += ["ANALYSIS_FORMAT", "ANALYSIS_FORMAT_VERSION", "AnalysisData", "file_sha256",
            "read_analysis", "write_analysis"]


def file_sha256(path) -> str:
    """The sha256 of a file's bytes, as 64 hex digits."""
    import hashlib

    digest = hashlib.sha256()
    try:
        with open(path, "rb") as handle:
            for block in iter(lambda: handle.read(1 << 20), b""):
                digest.update(block)
    except OSError as exc:
        raise StoreError(f"{os.fspath(path)}: cannot read ({exc.strerror})") from None
    return digest.hexdigest()


@dataclass(frozen=True, eq=False)
class AnalysisData:
    """The contents of one analysis file.

    Attributes
    ----------
    name : str
        The artefact (``chainrun.artefacts``), e.g. ``"fig05"``.
    title : str
    values : dict of str to float
        Named derived numbers, e.g. ``{"ejected_1": 0.98568}`` (NaN allowed).
    descriptions : dict of str to str
        One line per value: what it is and how it was computed.
    spreads : dict of str to float
        Each value's spread, ``|value - the same value from the check runs|`` (the
        runs again at ``chainrun.check.check_rtol``; ``chainrun analyze --check``):
        empty for an analysis without a check; 0 where both are NaN or equal.
    arrays : dict of str to ndarray
        Arrays by slash-separated path, e.g. ``"series/t=13.5/x"``; numeric or str.
    attrs : dict of str to dict
        Attributes of the groups holding the arrays, by path (``"series/t=13.5"``):
        str, int, float or bool values such as a legend label.
    settings : dict
        The parameters of the analysis (fit ranges, thresholds), JSON-compatible.
    inputs : list of dict
        Every file read: ``kind`` ("run" or "analysis"), ``name`` (e.g.
        ``"fig07/n=100"``), ``file`` (its path as read) and ``sha256``.
    path : Path or None
        Where it was read from (None before writing).
    format_version : int
    created : str
        ISO 8601 time of writing ("" before writing).
    creator_version : str
    """

    name: str
    title: str
    values: dict[str, float]
    descriptions: dict[str, str]
    arrays: dict[str, np.ndarray]
    attrs: dict[str, dict[str, Any]]
    settings: dict[str, Any]
    inputs: list[dict[str, str]]
    path: Path | None = None
    format_version: int = ANALYSIS_FORMAT_VERSION
    created: str = ""
    creator_version: str = ""
    spreads: dict[str, float] = dataclasses.field(default_factory=dict)

    def children(self, group: str) -> list[str]:
        """Names of the sub-groups of ``group`` (e.g. the series), in the order written."""
        prefix = group.rstrip("/") + "/"
        names: dict[str, None] = {}
        for key in list(self.arrays) + list(self.attrs):
            if key.startswith(prefix):
                rest = key[len(prefix):]
                if "/" in rest:
                    names.setdefault(rest.split("/", 1)[0], None)
        return list(names)


def _check_key(path: Path, key: str) -> None:
    parts = key.split("/")
    if not key or any(p in ("", ".", "..") for p in parts):
        raise StoreError(f"{path}: {key!r} cannot name an HDF5 object")


def _ensure_group(root: h5py.Group, key: str) -> h5py.Group:
    group = root
    for part in [p for p in key.split("/") if p]:
        group = group[part] if part in group else _group(group, part)
    return group


def write_analysis(path, data: AnalysisData) -> None:
    """Write an analysis file atomically (a temporary name, then a rename).

    Parameters
    ----------
    path : str or path
    data : AnalysisData
        ``path``, ``format_version``, ``created`` and ``creator_version`` are ignored:
        the file records this chainrun and the time of writing.
    """
    path = Path(path)
    for key in list(data.arrays) + list(data.attrs):
        _check_key(path, key)
    for key in data.values:
        _check_key(path, key)
        if "/" in key:
            raise StoreError(f"{path}: value name {key!r} contains '/'")
    missing = [c for row in data.inputs for c in ANALYSIS_INPUT_COLUMNS if c not in row]
    if missing:
        raise StoreError(f"{path}: inputs lack {', '.join(sorted(set(missing)))}")

    temp = atomic.temp_name(path)
    h5 = _create(path, temp, "analysis file")
    try:
        _stamp(h5, ANALYSIS_FORMAT)
        h5.attrs["artefact"] = str(data.name)
        h5.attrs["title"] = str(data.title)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        h5.attrs["settings"] = _to_json(data.settings)

        values = _group(h5, "values")
        for key, value in data.values.items():
            ds = values.create_dataset(key, data=np.float64(value))
            ds.attrs["description"] = str(data.descriptions.get(key, ""))
            if key in data.spreads:
                ds.attrs["spread"] = np.float64(data.spreads[key])

        arrays = _group(h5, "data")
        for key in dict.fromkeys(list(data.attrs) + [k.rsplit("/", 1)[0] for k in data.arrays
                                                      if "/" in k]):
            _ensure_group(arrays, key)
        for key, value in data.arrays.items():
            parent, _, leaf = key.rpartition("/")
            group = _ensure_group(arrays, parent)
            value = np.asarray(value)
            if value.dtype.kind in "US":
                ds = group.create_dataset(leaf, data=value.astype(object),
                                          dtype=h5py.string_dtype())
            else:
                ds = group.create_dataset(leaf, data=value)
        for key, attributes in data.attrs.items():
            group = _ensure_group(arrays, key)
            for name, value in attributes.items():
                if not isinstance(value, (str, bool, int, float, np.generic)):
                    raise StoreError(f"{path}: attribute {key}@{name} is not a scalar")
                group.attrs[name] = value

        inputs = _group(h5, "inputs")
        for column in ANALYSIS_INPUT_COLUMNS:
            inputs.create_dataset(column, data=np.array([str(r[column]) for r in data.inputs],
                                                        dtype=object),
                                  dtype=h5py.string_dtype())
        _commit(h5, temp, path)
    except BaseException:
        _discard(h5, temp)
        raise


def read_analysis(path) -> AnalysisData:
    """Read an analysis file after checking its format and version.

    Raises
    ------
    StoreError
        If the file is missing, not a chainrun analysis file, of another format
        version, or damaged.
    """
    name = os.fspath(path)
    with _open_read(name) as h5:
        version = _check_open(h5, name, ANALYSIS_FORMAT)
        try:
            values: dict[str, float] = {}
            descriptions: dict[str, str] = {}
            spreads: dict[str, float] = {}
            for key, ds in _get(h5, "values").items():
                values[key] = float(ds[()])
                descriptions[key] = _as_str(ds.attrs.get("description", ""))
                if "spread" in ds.attrs:
                    spreads[key] = float(ds.attrs["spread"])
            arrays: dict[str, np.ndarray] = {}
            attrs: dict[str, dict[str, Any]] = {}

            def visit(group: h5py.Group, prefix: str) -> None:
                if prefix and len(group.attrs):
                    attrs[prefix] = {k: _py(v) for k, v in group.attrs.items()}
                for key, item in group.items():
                    full = f"{prefix}/{key}" if prefix else key
                    if isinstance(item, h5py.Group):
                        visit(item, full)
                    elif h5py.check_string_dtype(item.dtype) is not None:
                        arrays[full] = np.array(item.asstr()[()], dtype=str)
                    else:
                        arrays[full] = item[()]

            visit(_get(h5, "data"), "")
            table = _get(h5, "inputs")
            columns = {c: _get(table, c).asstr()[()] for c in ANALYSIS_INPUT_COLUMNS}
            rows = len(columns["kind"])
            inputs = [{c: str(columns[c][i]) for c in ANALYSIS_INPUT_COLUMNS}
                      for i in range(rows)]
            return AnalysisData(
                name=_as_str(_attr(h5, "artefact")),
                title=_as_str(h5.attrs.get("title", "")),
                values=values,
                descriptions=descriptions,
                arrays=arrays,
                attrs=attrs,
                settings=json.loads(_as_str(_attr(h5, "settings"))),
                inputs=inputs,
                path=Path(name),
                format_version=version,
                created=_as_str(h5.attrs.get("created", "")),
                creator_version=_as_str(h5.attrs.get("creator_version", "")),
                spreads=spreads,
            )
        except KeyError as exc:
            raise StoreError(f"{name}: damaged analysis file (missing {exc.args[0]})") from None


# -------------------------------------------------------------------- spectrum files
#
# A *spectrum file* holds the linear spectrum of one run's line at rest
# (``chainrun.analysis.spectrum``): an xarray Dataset written as a flat netCDF-4 file,
# every coordinate a dimension scale, so ``xarray.open_dataset(path, engine="h5netcdf")``
# reads it as well as ``read_spectrum``. The tree is drawn in ``docs/schema.md``.

SPECTRUM_FORMAT = "chainrun-spectrum"
SPECTRUM_FORMAT_VERSION = 1
_FORMAT_VERSIONS[SPECTRUM_FORMAT] = SPECTRUM_FORMAT_VERSION
_READABLE[SPECTRUM_FORMAT] = (SPECTRUM_FORMAT_VERSION,)
#: Attributes h5py keeps for dimension scales, not the Dataset's.
_SCALE_ATTRS = ("CLASS", "NAME", "REFERENCE_LIST", "DIMENSION_LIST", "_Netcdf4Dimid")

__all__ += ["SPECTRUM_FORMAT", "SPECTRUM_FORMAT_VERSION", "read_spectrum", "write_spectrum"]


def _attribute(path: Path, where: str, value: Any) -> Any:
    """An attribute value HDF5 holds as it is: a str, int, float or bool scalar."""
    if isinstance(value, (np.generic,)):
        value = value.item()
    if not isinstance(value, (str, bool, int, float)):
        raise StoreError(f"{path}: attribute {where} is not a str, int, float or bool")
    return value


def write_spectrum(path, ds) -> None:
    """Write the spectrum Dataset ``ds`` (``chainrun.analysis.spectrum.line_spectrum``)
    atomically (a temporary name, then a rename).

    Each coordinate becomes a dimension scale and each data variable a dataset with its
    dimensions attached; the Dataset's attributes are the file's root attributes, beside
    ``format``, ``format_version``, ``created`` and the creator's name and version.
    """
    path = Path(path)
    temp = atomic.temp_name(path)
    h5 = _create(path, temp, "spectrum file")
    try:
        _stamp(h5, SPECTRUM_FORMAT)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        for key, value in ds.attrs.items():
            h5.attrs[key] = _attribute(path, f"@{key}", value)
        scales = {}
        for name in ds.dims:
            coord = ds[name]
            scales[name] = _scale(h5, name, coord.values, coord.attrs.get("long_name", name))
            for key, value in coord.attrs.items():
                scales[name].attrs[key] = _attribute(path, f"{name}@{key}", value)
        for name, var in ds.data_vars.items():
            dset = _array(h5, str(name), var.values, [scales[d] for d in var.dims],
                          var.attrs.get("long_name", str(name)))
            for key, value in var.attrs.items():
                dset.attrs[key] = _attribute(path, f"{name}@{key}", value)
        _commit(h5, temp, path)
    except BaseException:
        _discard(h5, temp)
        raise


def read_spectrum(path):
    """The spectrum file at ``path`` as an ``xarray.Dataset``, after checking its format.

    Raises
    ------
    StoreError
        If the file is missing, not a chainrun spectrum file, of another format version,
        or damaged.
    """
    import xarray as xr

    name = os.fspath(path)
    with _open_read(name) as h5:
        _check_open(h5, name, SPECTRUM_FORMAT)
        try:
            coords, data = {}, {}
            for key, item in h5.items():
                attrs = {k: _py(v) for k, v in item.attrs.items() if k not in _SCALE_ATTRS}
                if item.is_scale:
                    coords[key] = (key, item[()], attrs)
                else:
                    dims = tuple(item.dims[i][0].name.lstrip("/") for i in range(item.ndim))
                    data[key] = (dims, item[()], attrs)
            attrs = {k: _py(v) for k, v in h5.attrs.items()}
        except (KeyError, OSError, RuntimeError, IndexError) as exc:
            raise StoreError(f"{name}: damaged spectrum file ({_h5_reason(exc)})") from None
    return xr.Dataset(data, coords=coords, attrs=attrs)
