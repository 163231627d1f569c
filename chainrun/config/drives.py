"""Drives of an experiment file: a wall's prescribed motion (``walls.<side>.motion``) and
forces in time on chosen balls (``chain.drive``), as sines or samples from a data file.

Each is checked into a ``DriveSpec``: the table the file holds (canonical JSON, a data
file's table with the sha256 of its data) and the ``chainrun.solver.Drive`` it describes.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import BeforeValidator, PlainSerializer, ValidationInfo
from pydantic_core import PydanticCustomError

from chainrun import generators
from chainrun.config.problems import (Issue, bound, check_float, check_int, check_str, fail,
                                      key_text, suggest)
from chainrun.errors import show_value
from chainrun.solver.drive import Drive, Sine

#: The keys of a sine of a drive (amplitude, frequency in cycles per unit of time, ramp).
SINE_KEYS = ("amplitude", "frequency", "ramp")
#: What a required key of a sine is, by the drive's quantity, for the message that asks
#: for it.
_FREQUENCY = "the sine's frequency f, in cycles per unit of time; Hz in SI"
_MEANING = {
    ("amplitude", "displacement"): "the sine's amplitude A, the wall's largest "
                                   "displacement from its place; m in SI",
    ("amplitude", "force"): "the sine's amplitude, the force's largest value; N in SI",
    ("frequency", "displacement"): _FREQUENCY,
    ("frequency", "force"): _FREQUENCY,
}


@dataclass(frozen=True, eq=False)
class DriveSpec:
    """A checked drive of an experiment file: ``walls.<side>.motion`` (a displacement)
    or one entry of ``chain.drive`` (a force on ``ball``, numbered from 1).

    ``table`` is what the file holds, as canonical JSON (a file's table gains the
    sha256 of its data, as a generator's does); ``drive`` the function of time
    (``chainrun.solver.Drive``)."""

    table: str
    drive: Drive
    ball: int | None = None
    index: int | None = None  # its place in a list of them (chain.drive)

    def to_json(self) -> Any:
        return json.loads(self.table)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, DriveSpec) and (self.table, self.ball) == (other.table,
                                                                           other.ball)

    def __hash__(self) -> int:
        return hash((self.table, self.ball))

    @property
    def sine(self) -> bool:
        """Whether it is one sine table (whose keys a sweep may vary)."""
        table = self.to_json()
        return isinstance(table, Mapping) and "file" not in table


def _number_issue(table: Mapping, key: str, sub: tuple[str, ...], low: float | None = None,
                  strict: bool = True) -> tuple[float | None, list[Issue]]:
    """``table[key]`` as a finite number (above ``low``), or the issue."""
    try:
        x = check_float(table[key])
    except PydanticCustomError as exc:
        return None, [i._replace(sub=sub + (key,)) for i in exc.context["issues"]]
    if low is not None and (x <= low if strict else x < low):
        op = ">" if strict else ">="
        return None, [Issue(f"must be {op} {bound(low)}, got {show_value(table[key])}",
                            sub + (key,))]
    return x, []


def _drive_table(table: Any, sub: tuple[str, ...], base_dir: str, what: str,
                 ball: bool) -> tuple[dict | None, Any, list[Issue]]:
    """One table of a drive: a sine ``{amplitude, frequency, ramp}`` or ``{file}`` (with
    ``ball`` in ``chain.drive``). Returns its JSON form, a ``Sine`` or the samples
    ``(times, values)``, and its issues."""
    shape = "{ball, amplitude, frequency, ramp}" if ball else "{amplitude, frequency, ramp}"
    if not isinstance(table, Mapping):
        return None, None, [Issue(f"expected a table {shape} or {{file}}, got "
                                  f"{show_value(table)}", sub)]
    keys = [str(k) for k in table]
    allowed = (("file",) if "file" in keys else SINE_KEYS) + (("ball",) if ball else ())
    alone = " (a drive from a file takes no other key)" if "file" in keys else ""
    issues = [Issue(f"unknown key{suggest(k, list(allowed)) or alone}",
                    sub + (key_text(k),)) for k in keys if k not in allowed]
    out: dict[str, Any] = {}
    if ball:
        if "ball" not in table:
            issues.append(Issue("required (the driven ball, from 1)", sub + ("ball",)))
        else:
            try:
                number = check_int(table["ball"])
            except PydanticCustomError as exc:
                issues += [i._replace(sub=sub + ("ball",)) for i in exc.context["issues"]]
            else:
                if number < 1:
                    issues.append(Issue(f"must be a ball number >= 1, got {number}",
                                        sub + ("ball",)))
                out["ball"] = number
    if "file" in keys:
        try:
            name = check_str(table["file"])
        except PydanticCustomError as exc:
            return None, None, issues + [i._replace(sub=sub + ("file",))
                                         for i in exc.context["issues"]]
        path = os.path.join(base_dir, name)
        try:
            rows = generators.read_rows(path, 2)
            digest = generators.digest(path)
        except FileNotFoundError:
            return None, None, issues + [Issue(f"no such file {path}", sub + ("file",))]
        except (OSError, ValueError, UnicodeDecodeError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            return None, None, issues + [Issue(f"cannot read {path}: {reason}",
                                               sub + ("file",))]
        t, u = rows[:, 0], rows[:, 1]
        problem = None
        if t.size < 2:
            problem = f"{path} holds {t.size} rows: a drive needs at least two (time, {what})"
        elif not (np.all(np.isfinite(t)) and np.all(np.isfinite(u))):
            problem = f"{path} holds a value that is not finite"
        elif t[0] != 0.0:
            problem = f"{path}: the first time must be 0, got {float(t[0])!r}"
        elif np.any(np.diff(t) <= 0.0):
            i = int(np.flatnonzero(np.diff(t) <= 0.0)[0]) + 1
            problem = (f"{path}: times must increase, got {float(t[i])!r} after "
                       f"{float(t[i - 1])!r} (row {i + 1})")
        elif what == "displacement" and u[0] != 0.0:
            problem = (f"{path}: the wall starts at its place, so its displacement at t = 0 "
                       f"must be 0, got {float(u[0])!r}")
        if problem:
            return None, None, issues + [Issue(problem, sub + ("file",))]
        out.update(file=name, sha256=digest)
        return (out, (t, u), issues) if not issues else (None, None, issues)
    got: dict[str, float] = {}
    for key, low, strict in (("amplitude", None, True), ("frequency", 0.0, True),
                             ("ramp", 0.0, False)):
        if key not in table:
            if key != "ramp":
                issues.append(Issue(f"required ({_MEANING[key, what]})", sub + (key,)))
            continue
        x, found = _number_issue(table, key, sub, low, strict)
        issues += found
        if x is not None:
            got[key] = x
    if issues:
        return None, None, issues
    out.update(got)
    return out, Sine(got["amplitude"], got["frequency"], got.get("ramp", 0.0)), []


def _check_drive(value: Any, base_dir: str, what: str) -> DriveSpec:
    """``walls.<side>.motion``: a sine table, a list of them (their sum), or ``{file}``."""
    if isinstance(value, DriveSpec):
        return value
    tables = value if isinstance(value, (list, tuple)) else [value]
    if isinstance(value, (list, tuple)) and not value:
        raise fail([Issue("expected a table or a non-empty list of tables")])
    listed = isinstance(value, (list, tuple))
    issues: list[Issue] = []
    parts = []
    for i, table in enumerate(tables):
        sub = (f"[{i}]",) if listed else ()
        out, part, found = _drive_table(table, sub, base_dir, what, False)
        issues += found
        if listed and isinstance(part, tuple):
            issues.append(Issue("a file drives alone: give {file} without a list", sub))
        parts.append((out, part))
    if issues:
        raise fail(issues)
    if isinstance(parts[0][1], tuple):
        drive = Drive.from_samples(*parts[0][1])
    else:
        drive = Drive.of_sines([p for _, p in parts])
    table = [o for o, _ in parts] if listed else parts[0][0]
    return DriveSpec(json.dumps(table, sort_keys=True), drive)


def _check_ball_drives(value: Any, base_dir: str) -> tuple[DriveSpec, ...]:
    """``chain.drive``: a table ``{ball, amplitude, frequency, ramp}`` or ``{ball, file}``,
    or a list of them (several on one ball add up)."""
    if isinstance(value, tuple) and all(isinstance(v, DriveSpec) for v in value):
        return value
    listed = isinstance(value, (list, tuple))
    tables = value if listed else [value]
    if listed and not value:
        raise fail([Issue("expected a table or a non-empty list of tables")])
    issues: list[Issue] = []
    specs = []
    for i, table in enumerate(tables):
        sub = (f"[{i}]",) if listed else ()
        out, part, found = _drive_table(table, sub, base_dir, "force", True)
        issues += found
        if found:
            continue
        drive = Drive.from_samples(*part) if isinstance(part, tuple) else Drive.of_sines([part])
        specs.append(DriveSpec(json.dumps({k: v for k, v in out.items() if k != "ball"},
                                          sort_keys=True), drive, out["ball"],
                               i if listed else None))
    if issues:
        raise fail(issues)
    return tuple(specs)


def drive_validator(what: str):
    def check(value: Any, info: ValidationInfo) -> Any:
        if value is None:
            return None
        base = (info.context or {}).get("base_dir", ".")
        if what == "force":
            return _check_ball_drives(value, base)
        return _check_drive(value, base, what)

    return BeforeValidator(check)


def _dump_drive(value: Any) -> Any:
    if isinstance(value, DriveSpec):
        return value.to_json()
    if isinstance(value, tuple):
        return [{"ball": v.ball, **v.to_json()} for v in value]
    return value


DumpDrive = PlainSerializer(_dump_drive)
