"""The comparison table: every printed number beside the value chainrun computes.

This module owns the recipe of the ``paper-comparison`` artefact. It reads every other
analysis file, looks up the value behind each entry of ``chainrun.analysis.paper``,
decides agreement by the entry's rule and renders its note. The table is stored as
columns of the analysis file; ``chainrun plot paper-comparison`` only formats it.
"""

from __future__ import annotations

import numpy as np

from chainrun.analysis import Inputs, Result
from chainrun.analysis.paper import PRINTED, agrees, render_note
from chainrun.errors import ChainrunError

__all__ = ["COLUMNS", "paper_comparison"]

#: Columns of the table, in order (``computed`` is numeric, ``agrees`` boolean).
COLUMNS = ("key", "where", "quantity", "paper", "computed", "agrees", "rule", "note")


def _transform(value: float, how: str) -> float:
    return {"": value, "abs": abs(value), "neg": -value}[how]


def paper_comparison(inputs: Inputs) -> Result:
    """One row per printed number: key, where, quantity, paper, computed, agrees, note."""
    values = {name: inputs.analysis(name).values for name in inputs.artefact.needs}
    rows = []
    for entry in PRINTED:
        artefact, _, key = entry.source.partition("/")
        try:
            computed = _transform(values[artefact][key], entry.transform)
        except KeyError:
            raise ChainrunError(f"paper-comparison: {entry.key} needs {entry.source}, "
                                "which no analysis file provides") from None
        rows.append(dict(key=entry.key, where=entry.where, quantity=entry.quantity,
                         paper=entry.text, computed=computed, agrees=agrees(entry, computed),
                         rule=entry.rule, note=render_note(entry.note, values)))
    keys = [row["key"] for row in rows]
    if len(set(keys)) != len(keys):
        raise ChainrunError("paper-comparison: duplicate keys in chainrun.analysis.paper")
    r = Result()
    for column in COLUMNS:
        data = [row[column] for row in rows]
        if column == "computed":
            r.array(f"table/{column}", np.array(data, dtype=float))
        elif column == "agrees":
            r.array(f"table/{column}", np.array(data, dtype=bool))
        else:
            r.array(f"table/{column}", np.array(data, dtype=str))
    agree = sum(row["agrees"] for row in rows)
    explained = sum((not row["agrees"]) and bool(row["note"]) for row in rows)
    r.value("rows", len(rows), "numbers compared")
    r.value("agreeing", agree, "rows equal at the printed precision (or by their rule)")
    r.value("explained", explained, "rows that disagree, with an explanation")
    r.value("unexplained", len(rows) - agree - explained,
            "rows that disagree without an explanation (should be 0)")
    return r
