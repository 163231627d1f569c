"""The bench's section ``targets``: the timed targets as whole ``chainrun simulate``
processes, warm cache, to the terminal state, each against its limit (``Mode.targets``:
issue 34's, a cascade of collisions, the random line, the damped line, the paper's
Hertz N = 10^6 and linear N = 10^5). Each runs several times and every time is kept:
the machine's speed moves, and a target met only by the fastest run is not met. Each
run's events (the run file's diagnostics) give its wall time per event. A run over
``Mode.target_over`` times its limit is not repeated: the target is not met whatever
the others would give. The targets read as "no slower than the previous version" are
measured by the section ``previous`` and named here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.harness import ABOUT, Context, fmt_t, log
from benchmarks.sections import Result


@dataclass
class Target:
    """One target's runs: wall and CPU seconds and events of each, and whether all are
    within its limit."""

    label: str
    n: int
    alpha: float | None
    limit: float
    walls: list = field(default_factory=list)
    cpus: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    runs_within_limit: int = 0
    met: bool = False
    k: int = 1
    chain: dict | None = None
    top: dict | None = None
    events: list = field(default_factory=list)       # each run's, from its run file
    stopped: str | None = None                       # why fewer runs than asked
    diagnostics: list = field(default_factory=list)  # each run's (DIAGNOSTICS)

    @property
    def name(self) -> str:
        return f"{self.label} N = {self.n}" + (f", K = {self.k}" if self.k != 1 else "")

    def per_event_us(self) -> list[float]:
        """Each run's wall microseconds per event (runs whose events are known)."""
        return [1e6 * w / e for w, e in zip(self.walls, self.events) if e]


@dataclass
class TargetsResult(Result):
    targets: list = field(default_factory=list)       # of Target
    no_slower: list = field(default_factory=list)     # names of section previous's targets

    @classmethod
    def from_json(cls, data: dict) -> "TargetsResult":
        return cls(targets=[Target(**t) for t in data["targets"]],
                   no_slower=list(data.get("no_slower", [])))

    def lines(self) -> list[str]:
        out = ["Targets: whole chainrun simulate process (start-up, imports, numba cache "
               "load, solver, HDF5 file), warm cache, to the terminal state; every run's "
               "wall time, then the events of the runs (the run file's diagnostics), the "
               "whole process's wall time per event (start-up included), and the first "
               "run's steps and widest window:"]
        for t in self.targets:
            times = ", ".join(fmt_t(w) for w in t.walls) or "-"
            verdict = (f"met in {t.runs_within_limit} of {len(t.walls)} runs"
                       if t.walls else "no run finished")
            if t.stopped:
                verdict += f" ({t.stopped})"
            if t.errors:
                verdict += f"  [{t.errors[0]}]"
            line = (f"  {t.name}: {times} s (limit {t.limit:g} s): "
                    + ("MET, " if t.met else "NOT MET, ") + verdict)
            events = [e for e in t.events if e]
            if events:
                line += f"; {_span(events, '{:,}')} events"
                us = t.per_event_us()
                if us:
                    line += f", {_span(us, _us)} us per event"
            d = t.diagnostics[0] if t.diagnostics else {}
            if d.get("steps") is not None:
                line += (f"; first run: {d['steps']:,} steps ({d['rejected_steps']:,} "
                         f"rejected), window up to {d['max_window']:,} balls")
            out.append(line)
        for name in self.no_slower:
            out.append(f"  {name}: no slower than the previous version (new/old in the "
                       "same run: section previous)")
        kinds = [k for k in ABOUT if any(t.label == k for t in self.targets)]
        if kinds:
            out.append("  Lines: " + "; ".join(f"{k}: {ABOUT[k]}" for k in kinds) + ".")
        return out

    def get(self, label: str, n: int | None = None) -> Target | None:
        return next((t for t in self.targets
                     if t.label == label and (n is None or t.n == n)), None)


#: The run file's diagnostics a target keeps of each run.
DIAGNOSTICS = ("events", "steps", "rejected_steps", "max_window", "closed_form_collisions",
               "outcome", "end_time")


def _us(x: float) -> str:
    return f"{x:,.0f}" if x >= 10 else f"{x:.1f}"


def _span(xs, fmt) -> str:
    fmt = fmt.format if isinstance(fmt, str) else fmt
    lo, hi = fmt(min(xs)), fmt(max(xs))
    return lo if lo == hi else f"{lo}-{hi}"


RESULT = TargetsResult


def run(ctx: Context) -> TargetsResult:
    mode, procs = ctx.mode, ctx.procs
    out = TargetsResult(no_slower=[c.name for c in mode.previous_cases if c.no_slower])
    for case in mode.targets:
        limit = case.limit
        log(f"targets: {case.name}, to the terminal state, as a process "
            f"(limit {limit:g} s), {mode.target_runs} runs")
        t = Target(case.label, case.n, case.alpha, limit, k=case.k, chain=case.chain,
                   top=case.top)
        for i in range(mode.target_runs):
            r = procs.run(case.config("target"), timeout=max(mode.target_timeout, 10 * limit),
                          read_velocity=False, read_diagnostics=True)
            if r.error:
                t.errors.append(r.error)
                log(f"  {r.error}")
                break
            d = r.diagnostics or {}
            if d.get("outcome") != "terminal":
                t.errors.append(f"ended {d.get('outcome')} at t = {d.get('end_time')}, not in "
                                "the terminal state")
                log(f"  {t.errors[-1]}")
                break
            t.walls.append(r.wall)
            t.cpus.append(r.cpu)
            t.events.append(d.get("events"))
            t.diagnostics.append({k: d.get(k) for k in DIAGNOSTICS})
            log(f"  {fmt_t(r.wall)} s (cpu {fmt_t(r.cpu)} s, peak RSS {fmt_t(r.maxrss_mb)} MB"
                f", {d.get('events')} events)")
            if r.wall > mode.target_over * limit and i + 1 < mode.target_runs:
                t.stopped = f"not repeated: over {mode.target_over:g} x the limit"
                break
        t.runs_within_limit = sum(w <= limit for w in t.walls)
        t.met = bool(t.walls) and not t.errors and t.runs_within_limit == len(t.walls)
        out.targets.append(t)
    return out
