"""The bench's section ``targets``: the timed targets as whole ``chainrun simulate``
processes, warm cache, K = 1, to the terminal state (Hertz N = 10^6 within 10 s,
linear N = 10^5 within 30 s). Each runs several times and every time is kept: the
machine's speed moves, and a target met only by the fastest run is not met.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.harness import Context, config_text, fmt_t, log
from benchmarks.sections import Result


@dataclass
class Target:
    """One target's runs: wall and CPU seconds of each, and whether all are within."""

    label: str
    n: int
    alpha: float
    limit: float
    walls: list = field(default_factory=list)
    cpus: list = field(default_factory=list)
    errors: list = field(default_factory=list)
    runs_within_limit: int = 0
    met: bool = False


@dataclass
class TargetsResult(Result):
    targets: list = field(default_factory=list)       # of Target

    @classmethod
    def from_json(cls, data: dict) -> "TargetsResult":
        return cls(targets=[Target(**t) for t in data["targets"]])

    def lines(self) -> list[str]:
        out = ["Targets: whole chainrun simulate process (start-up, imports, numba cache "
               "load, solver, HDF5 file), K = 1, to the terminal state:"]
        for t in self.targets:
            times = ", ".join(fmt_t(w) for w in t.walls) or "-"
            verdict = (f"met in {t.runs_within_limit} of {len(t.walls)} runs"
                       if t.walls else "no run finished")
            if t.errors:
                verdict += f"  [{t.errors[0]}]"
            out.append(f"  {t.label} N = {t.n}: {times} s (limit {t.limit:g} s): "
                       + ("MET, " if t.met else "NOT MET, ") + verdict)
        return out

    def get(self, label: str) -> Target | None:
        return next((t for t in self.targets if t.label == label), None)


RESULT = TargetsResult


def run(ctx: Context) -> TargetsResult:
    mode, procs = ctx.mode, ctx.procs
    out = TargetsResult()
    for label, n, alpha, limit in mode.targets:
        log(f"targets: {label} N = {n}, K = 1, to the terminal state, as a process "
            f"(limit {limit:g} s), {mode.target_runs} runs")
        t = Target(label, n, alpha, limit)
        for _ in range(mode.target_runs):
            r = procs.run(config_text(f"target-{label.lower()}-{n}", n, 1, alpha),
                          timeout=10 * limit + 60, read_velocity=False)
            if r.error:
                t.errors.append(r.error)
                log(f"  {r.error}")
                break
            t.walls.append(r.wall)
            t.cpus.append(r.cpu)
            log(f"  {fmt_t(r.wall)} s (cpu {fmt_t(r.cpu)} s, peak RSS {fmt_t(r.maxrss_mb)} MB)")
        t.runs_within_limit = sum(w <= limit for w in t.walls)
        t.met = bool(t.walls) and not t.errors and t.runs_within_limit == len(t.walls)
        out.targets.append(t)
    return out
