"""The gallery's comparison of published numbers with chainrun's, as CSV and Markdown.

The analysis (``chainrun.analysis.gallery_comparison``) decides each row's status and
writes its note; this module only lays the table out, each computed value with no
digit beyond its spread and the spread beside it.
"""

from __future__ import annotations

import csv
import io
import math

from chainrun.plotting.comparison import _computed, _md_escape, _spread

COLUMNS = ("key", "item", "where", "quantity", "published", "computed", "spread", "status",
           "note")


def write(data) -> dict[str, str]:
    names = [c for c in COLUMNS if f"table/{c}" in data.arrays]
    t = {c: data.arrays[f"table/{c}"] for c in names}
    rows = [{"spread": math.nan} | {c: t[c][i] for c in names} for i in range(len(t["key"]))]
    v = data.values

    def cell(r, c):
        if c == "computed":
            return _computed(r[c], r["spread"])
        return _spread(r[c]) if c == "spread" else r[c]

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([cell(r, c) for c in COLUMNS])

    md = [
        "# The gallery's published numbers beside chainrun's",
        "",
        "Each number the gallery's sources print (or the closed form derived here from "
        "them) beside the value chainrun computes from its runs (`make gallery`; pages in "
        "`docs/gallery/`). *agrees*: equal at the printed precision (half a unit of the "
        "last printed digit). *explained*: it differs, and the note says why. *cannot be "
        "checked*: the number could not be read from a source at hand; chainrun's value "
        "is shown alone and counts as nothing. *spread*: how far chainrun's value moves "
        "when its runs are made again at a tenth of their tolerance (`make gallery` "
        "makes both and derives every number from each); the value shows no digit "
        "beyond it, and agreement is judged within it (0: the two agree to the last "
        "bit). The same table is in `gallery-comparison.csv`.",
        "",
        f"**{int(v['rows'])} numbers: {int(v['agrees'])} agree"
        + (f" ({int(v['by_spread'])} only within chainrun's spread)"
           if v.get("by_spread") else "")
        + f", {int(v['explained'])} "
        f"differ with the explanation below, {int(v['cannot_be_checked'])} cannot be "
        f"checked, {int(v['unexplained'])} differ unexplained.**",
        "",
        "| key | item | source | quantity | published | chainrun | spread | status |",
        "|---|---|---|---|---:|---:|---:|---|",
    ]
    for r in rows:
        md.append("| " + " | ".join(_md_escape(x) for x in (
            r["key"], r["item"], r["where"], r["quantity"], r["published"],
            cell(r, "computed"), cell(r, "spread"), r["status"])) + " |")
    md += ["", "## Notes", ""]
    for r in rows:
        if r["note"]:
            md += [f"- **{r['key']}** ({r['status']}): {r['note']}"]
    md.append("")
    return {".csv": out.getvalue(), ".md": "\n".join(md)}
