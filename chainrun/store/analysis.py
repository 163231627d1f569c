"""Analysis files: what ``chainrun analyze`` derives for one artefact of the paper.

An *analysis file* holds what ``chainrun analyze`` derives for one artefact (a figure, a
table or a set of printed numbers): named scalar values, the arrays a figure draws, the
settings that produced them, and the sha256 of every run or analysis file read.
``chainrun plot`` reads nothing else. The tree is drawn in ``docs/schema.md``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import h5py
import numpy as np

import chainrun
from chainrun import atomic
from chainrun.errors import StoreError
from chainrun.store import _h5
from chainrun.store._h5 import ANALYSIS_FORMAT, ANALYSIS_FORMAT_VERSION

#: Columns of an analysis file's ``/inputs`` table, in order.
ANALYSIS_INPUT_COLUMNS = ("kind", "name", "file", "sha256")


def file_sha256(path) -> str:
    """The sha256 of a file's bytes, as 64 hex digits."""
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
        group = group[part] if part in group else _h5.group(group, part)
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
    h5 = _h5.create(path, temp, "analysis file")
    try:
        _h5.stamp(h5, ANALYSIS_FORMAT)
        h5.attrs["artefact"] = str(data.name)
        h5.attrs["title"] = str(data.title)
        h5.attrs["creator_name"] = "chainrun"
        h5.attrs["creator_version"] = chainrun.__version__
        h5.attrs["settings"] = _h5.to_json(data.settings)

        values = _h5.group(h5, "values")
        for key, value in data.values.items():
            ds = values.create_dataset(key, data=np.float64(value))
            ds.attrs["description"] = str(data.descriptions.get(key, ""))
            if key in data.spreads:
                ds.attrs["spread"] = np.float64(data.spreads[key])

        arrays = _h5.group(h5, "data")
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

        inputs = _h5.group(h5, "inputs")
        for column in ANALYSIS_INPUT_COLUMNS:
            inputs.create_dataset(column, data=np.array([str(r[column]) for r in data.inputs],
                                                        dtype=object),
                                  dtype=h5py.string_dtype())
        _h5.commit(h5, temp, path)
    except BaseException:
        _h5.discard(h5, temp)
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
    with _h5.open_read(name) as h5:
        version = _h5.check_open(h5, name, ANALYSIS_FORMAT)
        try:
            values: dict[str, float] = {}
            descriptions: dict[str, str] = {}
            spreads: dict[str, float] = {}
            for key, ds in _h5.get(h5, "values").items():
                values[key] = float(ds[()])
                descriptions[key] = _h5.as_str(ds.attrs.get("description", ""))
                if "spread" in ds.attrs:
                    spreads[key] = float(ds.attrs["spread"])
            arrays: dict[str, np.ndarray] = {}
            attrs: dict[str, dict[str, Any]] = {}

            def visit(group: h5py.Group, prefix: str) -> None:
                if prefix and len(group.attrs):
                    attrs[prefix] = {k: _h5.py(v) for k, v in group.attrs.items()}
                for key, item in group.items():
                    full = f"{prefix}/{key}" if prefix else key
                    if isinstance(item, h5py.Group):
                        visit(item, full)
                    elif h5py.check_string_dtype(item.dtype) is not None:
                        arrays[full] = np.array(item.asstr()[()], dtype=str)
                    else:
                        arrays[full] = item[()]

            visit(_h5.get(h5, "data"), "")
            table = _h5.get(h5, "inputs")
            columns = {c: _h5.get(table, c).asstr()[()] for c in ANALYSIS_INPUT_COLUMNS}
            rows = len(columns["kind"])
            inputs = [{c: str(columns[c][i]) for c in ANALYSIS_INPUT_COLUMNS}
                      for i in range(rows)]
            return AnalysisData(
                name=_h5.as_str(_h5.attr(h5, "artefact")),
                title=_h5.as_str(h5.attrs.get("title", "")),
                values=values,
                descriptions=descriptions,
                arrays=arrays,
                attrs=attrs,
                settings=json.loads(_h5.as_str(_h5.attr(h5, "settings"))),
                inputs=inputs,
                path=Path(name),
                format_version=version,
                created=_h5.as_str(h5.attrs.get("created", "")),
                creator_version=_h5.as_str(h5.attrs.get("creator_version", "")),
                spreads=spreads,
            )
        except KeyError as exc:
            raise StoreError(f"{name}: damaged analysis file (missing {exc.args[0]})") from None


# -------------------------------------------------------------------- spectrum files
#
# A *spectrum file* holds the linear spectrum of one run's line at rest
# (``chainrun.analysis.spectrum``): an xarray Dataset written as a flat netCDF-4 file,
# every coordinate a dimension scale, so ``xarray.open_dataset(path, engine="h5netcdf")``
