"""Problems of an experiment file, one line each naming a dotted key: the checks of a
single value, and pydantic's errors translated into them.

A validator raises ``fail([Issue(...)])``; ``translate`` turns the pydantic error back
into ``Problem``s with their full keys (``chain.alpha[3]: must be >= 1, got 0.5``),
never pydantic's own text. Nothing here knows the schema's models beyond the map of
which model sits at which key that ``translate`` is given.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

from pydantic import BaseModel, ValidationError
from pydantic_core import PydanticCustomError

from chainrun.errors import show_value, suggest

#: Largest integer a config may hold: run files store integers as int64.
MAX_INT = 2**63 - 1

#: The pydantic error type of the problems raised by ``fail``.
_ERROR_TYPE = "chainrun"


class Issue(NamedTuple):
    """One problem found inside a validator, relative to the field it validates.

    ``sub`` extends the field's location (e.g. ``("step",)`` for ``output.times.step``);
    ``involves`` names sibling keys the problem also depends on (e.g. ``("n",)`` for
    ``chain.k <= chain.n``), which decides whether a sweep combination caused it.
    """

    reason: str
    sub: tuple[str, ...] = ()
    involves: tuple[str, ...] = ()


class Problem(NamedTuple):
    """A problem with its full dotted key, ready to print as ``key: reason``."""

    key: str
    reason: str
    involves: frozenset[str] = frozenset()

    def line(self) -> str:
        return f"{self.key}: {self.reason}" if self.key else self.reason


def fail(issues: list[Issue]) -> PydanticCustomError:
    """The pydantic error carrying ``issues``; ``translate`` unpacks it again."""
    return PydanticCustomError(
        _ERROR_TYPE, "{reason}", {"reason": "; ".join(i.reason for i in issues), "issues": issues}
    )


def key_path(parts: tuple[str, ...]) -> str:
    """A place in the file from its keys: ``chain.alpha[3]``, an index kept on its key."""
    return "".join(p if p.startswith("[") or i == 0 else "." + p for i, p in enumerate(parts))


def key_text(key: Any) -> str:
    """A user's key for a message: one line, at most 60 characters."""
    if not isinstance(key, str):
        return show_value(key)
    text = "".join(c if c.isprintable() else repr(c)[1:-1] for c in key[:200])
    return text if len(text) <= 60 else text[:57] + "..."


def bound(value: Any) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


# --- scalar checks shared by the models and the sweep table -------------------------------


def check_int(value: Any) -> int:
    """``value`` if it is a true integer (not a bool, not 2.0 or "3") that fits in an
    int64, else an error."""
    if isinstance(value, int) and not isinstance(value, bool):
        if -MAX_INT - 1 <= value <= MAX_INT:
            return value
        raise fail([Issue("must be a 64-bit integer (at most 2**63 - 1), got "
                            f"{show_value(value)}")])
    raise fail([Issue(f"expected an integer, got {show_value(value)}")])


def check_float(value: Any) -> float:
    """``value`` as a float if it is a finite int or float (not a bool), else an error."""
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        try:
            x = float(value)
        except OverflowError:  # an integer beyond 1.8e308
            raise fail([Issue(f"must be finite, got {show_value(value)}")]) from None
        if math.isfinite(x):
            return x
        raise fail([Issue(f"must be finite, got {show_value(value)}")])
    hint = ""
    if isinstance(value, str):
        try:
            float(value)
            hint = " (text, not a number; YAML reads 1e-12 as text: write 1.0e-12)"
        except ValueError:
            pass
    raise fail([Issue(f"expected a number, got {show_value(value)}{hint}")])


def check_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    raise fail([Issue(f"expected true or false, got {show_value(value)}")])


def check_str(value: Any) -> str:
    if isinstance(value, str):
        return value
    raise fail([Issue(f"expected a string, got {show_value(value)}")])


# --- pydantic errors -> one-line problems -------------------------------------------------


def _nested(loc: tuple[str, ...], choices: list[str]) -> str:
    """Where an unknown key joins a key of its table and one inside it with ``_``
    (``motion_frequency`` for ``motion.frequency``), that dotted key as a suggestion;
    else ""."""
    head, _, rest = loc[-1].partition("_")
    while rest:
        if head in choices:
            return f" (did you mean '{'.'.join(loc[:-1] + (head, rest))}'?)"
        more, _, rest = rest.partition("_")
        head = f"{head}_{more}"
    return ""


def _elsewhere(loc: tuple[str, ...], models: Mapping[tuple[str, ...], type[BaseModel]]) -> str:
    """Where an unknown key is a key of another table (``chain.sensors`` is
    ``output.sensors``, a top-level ``n`` is ``chain.n``), as a suggestion; else ""."""
    for where, model in models.items():
        if where != loc[:-1] and where and loc[-1] in model.model_fields:
            return f" (did you mean '{'.'.join(where + (loc[-1],))}'?)"
    return ""


def translate(exc: ValidationError, models: Mapping[tuple[str, ...], type[BaseModel]],
              prefix: tuple[str, ...] = ()) -> list[Problem]:
    """Each pydantic error as a ``key: reason`` problem (never pydantic's own text).

    ``models`` maps a table's keys (``("walls", "left")``) to the model read there,
    whose fields an unknown key is compared with; ``prefix`` is where the validated
    data sits in the file."""
    problems: list[Problem] = []
    for error in exc.errors(include_url=False):
        loc = prefix + tuple(key_text(part) for part in error["loc"])
        kind, ctx, value = error["type"], error.get("ctx") or {}, error.get("input")
        if kind == _ERROR_TYPE:
            for issue in ctx["issues"]:
                parent = loc + issue.sub
                problems.append(
                    Problem(
                        key_path(parent),
                        issue.reason,
                        frozenset(".".join(loc[:-1] + (k,)) for k in issue.involves),
                    )
                )
            continue
        key = ".".join(loc)
        if kind == "missing":
            reason = "required"
        elif kind == "extra_forbidden":
            model = models.get(loc[:-1])
            choices = list(model.model_fields) if model else []
            hint = (suggest(loc[-1], choices) or _nested(loc, choices)
                    or _elsewhere(loc, models))
            reason = f"unknown key{hint}"
        elif kind == "invalid_key":
            key = ".".join(loc[:-1]) or "top level"
            reason = f"unknown key {show_value(error['loc'][-1])} (keys must be text)"
        elif kind in ("model_type", "dict_type", "model_attributes_type"):
            reason = f"expected a table, got {show_value(value)}"
        elif kind == "string_type":
            reason = f"expected a string, got {show_value(value)}"
        elif kind in ("greater_than_equal", "greater_than", "less_than_equal", "less_than"):
            op, limit = {
                "greater_than_equal": (">=", "ge"),
                "greater_than": (">", "gt"),
                "less_than_equal": ("<=", "le"),
                "less_than": ("<", "lt"),
            }[kind]
            reason = f"must be {op} {bound(ctx[limit])}, got {show_value(value)}"
        else:  # not expected from this schema; pydantic's msg is one line
            reason = f"{error['msg']}, got {show_value(value)}"
        problems.append(Problem(key, reason))
    return problems
