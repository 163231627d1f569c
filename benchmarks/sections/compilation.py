"""The bench's section ``compile``: the first run's numba compilation and the warm
start-up, with numba's own start-up beside it.

``chainrun simulate`` runs a small config with an empty ``NUMBA_CACHE_DIR`` (cold),
then again with that cache (warm); compilation is cold - warm, in wall and CPU seconds.
numba's own start-up is a process that loads one cached one-line numba function: no
process that runs cached numba code starts faster.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.harness import Context, config_text, fmt_t, log, median
from benchmarks.sections import Result

CASE = "N=250, K=1, alpha=1.5, t_end=50, 3 snapshots"


@dataclass
class CompileResult(Result):
    """Cold and warm runs of one small config, and numba's floor (seconds)."""

    case: str = CASE
    cold_wall: float | None = None
    cold_cpu: float | None = None
    warm_wall: float | None = None
    warm_cpu: float | None = None
    warm_walls: list = field(default_factory=list)
    error: str | None = None
    compile_wall: float | None = None
    compile_cpu: float | None = None
    numba_floor: list = field(default_factory=list)

    def lines(self) -> list[str]:
        out = ["First-run numba compilation (chainrun simulate, empty NUMBA_CACHE_DIR, "
               f"{self.case}):",
               f"  cold {fmt_t(self.cold_wall)} s (cpu {fmt_t(self.cold_cpu)} s), warm "
               f"{fmt_t(self.warm_wall)} s (cpu {fmt_t(self.warm_cpu)} s): compilation "
               f"{fmt_t(self.compile_wall)} s wall, {fmt_t(self.compile_cpu)} s cpu"
               + (f"  [{self.error}]" if self.error else "")]
        if self.numba_floor:
            walls = self.numba_floor
            out.append(f"  numba's own start-up, a process loading one cached one-line "
                       f"function: {fmt_t(min(walls))} s at best, median "
                       f"{fmt_t(median(walls))} s (the warm run's floor)")
        return out


RESULT = CompileResult


def run(ctx: Context) -> CompileResult:
    """Cold (fresh numba cache) and warm runs of the same small config, as processes."""
    procs = ctx.procs
    log("compile: chainrun simulate with an empty numba cache (the first run)...")
    cache = Path(tempfile.mkdtemp(prefix="numba-cold-", dir=procs.scratch))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    text = config_text("compile", 250, 1, 1.5, t_end=50.0, times=[0.0, 25.0, 50.0])
    cold = procs.run(text, env=env)
    warm, walls = procs.timed(text, env=env)
    shutil.rmtree(cache, ignore_errors=True)
    out = CompileResult(cold_wall=cold.wall, cold_cpu=cold.cpu, warm_wall=warm.wall,
                        warm_cpu=warm.cpu, warm_walls=walls, error=cold.error or warm.error)
    if cold.wall is not None and warm.wall is not None:
        out.compile_wall = cold.wall - warm.wall
        out.compile_cpu = cold.cpu - warm.cpu
    log(f"  cold {fmt_t(cold.wall)} s (cpu {fmt_t(cold.cpu)} s), warm {fmt_t(warm.wall)} s")
    out.numba_floor = numba_floor(procs.scratch)
    log(f"  numba's own start-up: {fmt_t(min(out.numba_floor))} s at best")
    return out


_FLOOR_SCRIPT = """
import numba
from numba.np import linalg
def no_blas():
    raise ImportError
linalg.ensure_blas = no_blas  # numba's BLAS probe fails at once, as while chainrun loads
@numba.njit(cache=True)
def f(x):
    return x + 1.0
f(1.0)
"""


def numba_floor(scratch: Path, runs: int = 5) -> list[float]:
    """Wall times of a Python process that loads one cached one-line numba function
    and calls it: what any process running cached numba code pays before its own work
    (the warm start-up's floor). numba's probe for scipy's BLAS fails at once there, as
    it does while chainrun loads its kernels (``_jit._without_blas_probe``)."""
    folder = Path(tempfile.mkdtemp(prefix="numba-floor-", dir=scratch))
    script = folder / "floor.py"
    script.write_text(_FLOOR_SCRIPT)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(folder / "cache"))
    subprocess.run([sys.executable, str(script)], env=env, check=True)  # compiles, caches
    walls = []
    for _ in range(runs):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, str(script)], env=env, check=True)
        walls.append(time.perf_counter() - t0)
    shutil.rmtree(folder, ignore_errors=True)
    return walls
