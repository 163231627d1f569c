"""The comparison of every printed number with chainrun's value, as CSV and Markdown.

The analysis (``chainrun.analysis.comparison``) decides agreement and writes the notes;
this module only lays the table out.
"""

from __future__ import annotations

import csv
import io

COLUMNS = ("key", "where", "quantity", "paper", "computed", "agrees", "rule", "note")


def _computed(value: float) -> str:
    if value != value:   # NaN: no value
        return "—"
    if float(value).is_integer() and abs(value) < 1e6:
        return str(int(value))
    return f"{value:.6g}"


def _rows(data):
    t = {c: data.arrays[f"table/{c}"] for c in COLUMNS}
    for i in range(len(t["key"])):
        yield {c: t[c][i] for c in COLUMNS}


def _md_escape(text: str) -> str:
    return str(text).replace("|", "\\|")


def write(data) -> dict[str, str]:
    rows = list(_rows(data))
    v = data.values

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([r["key"], r["where"], r["quantity"], r["paper"], _computed(r["computed"]),
                    "true" if r["agrees"] else "false", r["rule"], r["note"]])

    md = [
        "# The paper's numbers beside chainrun's",
        "",
        "Every number printed in Hinch & Saint-Jean, *The fragmentation of a line of balls by "
        "an impact*, from the abstract to section 5d, with the value chainrun computes from "
        "its runs (or from the paper's theory, where the paper derives it). *agrees* means "
        "equal at the printed precision (half a unit of the last printed digit), unless the "
        "rule says otherwise: *exact* for fractions and counts, *between* / *below* for "
        "printed bounds. Regenerate with `make figures`; the same table is in "
        "`paper-comparison.csv`.",
        "",
        f"**{int(v['rows'])} numbers: {int(v['agreeing'])} agree, "
        f"{int(v['explained'])} disagree with the explanation below, "
        f"{int(v['unexplained'])} disagree unexplained.**",
        "",
        "| key | where | quantity | paper | computed | agrees |",
        "|---|---|---|---:|---:|:---:|",
    ]
    for r in rows:
        mark = "yes" if r["agrees"] else f"**no** ([note](#{r['key'].replace('.', '')}))"
        md.append(f"| {r['key']} | {_md_escape(r['where'])} | {_md_escape(r['quantity'])} | "
                  f"{_md_escape(r['paper'])} | {_computed(r['computed'])} | {mark} |")
    md += ["", "## Disagreements and their explanations", ""]
    for r in rows:
        if not r["agrees"]:
            md += [f"### {r['key']}", "",
                   f"{r['where']}, {r['quantity']}: the paper prints **{r['paper']}**, "
                   f"chainrun computes **{_computed(r['computed'])}**.", "",
                   r["note"] or "UNEXPLAINED.", ""]
    md += ["## How each value is computed", ""]
    for r in rows:
        if r["agrees"] and r["note"]:
            md.append(f"- **{r['key']}** ({r['paper']}): {r['note']}")
    md.append("")
    return {".csv": out.getvalue(), ".md": "\n".join(md)}
