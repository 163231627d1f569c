"""The bench's section ``previous``: this version against a previous one, in the same
run.

The previous revision (``worktree.resolve_against``) is checked out into a temporary
worktree with a numba cache of its own (its first run compiles, and is left out), and
the two versions' ``chainrun simulate`` processes alternate on the targets' paper
lines (this host's speed drifts by several per cent over minutes; alternating spreads
the drift over both).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from benchmarks.harness import (ROOT, Context, alternate, config_text, fmt_t, git_commit,
                                log, median, pythonpath, ratio, ratio_text, table,
                                times_text)
from benchmarks.sections import Result
from benchmarks.worktree import checkout, resolve_against, solver_changes_uncommitted


@dataclass
class PreviousResult(Result):
    """Which revision and why (``resolve_against``), its first run, and per case each
    version's runs (``alternate``) and the ratios new/old of their medians and minima."""

    cases: list = field(default_factory=list)
    runs: int = 0
    commit: str | None = None
    asked: str | None = None
    why: str | None = None
    subject: str | None = None
    new: dict | None = None
    old_first_run: dict | None = None
    error: str | None = None

    def lines(self) -> list[str]:
        if self.commit is None:
            return [f"Previous version: {self.error}"]
        new = self.new or {}
        out = [f"Previous version: {self.commit[:12]} \"{self.subject}\", chosen as "
               f"{self.why}; this version: commit {(new.get('commit') or '?')[:12]}"
               + (" with uncommitted solver changes" if new.get("solver_changes_uncommitted")
                  else "")]
        f = self.old_first_run
        if f and f.get("wall") is not None:
            out.append(f"  Its first run (a numba cache of its own, empty) took "
                       f"{fmt_t(f['wall'])} s (cpu {fmt_t(f['cpu'])} s), "
                       f"{fmt_t(f['warm_wall'])} s warm: left out of the times below.")
        if self.error:
            out.append(f"  {self.error}")
        if self.cases:
            out.append(f"  Whole chainrun simulate processes, K = 1, to the terminal state; "
                       f"{self.runs} runs of each version, alternating new, old, new, old, "
                       "...:")
            rows = []
            for c in self.cases:
                new_w, old_w = c["new"]["walls"], c["old"]["walls"]
                rows.append([f"{c['label']} {c['n']}",
                             fmt_t(min(new_w)) if new_w else "-",
                             fmt_t(median(new_w)) if new_w else "-",
                             fmt_t(min(old_w)) if old_w else "-",
                             fmt_t(median(old_w)) if old_w else "-",
                             ratio_text(c["ratio_median"]), ratio_text(c["ratio_min"])])
            out.append("  " + table(["case", "new min", "new median", "old min", "old median",
                                     "new/old median", "new/old min"], rows)
                       .replace("\n", "\n  "))
            for c in self.cases:
                line = (f"  {c['label']} N = {c['n']}: new {times_text(c['new']['walls'])} s; "
                        f"old {times_text(c['old']['walls'])} s")
                errors = c["new"]["errors"] + c["old"]["errors"]
                out.append(line + (f"  [{errors[0]}]" if errors else ""))
        return out


RESULT = PreviousResult


def run(ctx: Context) -> PreviousResult:
    """This version against the previous one on ``mode.previous_cases``."""
    mode, procs = ctx.mode, ctx.procs
    out = PreviousResult(runs=mode.previous_runs)
    try:
        chosen = resolve_against(ctx.against)
    except ValueError as exc:
        out.error = str(exc)
        log(f"previous: {exc}")
        return out
    out.commit, out.asked, out.why, out.subject = (chosen["commit"], chosen["asked"],
                                                   chosen["why"], chosen["subject"])
    tree = procs.scratch / f"previous-{out.commit[:12]}"
    log(f"previous: {out.commit[:12]} ({out.why}) into {tree}")
    try:
        out.new = {"commit": git_commit(),
                   "solver_changes_uncommitted": solver_changes_uncommitted()}
        with checkout(out.commit, tree):
            envs = {"new": dict(os.environ, PYTHONPATH=pythonpath(ROOT)),
                    "old": dict(os.environ, PYTHONPATH=pythonpath(tree),
                                NUMBA_CACHE_DIR=str(procs.scratch / "numba-previous"))}
            _compare(out, mode, procs, envs)
    except RuntimeError as exc:                   # git failing
        out.error = str(exc)
        log(f"  {exc}")
    return out


def _compare(out: PreviousResult, mode, procs, envs: dict) -> None:
    """The old version's first run, then each case, the versions alternating."""
    warm = config_text("previous-warmup", 50, 1, 1.5, times=[0.0, 10.0])
    log("  old: its first run, compiling into its own numba cache...")
    cold = procs.run(warm, env=envs["old"], timeout=900.0, read_velocity=False)
    again = procs.run(warm, env=envs["old"], timeout=300.0, read_velocity=False)
    out.old_first_run = {"wall": cold.wall, "cpu": cold.cpu, "warm_wall": again.wall,
                         "error": cold.error or again.error}
    if cold.error or again.error:
        out.error = f"the previous version does not run: {cold.error or again.error}"
        log(f"  {out.error}")
        return
    log(f"  first run {fmt_t(cold.wall)} s (cpu {fmt_t(cold.cpu)} s), then "
        f"{fmt_t(again.wall)} s")
    procs.run(warm, env=envs["new"], read_velocity=False)   # this version's cache
    for label, n, alpha in mode.previous_cases:
        log(f"previous: {label} N = {n}, K = 1, to the terminal state, "
            f"{mode.previous_runs} runs of each version, alternating")
        text = config_text(f"previous-{label.lower()}-{n}", n, 1, alpha)
        jobs = {v: {"text": text, "env": envs[v], "timeout": 900.0} for v in ("new", "old")}
        case = {"label": label, "n": n, "alpha": alpha}
        case.update(alternate(procs, jobs, mode.previous_runs))
        for v in ("new", "old"):
            case[v].pop("diagnostics")
        case["ratio_median"] = ratio(case["new"], case["old"])
        case["ratio_min"] = ratio(case["new"], case["old"], min)
        out.cases.append(case)
