"""The gallery's comparison of published numbers with chainrun's, as CSV and Markdown.

The analysis (``chainrun.analysis.gallery_comparison``) decides each row's status and
writes its note; this module only lays the table out.
"""

from __future__ import annotations

import csv
import io

from chainrun.plotting.comparison import _computed, _md_escape

COLUMNS = ("key", "item", "where", "quantity", "published", "computed", "status", "note")


def write(data) -> dict[str, str]:
    t = {c: data.arrays[f"table/{c}"] for c in COLUMNS}
    rows = [{c: t[c][i] for c in COLUMNS} for i in range(len(t["key"]))]
    v = data.values

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([r[c] if c != "computed" else _computed(r[c]) for c in COLUMNS])

    md = [
        "# The gallery's published numbers beside chainrun's",
        "",
        "Each number the gallery's sources print (or the closed form derived here from "
        "them) beside the value chainrun computes from its runs (`make gallery`; pages in "
        "`docs/gallery/`). *agrees*: equal at the printed precision (half a unit of the "
        "last printed digit). *explained*: it differs, and the note says why. *cannot be "
        "checked*: the number could not be read from a source at hand; chainrun's value "
        "is shown alone and counts as nothing. The same table is in "
        "`gallery-comparison.csv`.",
        "",
        f"**{int(v['rows'])} numbers: {int(v['agrees'])} agree, {int(v['explained'])} "
        f"differ with the explanation below, {int(v['cannot_be_checked'])} cannot be "
        f"checked, {int(v['unexplained'])} differ unexplained.**",
        "",
        "| key | item | source | quantity | published | chainrun | status |",
        "|---|---|---|---|---:|---:|---|",
    ]
    for r in rows:
        md.append("| " + " | ".join(_md_escape(x) for x in (
            r["key"], r["item"], r["where"], r["quantity"], r["published"],
            _computed(r["computed"]), r["status"])) + " |")
    md += ["", "## Notes", ""]
    for r in rows:
        if r["note"]:
            md += [f"- **{r['key']}** ({r['status']}): {r['note']}"]
    md.append("")
    return {".csv": out.getvalue(), ".md": "\n".join(md)}
