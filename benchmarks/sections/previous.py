"""The bench's section ``previous``: this version against a previous one, in the same
run.

The previous revision (``worktree.resolve_against``) is checked out into a temporary
worktree with a numba cache of its own (its first run compiles, and is left out), and
the two versions' ``chainrun simulate`` processes alternate on the lines of
``Mode.previous_cases`` (this host's speed drifts by several per cent over minutes;
alternating spreads the drift over both): the targets' lines, among them the one whose
target is to be no slower than the previous version (Hertz N = 10^4), met where the
ratio new/old of the medians is at most ``1 + Mode.previous_slack``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

from benchmarks.harness import (ABOUT, ROOT, Context, alternate, config_text, fmt_t,
                                git_commit, log, median, pythonpath, ratio, ratio_text,
                                table, times_text)
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
    slack: float = 0.05               # a no-slower target's allowance over 1

    @staticmethod
    def case_name(c: dict) -> str:
        return f"{c['label']} {c['n']}" + (f" K = {c['k']}" if c.get("k", 1) != 1 else "")

    def verdict(self, c: dict) -> str | None:
        """A no-slower target's verdict on the case ``c``; None for another case."""
        if not c.get("no_slower"):
            return None
        r = c.get("ratio_median")
        if r is None:
            return "NOT MEASURED"
        return ("MET" if r <= 1 + self.slack else "NOT MET") + f" (new/old median {r:.2f})"

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
                rows.append([self.case_name(c),
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
            for c in self.cases:
                verdict = self.verdict(c)
                if verdict is not None:
                    out.append(f"  Target {c['label']} N = {c['n']} no slower than the "
                               f"previous version (new/old median at most "
                               f"{1 + self.slack:g}): {verdict}")
            about = [f"{c['label']}: {c['about']}" for c in self.cases if c.get("about")]
            if about:
                out.append("  Lines: " + "; ".join(about) + ".")
        return out


RESULT = PreviousResult


def run(ctx: Context) -> PreviousResult:
    """This version against the previous one on ``mode.previous_cases``."""
    mode, procs = ctx.mode, ctx.procs
    out = PreviousResult(runs=mode.previous_runs, slack=mode.previous_slack)
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
    for spec in mode.previous_cases:
        log(f"previous: {spec.name}, to the terminal state, "
            f"{mode.previous_runs} runs of each version, alternating")
        text = spec.config("previous")
        jobs = {v: {"text": text, "env": envs[v], "timeout": 900.0} for v in ("new", "old")}
        case = {"label": spec.label, "n": spec.n, "k": spec.k, "alpha": spec.alpha,
                "chain": spec.chain, "top": spec.top, "no_slower": spec.no_slower}
        if spec.label in ABOUT and spec.label not in ("Hertz", "linear"):
            case["about"] = ABOUT[spec.label]
        case.update(alternate(procs, jobs, mode.previous_runs))
        for v in ("new", "old"):
            case[v].pop("diagnostics")
        case["ratio_median"] = ratio(case["new"], case["old"])
        case["ratio_min"] = ratio(case["new"], case["old"], min)
        out.cases.append(case)
