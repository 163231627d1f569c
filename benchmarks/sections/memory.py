"""The bench's section ``memory``: peak resident memory (max RSS) of a ``chainrun
simulate`` process, N = 10^6 with 200 snapshots and with 2 (the same if snapshots are
streamed); by default until t = 1000, ``--full`` to the terminal state.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from benchmarks.harness import Context, config_text, fmt_t, log
from benchmarks.sections import Result


@dataclass
class MemoryResult(Result):
    """Per snapshot count: the peak RSS (MB), the wall time and any error."""

    n: int = 0
    t_end: float | None = None
    runs: list = field(default_factory=list)

    def lines(self) -> list[str]:
        until = f"t_end = {self.t_end:g}" if self.t_end is not None else "the terminal state"
        out = [f"Peak resident memory of chainrun simulate, N = {self.n}, until {until}:"]
        for r in self.runs:
            out.append(f"  {r['snapshots']:4d} snapshots: {fmt_t(r['maxrss_mb'])} MB, "
                       f"{fmt_t(r['wall'])} s" + (f"  [{r['error']}]" if r["error"] else ""))
        return out


RESULT = MemoryResult


def run(ctx: Context) -> MemoryResult:
    mode, procs = ctx.mode, ctx.procs
    n = mode.memory_n
    t_last = mode.memory_t_end if mode.memory_t_end is not None else 1.25 * n + 20
    out = MemoryResult(n=n, t_end=mode.memory_t_end)
    for count in (200, 2):
        times = np.linspace(0.0, t_last, count)
        log(f"memory: N = {n}, {count} snapshots until t = {t_last:g}"
            + ("" if mode.memory_t_end is not None else " (run to the terminal state)"))
        r = procs.run(config_text(f"memory-{count}", n, 1, 1.5, t_end=mode.memory_t_end,
                                  times=times),
                      timeout=None if mode.full else 600.0, read_velocity=False)
        out.runs.append({"snapshots": count, "maxrss_mb": r.maxrss_mb, "wall": r.wall,
                         "error": r.error})
        log(f"  peak RSS {fmt_t(r.maxrss_mb)} MB, {fmt_t(r.wall)} s {r.error or ''}")
    return out
