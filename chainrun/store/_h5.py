"""What every chainrun file shares: format stamps, atomic creation, and HDF5 helpers.

Each file chainrun writes names its format and version in root attributes
(``format``, ``format_version``, ``created``); ``check_format`` reads them first and
refuses, in one line, a file it cannot read. Files are created under a temporary name
beside the target and renamed over it only when complete (``chainrun.atomic``), so a
reader never sees a half-written file under the final name. Datasets carry netCDF-4
dimension scales and a ``long_name``; large ones are chunked and compressed.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import re
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from chainrun import atomic
from chainrun.errors import StoreError

#: Format name and version of a run file (root attributes ``format``, ``format_version``).
RUN_FORMAT = "chainrun-run"
RUN_FORMAT_VERSION = 2
#: Format name and version of an experiment's index file.
INDEX_FORMAT = "chainrun-index"
INDEX_FORMAT_VERSION = 1
#: Format name and version of an analysis file.
ANALYSIS_FORMAT = "chainrun-analysis"
ANALYSIS_FORMAT_VERSION = 1
#: Format name and version of a spectrum file.
SPECTRUM_FORMAT = "chainrun-spectrum"
SPECTRUM_FORMAT_VERSION = 1

_FORMAT_VERSIONS = {RUN_FORMAT: RUN_FORMAT_VERSION, INDEX_FORMAT: INDEX_FORMAT_VERSION,
                    ANALYSIS_FORMAT: ANALYSIS_FORMAT_VERSION,
                    SPECTRUM_FORMAT: SPECTRUM_FORMAT_VERSION}
#: The versions each format is still read in: a run file of version 1 numbers its event
#: log's contacts from 0 and keeps the walls' impulses and dissipation as attributes.
_READABLE = {RUN_FORMAT: (1, 2), INDEX_FORMAT: (1,), ANALYSIS_FORMAT: (1,),
             SPECTRUM_FORMAT: (1,)}

#: Chunk length along the first axis of large arrays (2**16 float64 = 512 KiB).
BALL_CHUNK = 2**16
#: Arrays with more elements than this are chunked and compressed.
COMPRESS_ABOVE = 4096
#: HDF5's own filters: shuffle, then deflate at level 1 (any HDF5 reader decodes them).
GZIP = dict(compression="gzip", compression_opts=1, shuffle=True)

# HDF5 1.8 object headers: large attributes (the config text) go to dense storage.
_LIBVER = "v108"


# ------------------------------------------------------------------ values and text


def now() -> str:
    return _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds")


def fixed_str(value: str) -> np.ndarray:
    """A scalar fixed-length UTF-8 string, as H5MD asks for its metadata."""
    raw = value.encode("utf-8") or b" "
    return np.array(raw, dtype=h5py.string_dtype("utf-8", len(raw)))


def as_str(value: Any) -> str:
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


def to_json(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, default=_json_default)


def py(value: Any) -> Any:
    """An HDF5 attribute value as a plain Python object."""
    if isinstance(value, (bytes, np.bytes_)):
        return bytes(value).decode("utf-8")
    if isinstance(value, np.ndarray):
        return [py(v) for v in value.tolist()] if value.ndim else py(value[()])
    if isinstance(value, np.generic):
        return value.item()
    return value


# ------------------------------------------------------------------ groups and datasets


def group(parent: h5py.Group, name: str) -> h5py.Group:
    return parent.create_group(name, track_order=True)


def scale(parent: h5py.Group, name: str, data: np.ndarray, long_name: str) -> h5py.Dataset:
    """A 1-d dataset that is also the netCDF dimension ``name`` of its group."""
    ds = array(parent, name, data, [], long_name)
    ds.make_scale(name)
    return ds


def bits(data: np.ndarray) -> np.ndarray | None:
    """``data``'s elements as unsigned integers of the same size, flattened: equal where
    their bytes are (a NaN equals itself, -0.0 is not 0.0); None for other sizes."""
    size = data.dtype.itemsize
    if size not in (1, 2, 4, 8):
        return None
    return np.ascontiguousarray(data).reshape(-1).view(f"u{size}")


def write_chunks(ds: h5py.Dataset, lead: tuple[int, ...], data: np.ndarray) -> None:
    """Write ``data`` into ``ds[lead + (...)]`` chunk by chunk through HDF5's filters,
    skipping the chunks made of the fill value alone.

    ``ds`` is chunked along ``data``'s first axis (its chunks span the trailing
    axes). HDF5 reads a chunk never stored as the fill value: ahead of a wave the
    balls are at rest where they started, so a snapshot of a long line is mostly
    chunks of zeros, and the masses of a uniform line are one value, the fill value
    ``array`` gives them. (Only for chunks not stored before, which is how the writers
    here use it.)
    """
    step = ds.chunks[len(lead)]
    data = np.asarray(data, dtype=ds.dtype)
    fill = bits(np.asarray([ds.fillvalue], dtype=ds.dtype))
    for start in range(0, data.shape[0], step):
        part = data[start:start + step]
        if fill is not None and np.all(bits(part) == fill):
            continue
        ds[lead + (slice(start, start + len(part)),)] = part


#: A large array is stored compressed where a sample of it shrinks below this share of
#: its size: noisy floats (a long line's final velocities) barely shrink, and deflating
#: them cost a run of 10^6 balls half a second to save a tenth of the space.
WORTH_COMPRESSING = 0.85
#: The sample: this many runs of this many elements, spread over the array.
_SAMPLE_RUNS, _SAMPLE_RUN = 8, 4096


def _compresses(data: np.ndarray) -> bool:
    """Whether ``GZIP`` shrinks a sample of ``data`` below ``WORTH_COMPRESSING`` of it:
    the same shuffle and deflate level, on up to ``_SAMPLE_RUNS`` runs of elements."""
    import zlib

    flat = np.ascontiguousarray(data).reshape(-1)
    if flat.size <= _SAMPLE_RUNS * _SAMPLE_RUN:
        sample = flat
    else:
        starts = np.linspace(0, flat.size - _SAMPLE_RUN, _SAMPLE_RUNS).astype(np.int64)
        sample = np.concatenate([flat[i:i + _SAMPLE_RUN] for i in starts])
    raw = sample.view(np.uint8).reshape(sample.size, sample.itemsize)
    shuffled = np.ascontiguousarray(raw.T).tobytes()
    return len(zlib.compress(shuffled, GZIP["compression_opts"])) < (
        WORTH_COMPRESSING * len(shuffled))


def array(parent: h5py.Group, name: str, data, scales: list[h5py.Dataset],
          long_name: str, dtype=None) -> h5py.Dataset:
    """A fixed-size dataset, chunked and compressed when large, with dims attached."""
    data = np.asarray(data, dtype=dtype)
    if data.size > COMPRESS_ABOVE and data.dtype.kind in "biufS":
        # one value throughout (a uniform line's masses): the fill value, stored nowhere
        raw = bits(data)
        fill = data.reshape(-1)[0] if raw is not None and np.all(raw == raw[0]) else None
        ds = parent.create_dataset(name, shape=data.shape, dtype=data.dtype,
                                   chunks=(min(data.shape[0], BALL_CHUNK),) + data.shape[1:],
                                   fillvalue=fill, **(GZIP if _compresses(data) else {}))
        write_chunks(ds, (), data)
    else:
        ds = parent.create_dataset(name, data=data)
    for axis, dim in enumerate(scales):
        ds.dims[axis].attach_scale(dim)
    ds.attrs["long_name"] = long_name
    return ds


# ------------------------------------------------------------------ atomic files


def create(path: Path, temp: Path, what: str) -> h5py.File:
    """Open ``temp`` (``atomic.temp_name(path)``) for writing ``what``, e.g. "run file"."""
    if not path.parent.is_dir():
        raise StoreError(f"{path}: cannot create {what} (no folder {path.parent})")
    try:
        return h5py.File(temp, "w", libver=_LIBVER, track_order=True)
    except OSError as exc:
        found = re.search(r"error message = '([^']*)'", str(exc))
        reason = found.group(1) if found else str(exc).splitlines()[0]
        raise StoreError(f"{path}: cannot create {what} ({reason})") from exc


def commit(h5: h5py.File, temp: Path, path: Path) -> None:
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


def discard(h5: h5py.File | None, temp: Path) -> None:
    if h5 is not None:
        try:
            h5.close()
        except Exception:  # already closed or broken: removing the file is what matters
            pass
    try:
        os.unlink(temp)
    except FileNotFoundError:
        pass


def stamp(h5: h5py.File, fmt: str) -> None:
    h5.attrs["format"] = fmt
    h5.attrs["format_version"] = np.int64(_FORMAT_VERSIONS[fmt])
    h5.attrs["created"] = now()


# ------------------------------------------------------------------ reading


def get(h5: h5py.Group, item: str):
    if item not in h5:
        raise KeyError(item)
    return h5[item]


def attr(obj, key: str):
    if key not in obj.attrs:
        raise KeyError(f"{obj.name}@{key}")
    return obj.attrs[key]


def check_format(path_or_h5file, expected: str = RUN_FORMAT) -> int:
    """Check that a file is a chainrun file of the expected format and a known version.

    Parameters
    ----------
    path_or_h5file : str, path or h5py.File
    expected : {"chainrun-run", "chainrun-index", "chainrun-analysis", "chainrun-spectrum"}

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
        return check_open(path_or_h5file.file, path_or_h5file.file.filename, expected)
    name = os.fspath(path_or_h5file)
    with open_read(name) as h5:
        return check_open(h5, name, expected)


def open_read(name: str) -> h5py.File:
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


def h5_reason(exc: BaseException) -> str:
    """One line for an h5py error: HDF5's own reason, without its stack."""
    raw = exc.args[0] if isinstance(exc, KeyError) and exc.args else exc  # KeyError quotes
    text = " ".join(str(raw).split()) or type(exc).__name__
    found = re.search(r"\(([^()]*)\)\s*$", text)  # "Unable to ... (the reason)"
    return found.group(1) if found and text.startswith(("Unable", "Can't", "Error")) else text


def check_open(h5: h5py.File, name: str, expected: str) -> int:
    noun = expected.removeprefix("chainrun-")
    try:
        fmt = h5.attrs.get("format")
        raw_version = h5.attrs.get("format_version")
    except (KeyError, OSError, RuntimeError) as exc:  # a damaged object header
        raise StoreError(f"{name}: damaged HDF5 file ({h5_reason(exc)})") from None
    if fmt is None:
        raise StoreError(f"{name}: not a chainrun {noun} file (no format attribute)")
    try:
        fmt = as_str(fmt)
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
