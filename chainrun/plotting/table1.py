"""Table 1: the final velocities of a line of five spheres, as Markdown and CSV.

Values are printed with as many decimals as the paper prints in the same cell; cells
where chainrun's value differs from the printed one at that precision are marked and
the printed value given beneath the table.
"""

from __future__ import annotations

import csv
import io


def _decimals(text: str) -> int:
    return len(text.split(".")[1]) if "." in text else 0


def write(data) -> dict[str, str]:
    velocity = data.arrays["table/velocity"]
    paper = data.arrays["table/paper"]
    ks = [int(k) for k in data.arrays["table/k"]]
    rows, cols = velocity.shape

    md = ["# Table 1. The final velocities of a line of five spheres", "",
          "Hertz contacts (alpha = 3/2); the columns are for different numbers K of impacting "
          "spheres. Computed by chainrun (`configs/table1.toml`), printed with the paper's "
          "digits.", "",
          "| n | " + " | ".join(f"K = {k}" for k in ks) + " |",
          "|---:|" + "---:|" * cols]
    footnotes = []
    for i in range(rows):
        cells = []
        for j in range(cols):
            text = f"{velocity[i, j]:.{_decimals(str(paper[i, j]))}f}"
            if text != paper[i, j]:
                footnotes.append(f"n = {i + 1}, K = {ks[j]}: the paper prints {paper[i, j]}; "
                                 f"chainrun's value is {velocity[i, j]:.6f}.")
                text += f" [{len(footnotes)}]"
            cells.append(text)
        md.append(f"| {i + 1} | " + " | ".join(cells) + " |")
    if footnotes:
        md += ["", "Differences from the printed table (explained in "
               "`results/paper-comparison.md`):", ""]
        md += [f"[{i + 1}] {note}" for i, note in enumerate(footnotes)]
    md.append("")

    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(["n", "K", "computed", "paper"])
    for i in range(rows):
        for j in range(cols):
            w.writerow([i + 1, ks[j], f"{velocity[i, j]:.8f}", paper[i, j]])
    return {".md": "\n".join(md), ".csv": out.getvalue()}
