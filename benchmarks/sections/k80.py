"""The bench's section ``k80``: N = 2000, K = 80, Hertz, to the terminal state
in-process (``--full``: as a whole process too), with how many of its collisions were
taken in closed form. Where this cascade ends is steered by rounding:
``benchmarks.cascade`` measures how far.
"""

from __future__ import annotations

from dataclasses import dataclass

from benchmarks.harness import Context, chainrun_point, config_text, fmt_t, log
from benchmarks.sections import Result

N, K = 2000, 80


@dataclass
class K80Result(Result):
    """The in-process run (its fastest time, seconds) and its counts, or its error."""

    time: float | None = None
    times: list | None = None
    end_time: float | None = None
    events: int | None = None
    steps: int | None = None
    closed_form: int | None = None
    outcome: str | None = None
    max_window: int | None = None
    energy_error: float | None = None
    momentum_error: float | None = None
    process_time: float | None = None
    process_error: str | None = None
    error: str | None = None

    def lines(self) -> list[str]:
        head = f"N = {N}, K = {K}, Hertz, to the terminal state: "
        if self.time is None:
            return [head + str(self.error)]
        return [head + f"{fmt_t(self.time)} s in-process, {fmt_t(self.process_time)} s as "
                f"a process (--full); terminal t = {self.end_time:.6g}, {self.events} "
                f"events, {self.steps} steps, {self.closed_form or 0} collisions in "
                "closed form"]


RESULT = K80Result


def run(ctx: Context) -> K80Result:
    mode, procs = ctx.mode, ctx.procs
    log(f"k80: N = {N}, K = {K}, Hertz, to the terminal state "
        f"(limit {fmt_t(mode.k80_timeout)} s)")
    p = chainrun_point(N, K, 1.5, timeout=mode.k80_timeout)
    p.pop("final_velocity", None)
    p.pop("n")
    out = K80Result(**p)
    if out.time is None:
        log(f"  {out.error}")
        return out
    if mode.k80_process:
        proc = procs.run(config_text("k80", N, K, 1.5), timeout=mode.k80_timeout * 3 + 60,
                         read_velocity=False)
        out.process_time, out.process_error = proc.wall, proc.error
    log(f"  {fmt_t(out.time)} s in-process, {fmt_t(out.process_time)} s process, "
        f"terminal t = {out.end_time:.6g}, {out.events} events, {out.steps} steps, "
        f"{out.closed_form} collisions in closed form")
    return out
