"""The bench's measured numbers, kept once: ``benchmarks/results.json`` and what is
written from it.

Each section run by ``benchmarks.run`` replaces its own entry of the results file (its
result's JSON, with the commit, date, mode, machine, load average and wall time of its
run), so ``--only SECTION`` refreshes that section and keeps the others. From the file
come ``benchmarks/results.md`` (every section's part of the report) and the block of
README.md between ``BEGIN`` and ``END`` (the numbers the README quotes); neither is
edited by hand, and a test checks that both are what the file renders.
"""

from __future__ import annotations

import json
import os
import textwrap
from pathlib import Path

from benchmarks.harness import ROOT, fmt_e, fmt_t
from benchmarks.sections import SECTIONS, module

RESULTS = ROOT / "benchmarks" / "results.json"
README = ROOT / "README.md"
BEGIN = ("<!-- bench:begin (written by `make bench` from benchmarks/results.json; "
         "not by hand) -->")
END = "<!-- bench:end -->"


def markdown_path(path: Path) -> Path:
    """The rendered file beside a results file: results.json -> results.md."""
    return path.with_suffix(".md")


def entry(result, *, meta: dict, date: str, load_start, load_end, wall: float,
          notes: list) -> dict:
    """A section's entry: its result and the circumstances of its run (``date``: when
    it started; ``meta``: the bench run's commit, mode, machine and versions)."""
    machine = meta["machine"]
    return {"commit": meta["git_commit"], "date": date, "mode": meta["mode"],
            "machine": {k: machine.get(k) for k in ("cpu", "machine", "cpus", "memory_gb")},
            "versions": meta["versions"], "load_start": list(load_start),
            "load_end": list(load_end), "wall": wall, "notes": list(notes),
            "result": result.to_json()}


def load(path: Path = RESULTS) -> dict:
    if not path.exists():
        return {"sections": {}}
    return json.loads(path.read_text())


def update(path: Path, name: str, section_entry: dict) -> dict:
    """Replace the entry of the section ``name`` in the results file at ``path`` (the
    others kept) and write the file and its rendering beside it; the new contents."""
    data = load(path)
    data["sections"][name] = section_entry
    data["sections"] = {k: data["sections"][k] for k in SECTIONS if k in data["sections"]}
    _write(path, json.dumps(data, indent=1) + "\n")
    _write(markdown_path(path), render(data))
    return data


def _write(path: Path, text: str) -> None:
    partial = path.with_name(path.name + ".partial")
    partial.write_text(text)
    os.replace(partial, path)


def result_of(data: dict, name: str):
    """The typed result of the section ``name`` in the results ``data``, or None."""
    got = data["sections"].get(name)
    return None if got is None else module(name).RESULT.from_json(got["result"])


def _circumstances(e: dict) -> str:
    m = e["machine"]
    return (f"commit {(e['commit'] or '?')[:12]}, {e['date']}, {e['mode']} mode; "
            f"{m.get('cpu') or m.get('machine')}, {m.get('cpus')} cores, "
            f"{m.get('memory_gb')} GB; load average {e['load_start'][0]:.1f} at the start, "
            f"{e['load_end'][0]:.1f} at the end; {e['wall']:.0f} s")


def render(data: dict) -> str:
    """``results.md``: each section's part of the report, with its circumstances."""
    out = ["# What `make bench` measured", "",
           "Written by the bench from `results.json`, not by hand: each section as it last "
           "ran (`python -m benchmarks.run --only SECTION` runs one again and keeps the "
           "others). The machine may be shared, and its speed moves with its load: each "
           "section gives the load average during its run. `benchmarks/README.md` says "
           "what each section and column means."]
    for name, e in data["sections"].items():
        out += ["", f"## {name}", "", _circumstances(e) + ".", "", "```"]
        out += result_of(data, name).lines()
        out += [f"Note: {n}" for n in e["notes"]]
        out += ["```"]
    return "\n".join(out) + "\n"


def _balls(n: int) -> str:
    k = len(str(n)) - 1
    return f"10^{k} balls" if n >= 10_000 and n == 10**k else f"{n} balls"


def _times(ratio: float) -> str:
    """A speed-up as text: 2,404x, 91x, 6.6x."""
    return f"{ratio:,.0f}x" if ratio >= 10 else f"{ratio:.2g}x"


def _span(xs) -> str:
    lo, hi = fmt_t(min(xs)), fmt_t(max(xs))
    return lo if lo == hi else f"{lo}-{hi}"


def readme_block(data: dict) -> str:
    """The README's measured numbers, from the results ``data``: the peers' largest
    case, the targets, the compilation and the start-up, and where they come from."""
    sentences, used = [], []
    peers = result_of(data, "peers")
    case = peers.largest() if peers else None
    if case:
        used.append("peers")
        tools = case["tools"]
        cr = tools["chainrun"]
        others = []
        for name, label in (("scipy", "scipy's DOP853"), ("heyoka", "heyoka")):
            t = tools.get(name)
            if t is None:
                others.append(f"{label} (not installed)")
            elif t.get("time") is not None:
                others.append(f"{fmt_t(t['time'])} s for {label}")
            elif t.get("skipped"):
                others.append(f"{label} (skipped: {t['skipped']})")
            else:
                others.append(f"{label} (failed: {t.get('error')})")
        sentences.append(
            f"A Hertz line of {_balls(case['n'])} (K = 1, until t = {case['t_stop']:g}) "
            f"takes {fmt_t(cr['time'])} s in the solver ({fmt_t(cr['process_time'])} s for "
            f"the whole `chainrun simulate` process), against {' and '.join(others)} on the "
            f"same line, with final velocities within {fmt_e(cr['error_vs_reference'])} of "
            "the converged ones.")
    targets = result_of(data, "targets")
    if targets:
        used.append("targets")
        timed = [t for t in targets.targets if t.walls]
        parts = [f"a {t.label} line of {_balls(t.n)}"
                 + (f" (K = {t.k})" if t.k != 1 else "")
                 + f" in {_span(t.walls)} s (limit {t.limit:g} s)" for t in timed]
        if parts:
            counts = sorted({len(t.walls) for t in timed})
            runs = (f"{counts[0]} runs each" if len(counts) == 1 else
                    f"{'-'.join(str(c) for c in (counts[0], counts[-1]))} runs each: a run "
                    "far over its limit is not repeated")
            sentences.append(f"To the terminal state as a whole process ({runs}): "
                             f"{', '.join(parts[:-1])}{', and ' if len(parts) > 1 else ''}"
                             f"{parts[-1]}.")
    lammps = result_of(data, "lammps")
    costs = [c for c in (lammps.cost or []) if c.get("ratio") and c.get("target")] \
        if lammps else []
    if costs:
        used.append("lammps")
        parts = [f"{_times(c['ratio'])} on the {c['kind']} line of {_balls(c['n'])} "
                 f"(target {c['target']:g}x{'' if c['met'] else ', not met'}"
                 f"{'' if c['lammps'].get('measured') else '; LAMMPS extrapolated'})"
                 for c in costs]
        sentences.append(
            "Against LAMMPS on lines of steel beads, at the time step where its largest "
            f"velocity error is {lammps.target_error:g} of the impact speed, chainrun "
            f"(exact to rounding) is faster by {' and '.join(parts)}, whole processes.")
    comp = result_of(data, "compile")
    if comp and comp.compile_wall is not None:
        used.append("compile")
        sentences.append(
            f"The first run compiles the solver in {comp.compile_wall:.0f} s "
            f"({comp.compile_cpu:.0f} s of CPU); a warm `chainrun simulate` of a small line "
            f"then takes {fmt_t(comp.warm_wall)} s, of which numba's own start-up is "
            f"{_span(comp.numba_floor)} s (a process loading one cached one-line function).")
    if not used:
        return "Nothing measured yet: `make bench` writes these numbers."
    entries = [data["sections"][name] for name in used]
    loads = [x for e in entries for x in (e["load_start"][0], e["load_end"][0])]
    load = f"{min(loads):.1f}" + ("" if f"{min(loads):.1f}" == f"{max(loads):.1f}"
                                  else f" to {max(loads):.1f}")
    m = entries[0]["machine"]
    commits = sorted({(e["commit"] or "?")[:12] for e in entries})
    dates = sorted({e["date"][:10] for e in entries})
    sentences.append(
        f"Measured on {m.get('cpu') or m.get('machine')} ({m.get('cpus')} cores), shared, "
        f"at load average {load} ({', '.join(dates)}; "
        f"commit {', '.join(commits)}; sections {', '.join(used)} of "
        "[benchmarks/results.md](benchmarks/results.md)); its speed moves with the load.")
    return textwrap.fill(" ".join(sentences), width=88, break_long_words=False,
                         break_on_hyphens=False)


def readme_text(text: str, data: dict) -> str:
    """README.md's text with the block between BEGIN and END written from ``data``."""
    head, sep, rest = text.partition(BEGIN)
    _, sep2, tail = rest.partition(END)
    if not sep or not sep2:
        raise ValueError(f"README.md has no block between {BEGIN!r} and {END!r}")
    return head + BEGIN + "\n" + readme_block(data) + "\n" + END + tail


def rewrite_readme(data: dict, path: Path = README) -> None:
    text = path.read_text()
    new = readme_text(text, data)
    if new != text:
        _write(path, new)
