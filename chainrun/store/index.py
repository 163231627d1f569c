"""Index files: the table of an experiment's runs, with a link to each run file.

An *index file* lists the runs of one experiment (one row per run: its id, file,
parameters and summary) and links to each run file (HDF5 external links), so that one
file opens a whole sweep. The tree is drawn in ``docs/schema.md``; change it together
with ``INDEX_FORMAT_VERSION``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Iterable

import h5py
import numpy as np

import chainrun
from chainrun import atomic
from chainrun.errors import StoreError
from chainrun.store import _h5
from chainrun.store._h5 import INDEX_FORMAT

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
    h5 = _h5.create(path, temp, "index file")
    try:
        _h5.stamp(h5, INDEX_FORMAT)
        h5.attrs["experiment"] = str(experiment)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        table = _h5.group(h5, "table")
        run = _h5.scale(table, "run", np.arange(len(entries), dtype=np.int64), "row number")
        for name, kind in kinds.items():
            data = _column([e[name] for e in entries], kind, name, path)
            ds = table.create_dataset(name, data=data)
            ds.dims[0].attach_scale(run)
        table.attrs["columns"] = json.dumps(list(kinds))
        runs = _h5.group(h5, "runs")
        for entry in entries:
            runs[str(entry["run_id"])] = h5py.ExternalLink(os.fspath(entry["file"]), "/")
        _h5.commit(h5, temp, path)
    except BaseException:
        _h5.discard(h5, temp)
        raise


def read_index(path) -> list[dict]:
    """Read the table of an index file: one dict per run, in the order written."""
    name = os.fspath(path)
    with _h5.open_read(name) as h5:
        _h5.check_open(h5, name, INDEX_FORMAT)
        try:
            table = _h5.get(h5, "table")
            columns = json.loads(_h5.as_str(_h5.attr(table, "columns")))
            data = {c: _h5.get(table, c)[()] for c in columns}
        except KeyError as exc:
            raise StoreError(f"{name}: damaged index file (missing {exc.args[0]})") from None
        except (OSError, ValueError) as exc:
            raise StoreError(f"{name}: damaged index file ({exc})") from None
    rows = len(data[columns[0]]) if columns else 0
    return [{c: _h5.py(data[c][i]) for c in columns} for i in range(rows)]

