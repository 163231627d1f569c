"""The comparison table: every printed number beside the value chainrun computes.

This module owns the recipe of the ``paper-comparison`` artefact. It reads every other
analysis file, looks up the value behind each entry of ``chainrun.analysis.paper`` and
its spread (how far it moves when the runs' tolerance is cut tenfold, where the
analysis was made with ``--check``), decides agreement by the entry's rule within that
spread and renders its note with no digit beyond the spreads. The table is stored as
columns of the analysis file; ``chainrun plot paper-comparison`` only formats it.
"""

from __future__ import annotations

import numpy as np

from chainrun.analysis import Inputs, Result
from chainrun.analysis.paper import PRINTED, agrees, render_note
from chainrun.errors import ChainrunError

__all__ = ["COLUMNS", "paper_comparison"]

#: Columns of the table, in order (``computed`` and ``spread`` are numeric, ``agrees`` and
#: ``by_spread`` boolean: ``by_spread`` marks a row that agrees only within its spread).
COLUMNS = ("key", "where", "quantity", "paper", "computed", "spread", "agrees", "by_spread",
           "rule", "note")


def _transform(value: float, how: str) -> float:
    return {"": value, "abs": abs(value), "neg": -value}[how]


def paper_comparison(inputs: Inputs) -> Result:
    """One row per printed number: key, where, quantity, paper, computed, spread,
    agrees, by_spread, rule, note."""
    analyses = {name: inputs.analysis(name) for name in inputs.artefact.needs}
    values = {name: data.values for name, data in analyses.items()}
    spreads = {name: data.spreads for name, data in analyses.items()}
    rows = []
    for entry in PRINTED:
        artefact, _, key = entry.source.partition("/")
        try:
            computed = _transform(values[artefact][key], entry.transform)
        except KeyError:
            raise ChainrunError(f"paper-comparison: {entry.key} needs {entry.source}, "
                                "which no analysis file provides") from None
        spread = spreads[artefact].get(key, np.nan)
        agree = agrees(entry, computed, spread)
        rows.append(dict(key=entry.key, where=entry.where, quantity=entry.quantity,
                         paper=entry.text, computed=computed, spread=spread, agrees=agree,
                         by_spread=agree and not agrees(entry, computed), rule=entry.rule,
                         note=render_note(entry.note, values, spreads)))
    keys = [row["key"] for row in rows]
    if len(set(keys)) != len(keys):
        raise ChainrunError("paper-comparison: duplicate keys in chainrun.analysis.paper")
    r = Result()
    for column in COLUMNS:
        data = [row[column] for row in rows]
        if column in ("computed", "spread"):
            r.array(f"table/{column}", np.array(data, dtype=float))
        elif column in ("agrees", "by_spread"):
            r.array(f"table/{column}", np.array(data, dtype=bool))
        else:
            r.array(f"table/{column}", np.array(data, dtype=str))
    agree = sum(row["agrees"] for row in rows)
    explained = sum((not row["agrees"]) and bool(row["note"]) for row in rows)
    r.value("rows", len(rows), "numbers compared")
    r.value("agreeing", agree, "rows equal at the printed precision (or by their rule), "
            "within chainrun's spread")
    r.value("by_spread", sum(row["by_spread"] for row in rows),
            "rows that agree only within chainrun's spread")
    r.value("checked", sum(not np.isnan(row["spread"]) for row in rows),
            "rows whose computed value has a measured spread")
    r.value("explained", explained, "rows that disagree, with an explanation")
    r.value("unexplained", len(rows) - agree - explained,
            "rows that disagree without an explanation (should be 0)")
    return r
