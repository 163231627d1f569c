"""Per-ball and per-contact values of an experiment file: numbers, lists and generators.

This module owns what a key such as ``chain.mass`` may hold and how it becomes an array
of one value per ball (or per contact):

    mass = 1.0                                        # every ball alike
    mass = [1.0, 0.5, 1.0]                            # one value each
    mass = {pattern = [1.0, 0.5]}                     # repeated: 1, 0.5, 1, 0.5, ...
    mass = {taper = 0.9, start = 1.0}                 # geometric: start * taper^i, i from 0
    mass = {random = "uniform", low = 0.5, high = 2.0, seed = 1}
    mass = {random = "lognormal", median = 1.0, sigma = 0.2, seed = 1}
    mass = {value = 1.0, impurity = {at = 20, value = 0.1}}
    mass = {file = "masses.npy"}                      # or .csv/.txt, beside the config file

A table holds exactly one base (``value``, ``pattern``, ``taper``, ``random`` or
``file``) and optionally ``impurity``, which overrides the base at some balls (or
contacts): ``{at = 20, value = 0.1}``, ``{at = [20, 40], value = 0.1}``, or a list of
such tables. ``at`` counts from 1, as balls are numbered (contact j joins balls j and
j + 1). Text keys (``chain.material``) take a string, a list, ``pattern`` or
``value`` with ``impurity``.

Random values come from numpy's ``default_rng(seed)`` (PCG64): the same seed gives the
same values. A file's sha256 is part of the resolved configuration, so a run whose
data file changed is a new computation.

``check`` turns what the file holds into a ``Values`` (checked, hashable, JSON-able);
``expand`` turns that into an array of a given length. Problems are raised as
``ValuesError`` with the path below the key (e.g. ``("impurity", "at")``); the
experiment file's module turns them into its one-line messages.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from chainrun.errors import show_value, suggest

__all__ = ["BASES", "Values", "ValuesError", "check", "digest", "expand", "is_uniform",
           "read_rows"]

#: The base of a generator table and the keys each takes (besides ``impurity``).
BASES: dict[str, tuple[str, ...]] = {
    "value": ("value",),
    "pattern": ("pattern",),
    "taper": ("taper", "start"),
    "random": ("random", "seed", "low", "high", "median", "sigma"),
    "file": ("file", "sha256"),
}
#: Keys each kind of random values needs.
RANDOM = {"uniform": ("low", "high"), "lognormal": ("median", "sigma")}
#: Most values a list or pattern in the file may hold (longer ones: a data file).
MAX_LIST = 1_000_000


class ValuesError(ValueError):
    """A problem with a key's values; ``sub`` is the place below the key."""

    def __init__(self, reason: str, sub: tuple[str, ...] = ()):
        super().__init__(reason)
        self.reason = reason
        self.sub = sub


@dataclass(frozen=True)
class Values:
    """Checked values of one key: a number or text (``scalar``), a list (``items``) or a
    generator table (``table``, canonical JSON text). Exactly one is set."""

    scalar: float | str | None = None
    items: tuple | None = None
    table: str | None = None
    path: str | None = None  # a data file's absolute path (not part of the JSON)

    def to_json(self) -> Any:
        """As the experiment file would write it (a file's table gains its sha256)."""
        if self.table is not None:
            return json.loads(self.table)
        if self.items is not None:
            return list(self.items)
        return self.scalar

    @property
    def is_scalar(self) -> bool:
        return self.items is None and self.table is None


def _number(value: Any, sub: tuple[str, ...]) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            x = float(value)
        except OverflowError:
            x = math.inf
        if math.isfinite(x):
            return x
        raise ValuesError(f"must be finite, got {show_value(value)}", sub)
    raise ValuesError(f"expected a number, got {show_value(value)}", sub)


def _text(value: Any, sub: tuple[str, ...]) -> str:
    if isinstance(value, str):
        return value
    raise ValuesError(f"expected a string, got {show_value(value)}", sub)


def _int(value: Any, sub: tuple[str, ...], low: int) -> int:
    if isinstance(value, int) and not isinstance(value, bool) and low <= value < 2**63:
        return value
    raise ValuesError(f"expected an integer >= {low}, got {show_value(value)}", sub)


def _list(value: Any, sub: tuple[str, ...], item) -> list:
    if not isinstance(value, (list, tuple)) or not value:
        raise ValuesError(f"expected a non-empty list, got {show_value(value)}", sub)
    if len(value) > MAX_LIST:
        raise ValuesError(f"a list of {len(value)} values is too long (at most {MAX_LIST}; "
                          f"use a file)", sub)
    return [item(v, sub[:-1] + (f"{sub[-1]}[{i}]",) if sub else (f"[{i}]",))
            for i, v in enumerate(value)]


def _read(path: str) -> np.ndarray:
    """The numbers of a ``.npy`` file, or of a text file (``.csv``, ``.txt``: numbers
    separated by commas, spaces or new lines; ``#`` starts a comment)."""
    if path.lower().endswith(".npy"):
        data = np.load(path, allow_pickle=False)
    else:
        with open(path, encoding="utf-8") as handle:
            words = []
            for line in handle:
                words += line.split("#", 1)[0].replace(",", " ").split()
        data = np.array([float(w) for w in words], dtype=float)
    data = np.asarray(data)
    if data.dtype.kind not in "iuf":
        raise ValueError(f"holds {data.dtype} values, not numbers")
    return data.astype(float).reshape(-1)


def read_rows(path: str, columns: int) -> np.ndarray:
    """The rows of a data file, shape (M, columns): a ``.npy`` array of that shape, or
    a text file (``.csv``, ``.txt``) of one row a line, its numbers separated by commas
    or spaces (``#`` starts a comment; a first line of text is a header).

    Raises
    ------
    OSError, ValueError
        The file cannot be read, or a row is not ``columns`` numbers (naming its line).
    """
    if path.lower().endswith(".npy"):
        data = np.asarray(np.load(path, allow_pickle=False))
        if data.dtype.kind not in "iuf" or data.ndim != 2 or data.shape[1] != columns:
            raise ValueError(f"holds an array of {data.dtype} and shape {data.shape}, not "
                             f"rows of {columns} numbers")
        return data.astype(float)
    rows = []
    with open(path, encoding="utf-8") as handle:
        for number, line in enumerate(handle, start=1):
            words = line.split("#", 1)[0].replace(",", " ").split()
            if not words:
                continue
            try:
                row = [float(w) for w in words]
            except ValueError:
                if not rows and number == _first_line(path):
                    continue  # a header
                raise ValueError(f"line {number}: not a row of numbers") from None
            if len(row) != columns:
                raise ValueError(f"line {number}: {len(row)} numbers, expected {columns}")
            rows.append(row)
    return np.array(rows, dtype=float).reshape(-1, columns)


def _first_line(path: str) -> int:
    """The number of the first line of a text file that is not blank or a comment."""
    with open(path, encoding="utf-8") as handle:
        for number, line in enumerate(handle, start=1):
            if line.split("#", 1)[0].strip():
                return number
    return 0


def digest(path: str) -> str:
    """The sha256 of a file's bytes, as hex."""
    return _digest(path)


def _digest(path: str) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _impurities(value: Any, text: bool) -> list[dict]:
    """``impurity``: a table ``{at, value}`` or a list of them, checked."""
    tables = value if isinstance(value, (list, tuple)) else [value]
    if not tables:
        raise ValuesError("expected a table {at, value} or a list of them", ("impurity",))
    out = []
    for i, table in enumerate(tables):
        sub = ("impurity",) if not isinstance(value, (list, tuple)) else (f"impurity[{i}]",)
        if not isinstance(table, Mapping):
            raise ValuesError(f"expected a table {{at, value}}, got {show_value(table)}", sub)
        for key in table:
            if key not in ("at", "value"):
                raise ValuesError("unknown key (expected 'at' and 'value')", sub + (str(key),))
        for key in ("at", "value"):
            if key not in table:
                raise ValuesError("required", sub + (key,))
        at = table["at"]
        at = (_list(at, sub + ("at",), lambda v, s: _int(v, s, 1))
              if isinstance(at, (list, tuple)) else [_int(at, sub + ("at",), 1)])
        item = _text if text else _number
        out.append({"at": at, "value": item(table["value"], sub + ("value",))})
    return out


def check(value: Any, *, text: bool = False, base_dir: str = ".") -> Values:
    """``value`` from an experiment file, checked (not yet expanded to a length).

    Parameters
    ----------
    value : number, str, list or table
    text : bool
        Values are strings (material names), not numbers.
    base_dir : str
        The folder a ``file`` is relative to (the experiment file's).

    Raises
    ------
    ValuesError
    """
    item = _text if text else _number
    if isinstance(value, Mapping):
        table = _check_table(value, text, base_dir)
        path = table.pop("path", None)
        return Values(table=json.dumps(table, sort_keys=True), path=path)
    if isinstance(value, (list, tuple)):
        return Values(items=tuple(_list(value, (), lambda v, s: item(v, s))))
    if text and not isinstance(value, str):
        raise ValuesError(f"expected a string, a list or a table, got {show_value(value)}")
    if not text and not (isinstance(value, (int, float)) and not isinstance(value, bool)):
        raise ValuesError(f"expected a number, a list or a table, got {show_value(value)}")
    return Values(scalar=item(value, ()))


def _check_table(table: Mapping, text: bool, base_dir: str) -> dict:
    keys = [str(k) for k in table]
    bases = [k for k in keys if k in BASES]
    if len(bases) != 1:
        what = "none" if not bases else " and ".join(repr(b) for b in bases)
        choices = ", ".join(BASES) if not text else "value, pattern"
        raise ValuesError(f"a table needs exactly one of {choices} (got {what})")
    base = bases[0]
    allowed = set(BASES[base]) | {"impurity"}
    for key in keys:
        if key not in allowed:
            raise ValuesError(f"unknown key for a {base!r} table"
                              f"{suggest(key, sorted(allowed))}", (key,))
    if text and base not in ("value", "pattern"):
        raise ValuesError(f"{base!r} makes numbers; text takes 'value' or 'pattern'", (base,))
    item = _text if text else _number
    out: dict[str, Any] = {}
    if base == "value":
        out["value"] = item(table["value"], ("value",))
    elif base == "pattern":
        out["pattern"] = _list(table["pattern"], ("pattern",), item)
    elif base == "taper":
        taper = _number(table["taper"], ("taper",))
        if taper <= 0:
            raise ValuesError(f"must be > 0, got {taper!r}", ("taper",))
        if "start" not in table:
            raise ValuesError("required (the first value)", ("start",))
        out.update(taper=taper, start=_number(table["start"], ("start",)))
    elif base == "random":
        kind = table["random"]
        if kind not in RANDOM:
            raise ValuesError(f"expected one of {', '.join(map(repr, RANDOM))}, got "
                              f"{show_value(kind)}", ("random",))
        out["random"] = kind
        if "seed" not in table:
            raise ValuesError("required (the same seed gives the same values)", ("seed",))
        out["seed"] = _int(table["seed"], ("seed",), 0)
        for key in ("low", "high", "median", "sigma"):
            if key in table and key not in RANDOM[kind]:
                raise ValuesError(f"not a parameter of {kind!r} values "
                                  f"(they take {' and '.join(RANDOM[kind])})", (key,))
        for key in RANDOM[kind]:
            if key not in table:
                raise ValuesError("required", (key,))
            out[key] = _number(table[key], (key,))
        if kind == "uniform" and not out["low"] < out["high"]:
            raise ValuesError(f"must be > low ({out['low']!r}), got {out['high']!r}", ("high",))
        if kind == "lognormal":
            if out["median"] <= 0:
                raise ValuesError(f"must be > 0, got {out['median']!r}", ("median",))
            if out["sigma"] < 0:
                raise ValuesError(f"must be >= 0, got {out['sigma']!r}", ("sigma",))
    else:
        name = _text(table["file"], ("file",))
        if "sha256" in table:
            raise ValuesError("is computed from the file; do not give it", ("sha256",))
        path = os.path.join(base_dir, name)
        try:
            data = _read(path)
            digest = _digest(path)
        except FileNotFoundError:
            raise ValuesError(f"no such file {path}", ("file",)) from None
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise ValuesError(f"cannot read {path}: {show_value(reason)}", ("file",)) from None
        if data.size == 0:
            raise ValuesError(f"{path} holds no numbers", ("file",))
        # the folder is the experiment file's: keep the path as written, and the data's hash
        out.update(file=name, sha256=digest, path=os.path.abspath(path))
    if "impurity" in table:
        out["impurity"] = _impurities(table["impurity"], text)
    return out


def expand(values: Values, size: int) -> np.ndarray:
    """The ``size`` values (float array, or object array of str for text).

    Raises
    ------
    ValuesError
        A list or file of another length, or an impurity beyond ``size``.
    """
    if values.scalar is not None:
        dtype = object if isinstance(values.scalar, str) else float
        return np.full(size, values.scalar, dtype=dtype)
    if values.items is not None:
        if len(values.items) != size:
            raise ValuesError(f"expected a number or a list of {size} values, got a list "
                              f"of {len(values.items)}")
        dtype = object if isinstance(values.items[0], str) else float
        return np.array(values.items, dtype=dtype)
    table = json.loads(values.table)
    if "value" in table:
        a = np.full(size, table["value"], dtype=object if isinstance(table["value"], str)
                    else float)
    elif "pattern" in table:
        p = table["pattern"]
        a = np.resize(np.array(p, dtype=object if isinstance(p[0], str) else float), size)
    elif "taper" in table:
        with np.errstate(over="ignore", under="ignore"):
            a = table["start"] * np.power(table["taper"], np.arange(size, dtype=float))
    elif "random" in table:
        rng = np.random.default_rng(table["seed"])
        if table["random"] == "uniform":
            a = rng.uniform(table["low"], table["high"], size)
        else:
            a = table["median"] * np.exp(table["sigma"] * rng.standard_normal(size))
    else:
        data = _read(values.path)
        if _digest(values.path) != table["sha256"]:
            raise ValuesError(f"{values.path} changed since the experiment was read",
                              ("file",))
        if data.size != size:
            raise ValuesError(f"{table['file']} holds {data.size} numbers, expected "
                              f"{size}", ("file",))
        a = data
    for i, imp in enumerate(table.get("impurity", ())):
        for at in imp["at"]:
            if at > size:
                sub = ("impurity", "at") if len(table["impurity"]) == 1 else (
                    f"impurity[{i}]", "at")
                raise ValuesError(f"{at} is beyond the {size} values", sub)
            a[at - 1] = imp["value"]
    return a


def is_uniform(values: Values) -> bool:
    """Whether the values are one number, whatever the length (a scalar)."""
    return values.is_scalar
