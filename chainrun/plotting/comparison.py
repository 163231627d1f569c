"""The comparison of every printed number with chainrun's value, as CSV and Markdown.

The analysis (``chainrun.analysis.comparison``) decides agreement and writes the notes;
this module only lays the table out: each computed value with no digit beyond its
spread (``chainrun.units.format_supported``), and the spread beside it.
"""

from __future__ import annotations

import csv
import io
import math

from chainrun.units import format_supported

COLUMNS = ("key", "where", "quantity", "paper", "computed", "spread", "agrees", "rule", "note")


def _computed(value: float, spread: float = math.nan) -> str:
    """A computed value, with no digit beyond its spread (NaN: not measured)."""
    if value != value:   # NaN: no value
        return "—"
    if (float(value).is_integer() and abs(value) < 1e6
            and (math.isnan(spread) or spread < 1.0)):
        return str(int(value))
    return format_supported(float(value), float(spread))


def _spread(spread: float) -> str:
    """A spread: ``3e-13``, ``0`` (the runs agree to every bit), ``—`` (not measured)."""
    if math.isnan(spread):
        return "—"
    if spread == 0.0:
        return "0"
    return f"{spread:.0e}" if math.isfinite(spread) else "inf"


def _rows(data):
    names = [c for c in COLUMNS + ("by_spread",) if f"table/{c}" in data.arrays]
    t = {c: data.arrays[f"table/{c}"] for c in names}
    for i in range(len(t["key"])):
        row = {c: t[c][i] for c in names}
        row.setdefault("spread", math.nan)
        row.setdefault("by_spread", False)
        yield row


def _md_escape(text: str) -> str:
    return str(text).replace("|", "\\|")


def write(data) -> dict[str, str]:
    rows = list(_rows(data))
    v = data.values

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([r["key"], r["where"], r["quantity"], r["paper"],
                    _computed(r["computed"], r["spread"]), _spread(r["spread"]),
                    "true" if r["agrees"] else "false", r["rule"], r["note"]])

    md = [
        "# The paper's numbers beside chainrun's",
        "",
        "Every number printed in Hinch & Saint-Jean, *The fragmentation of a line of balls by "
        "an impact*, from the abstract to section 5d, with the value chainrun computes from "
        "its runs (or from the paper's theory, where the paper derives it). *agrees* means "
        "equal at the printed precision (half a unit of the last printed digit), unless the "
        "rule says otherwise: *exact* for fractions and counts, *between* / *below* for "
        "printed bounds. *spread* is how far chainrun's value moves when its runs are "
        "made again at a tenth of their tolerance (`make figures` makes both and derives "
        "every number from each): *computed* shows no digit beyond it (0: the two agree "
        "to the last bit, as a number from theory alone does; —: not measured), and "
        "agreement is judged within it. Regenerate with `make figures`; the same table is in "
        "`paper-comparison.csv`.",
        "",
        f"**{int(v['rows'])} numbers: {int(v['agreeing'])} agree"
        + (f" ({int(v['by_spread'])} only within chainrun's spread)"
           if v.get("by_spread") else "")
        + f", {int(v['explained'])} disagree with the explanation below, "
        f"{int(v['unexplained'])} disagree unexplained.**",
        "",
        "| key | where | quantity | paper | computed | spread | agrees |",
        "|---|---|---|---:|---:|---:|:---:|",
    ]
    for r in rows:
        mark = (("yes, within the spread" if r["by_spread"] else "yes") if r["agrees"]
                else f"**no** ([note](#{r['key'].replace('.', '')}))")
        md.append(f"| {r['key']} | {_md_escape(r['where'])} | {_md_escape(r['quantity'])} | "
                  f"{_md_escape(r['paper'])} | {_computed(r['computed'], r['spread'])} | "
                  f"{_spread(r['spread'])} | {mark} |")
    md += ["", "## Disagreements and their explanations", ""]
    for r in rows:
        if not r["agrees"]:
            md += [f"### {r['key']}", "",
                   f"{r['where']}, {r['quantity']}: the paper prints **{r['paper']}**, "
                   f"chainrun computes **{_computed(r['computed'], r['spread'])}**.", "",
                   r["note"] or "UNEXPLAINED.", ""]
    md += ["## How each value is computed", ""]
    for r in rows:
        if r["agrees"] and r["note"]:
            md.append(f"- **{r['key']}** ({r['paper']}): {r['note']}")
    md.append("")
    return {".csv": out.getvalue(), ".md": "\n".join(md)}
