"""``make bench``: chainrun against its peers on the cases of issue 6, in one run.

This module owns the benchmark harness: it runs chainrun (as a whole ``chainrun
simulate`` process and in-process) and the peers of ``benchmarks.peers`` on the same
cases, checks that they agree to their accuracy, fits how their time grows with N,
and prints one report, also written as JSON to ``results/bench/`` so that runs can
be compared over time. See ``benchmarks/README.md`` for what each column means.

Sections (each bounded in time; ``--full`` lifts the bounds for the largest cases):

1. compile: the first run's numba compilation (a fresh ``NUMBA_CACHE_DIR``).
2. peers: Hertz line, K = 1, until t = 1.25 N + 20, N = 250, 1000, 4000; errors of
   the final velocities against chainrun at rtol = 1e-14 to the same time; the
   agreement check.
3. scaling: Hertz N = 250 ... 10^6 and linear N = 100 ... 10^5, to the terminal
   state; the fitted exponent of time versus N for each tool.
4. targets: the timed targets as whole ``chainrun simulate`` processes, each run
   three times: Hertz N = 10^6 and linear N = 10^5, K = 1, to the terminal state,
   against their limits (10 s and 30 s).
5. k80: N = 2000, K = 80, Hertz, to the terminal state.
6. memory: peak resident memory of ``chainrun simulate``, N = 10^6, 200 snapshots
   (and 2, to show it does not depend on their number).
7. general: the paper's Hertz line against a random one (masses and stiffnesses
   uniform in [1, 10), fixed seeds), K = 1, to the terminal state, as processes, and
   the ratio (the requirement: within 2x at N = 10^6); a random-line size predicted
   over its cap is skipped. The steel line in SI units against the paper's, N = 10^5.
8. previous: this version against a previous one (``--against REV``; by default the
   solver before its latest change), checked out into a temporary git worktree, on
   Hertz N = 10^4 and 10^6 and linear N = 10^5, the two versions' runs alternating.
9. lammps: chainrun against LAMMPS (optional) on lines of steel spheres, elastic and
   damped: two-ball checks and restitutions, accuracy against the time step and rtol
   (N = 20), and whole-process times at N = 2000, 10^4 (elastic) and 3000 (damped)
   (``benchmarks.against_lammps``).

Examples::

    python -m benchmarks.run                 # default, 13-18 minutes
    python -m benchmarks.run --full          # everything, the largest cases too
    python -m benchmarks.run --only peers scaling
    python -m benchmarks.run --only previous --against main~3
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import platform
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from benchmarks.peers import PeerResult, PeerUnavailable

ROOT = Path(__file__).resolve().parents[1]
SECTIONS = ("compile", "peers", "scaling", "targets", "k80", "memory", "general",
            "previous", "lammps")

#: The accuracy each tool claims for the final velocities (max abs error, paper
#: units): chainrun's target in issue 6, the scipy and heyoka settings' measured
#: accuracy with a margin, and the paper's RK4 at dt = 0.02 (about 1e-7).
ACCURACY = {"chainrun": 1e-9, "chainrun-cli": 1e-9, "scipy": 1e-9, "heyoka": 1e-9,
            "rk4": 1e-6}
#: rtol of the converged chainrun run the errors are measured against.
REFERENCE_RTOL = 1e-14
#: Runs shorter than this (seconds) are repeated and the minimum is reported.
SHORT = 5.0
#: The same for the points of the scaling series.
SERIES_SHORT = 2.0

#: The general section's random line: masses and stiffnesses uniform in [1, 10) (ratios
#: up to 10), with fixed seeds, so that every bench runs the same line.
RANDOM_LINE = {"mass": {"random": "uniform", "low": 1.0, "high": 10.0, "seed": 1},
               "stiffness": {"random": "uniform", "low": 1.0, "high": 10.0, "seed": 2}}
#: Its steel line in SI units: beads of one inch, the first striking at 0.5 m/s.
SI_LINE = {"speed": 0.5, "diameter": 0.0254, "material": "steel"}
#: The requirement on the random line: at most this many times the paper's line's time,
#: at the general section's largest N.
GENERAL_LIMIT = 2.0
#: The environment variable naming the previous section's revision (as --against does).
AGAINST_ENV = "CHAINRUN_BENCH_AGAINST"
#: The default previous version is the solver before the latest change under this path.
SOLVER_PATH = "chainrun/solver"


@dataclass
class Mode:
    """The sizes and time limits of one benchmark run."""

    full: bool
    peers_n: tuple = (250, 1000, 4000)
    scipy_max_n: int = 4000
    peers_cap: float = 180.0          # a peer whose predicted time is above is skipped
    hertz_n: tuple = (250, 1000, 4000, 16_000, 64_000, 250_000, 1_000_000)
    linear_n: tuple = (100, 300, 1000, 3000, 10_000, 30_000, 100_000)
    hertz_budget: float = 120.0       # seconds of chainrun time in the Hertz series
    linear_budget: float = 60.0
    linear_peer_n: tuple = (100, 300, 1000)
    peer_point_cap: float = 40.0      # a peer's predicted time above which N stops
    k80_timeout: float = 600.0
    k80_process: bool = False         # also time it as a whole process (as long again)
    memory_t_end: float | None = 1000.0
    memory_n: int = 1_000_000
    # (label, N, alpha, limit in seconds): whole processes to the terminal state
    targets: tuple = (("Hertz", 1_000_000, 1.5, 10.0), ("linear", 100_000, 1.0, 30.0))
    target_runs: int = 3
    # general: the paper's Hertz line against RANDOM_LINE, to the terminal state; a
    # random-line size predicted over general_cap seconds is skipped (the requirement is
    # read at the largest N)
    general_n: tuple = (300, 1000, 10_000, 1_000_000)
    general_cap: float = 60.0
    general_runs: int = 3
    units_n: int = 100_000            # the SI steel line against the paper's
    # previous: (label, N, alpha) to the terminal state, both versions alternating
    previous_cases: tuple = (("Hertz", 10_000, 1.5), ("Hertz", 1_000_000, 1.5),
                             ("linear", 100_000, 1.0))
    previous_runs: int = 5
    # lammps (benchmarks.against_lammps): the accuracy line's N, LAMMPS's steps t_c / f,
    # the N of the mid-wave error's growth, the timed lines (kind, N, target ratio); a
    # LAMMPS run predicted over lammps_cap seconds is timed on fractions of its steps
    # (the longer about lammps_fraction_seconds) and extrapolated
    lammps_accuracy_n: int = 20
    lammps_fractions: tuple = (20, 50, 100, 200, 400, 1000)
    lammps_growth_n: tuple = (20, 200, 2000)
    lammps_cost: tuple = (("elastic", 2000, None), ("elastic", 10_000, 200.0),
                          ("damped", 3000, 20.0))
    lammps_cap: float = 120.0
    lammps_fraction_seconds: float = 20.0

    @classmethod
    def make(cls, full: bool, smoke: bool = False) -> "Mode":
        if smoke:                     # the harness itself, in two minutes: tiny sizes
            return cls(full=False, peers_n=(30, 60), scipy_max_n=60, peers_cap=10.0,
                       hertz_n=(100, 200, 400),
                       linear_n=(50, 100, 200), hertz_budget=10.0, linear_budget=10.0,
                       linear_peer_n=(30, 60), peer_point_cap=10.0, k80_timeout=5.0,
                       memory_t_end=20.0, memory_n=10_000,
                       targets=(("Hertz", 2000, 1.5, 10.0), ("linear", 500, 1.0, 30.0)),
                       target_runs=2, general_n=(30, 100, 300), general_cap=10.0,
                       general_runs=2, units_n=1000,
                       previous_cases=(("Hertz", 200, 1.5), ("Hertz", 2000, 1.5),
                                       ("linear", 500, 1.0)),
                       previous_runs=2, lammps_fractions=(20, 100, 400),
                       lammps_growth_n=(20, 60), lammps_cost=(("elastic", 200, None),
                                                              ("damped", 60, 20.0)),
                       lammps_cap=3.0, lammps_fraction_seconds=1.0)
        if not full:
            return cls(full=False)
        return cls(full=True, peers_n=(250, 1000, 4000, 10_000), scipy_max_n=10_000,
                   peers_cap=math.inf,
                   hertz_budget=math.inf, linear_budget=math.inf,
                   linear_peer_n=(100, 300, 1000, 3000), peer_point_cap=600.0,
                   k80_timeout=3600.0, k80_process=True, memory_t_end=None,
                   general_cap=4 * 3600.0, lammps_cap=math.inf)


# --- small utilities ---------------------------------------------------------------------


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


class Deadline(Exception):
    """Raised from the solver's progress hook when a run exceeds its time limit."""


def timed(fn: Callable[[], object], *, short: float = SHORT, max_repeats: int = 3):
    """Run ``fn``; repeat short runs and keep the fastest.

    Returns (result of the fastest run, min time, all times). A run under ``short``
    seconds is repeated up to ``max_repeats`` times in all (5 under a tenth of it).
    """
    times = []
    best = None
    while True:
        t0 = time.perf_counter()
        result = fn()
        elapsed = time.perf_counter() - t0
        if not times or elapsed < min(times):
            best = result
        times.append(elapsed)
        limit = 5 if min(times) < short / 10 else max_repeats
        if min(times) >= short or len(times) >= limit:
            return best, min(times), times


def max_error(v, ref) -> float:
    return float(np.max(np.abs(np.asarray(v) - np.asarray(ref))))


def fit_exponent(ns, ts, min_time: float = 0.05) -> dict | None:
    """Least-squares slope of log(time) against log(N).

    Points faster than ``min_time`` (start-up dominated) are left out while at least
    two others remain. Also the local exponent between the two largest N.
    """
    pts = sorted((n, t) for n, t in zip(ns, ts) if t is not None and t > 0)
    used = [p for p in pts if p[1] >= min_time]
    if len(used) < 2:
        used = pts
    if len(used) < 2:
        return None
    x = np.log([p[0] for p in used])
    y = np.log([p[1] for p in used])
    slope = float(np.polyfit(x, y, 1)[0])
    local = float((y[-1] - y[-2]) / (x[-1] - x[-2]))
    return {"exponent": slope, "local_exponent": local, "n_min": used[0][0],
            "n_max": used[-1][0], "points": len(used)}


def fmt_t(t: float | None) -> str:
    if t is None:
        return "-"
    if t >= 100:
        return f"{t:.0f}"
    if t >= 10:
        return f"{t:.1f}"
    if t >= 0.1:
        return f"{t:.2f}"
    return f"{t:.3f}"


def fmt_e(e: float | None) -> str:
    return "-" if e is None else f"{e:.1e}"


def table(headers: list[str], rows: list[list[str]], align: str | None = None) -> str:
    align = align or "l" + "r" * (len(headers) - 1)
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h)
              for i, h in enumerate(headers)]

    def line(cells):
        return "  ".join(c.ljust(w) if a == "l" else c.rjust(w)
                         for c, w, a in zip(cells, widths, align)).rstrip()

    out = [line(headers), line(["-" * w for w in widths])]
    out += [line(r) for r in rows]
    return "\n".join(out)


# --- machine, versions, commit ------------------------------------------------------------


def git_commit(root: Path = ROOT) -> str | None:
    """The checked-out commit, read from .git without running git."""
    git = root / ".git"
    try:
        if git.is_file():                          # a worktree: "gitdir: <path>"
            git = Path(git.read_text().split(":", 1)[1].strip())
        head = (git / "HEAD").read_text().strip()
        if not head.startswith("ref:"):
            return head
        ref = head.split(None, 1)[1]
        common = git
        if (git / "commondir").is_file():
            common = (git / (git / "commondir").read_text().strip()).resolve()
        for base in (git, common):
            if (base / ref).is_file():
                return (base / ref).read_text().strip()
        packed = common / "packed-refs"
        if packed.is_file():
            for line in packed.read_text().splitlines():
                if line.endswith(" " + ref):
                    return line.split()[0]
    except OSError:
        return None
    return None


def machine_info() -> dict:
    info = {"platform": platform.platform(), "machine": platform.machine(),
            "cpus": os.cpu_count(), "python": platform.python_version()}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                info["memory_gb"] = round(int(line.split()[1]) / 2**20, 1)
                break
    except OSError:
        pass
    return info


def versions() -> dict:
    import h5py
    import numba
    import scipy

    import chainrun
    from benchmarks.peers import heyoka_peer, lammps_peer

    return {"chainrun": chainrun.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "numba": numba.__version__, "h5py": h5py.__version__,
            "heyoka": heyoka_peer.version(), "lammps": lammps_peer.version()}


# --- chainrun as a process -----------------------------------------------------------------

# Runs one command and reports its own children's usage: the max RSS of exactly that
# command, which RUSAGE_CHILDREN of this (long-lived) process could not isolate.
_WRAPPER = """
import json, resource, subprocess, sys, time
log = open(sys.argv[1], "w")
t0 = time.perf_counter()
rc = subprocess.run(sys.argv[2:], stdout=log, stderr=subprocess.STDOUT).returncode
wall = time.perf_counter() - t0
u = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps(dict(rc=rc, wall=wall, cpu=u.ru_utime + u.ru_stime, maxrss_kb=u.ru_maxrss)))
"""


def chainrun_command() -> list[str]:
    exe = Path(sys.executable).with_name("chainrun")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "chainrun"]


def _toml(value) -> str:
    """A TOML value: a number, a string, a list or an inline table of those."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_toml(v)}" for k, v in value.items()) + "}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return repr(value)


def config_text(name: str, n: int, k: int, alpha: float | None, *,
                t_end: float | None = None, times=None, chain: dict | None = None,
                top: dict | None = None, rtol: float | None = None) -> str:
    """An experiment file of one run: the paper's line of ``n`` balls, ``k`` strikers,
    exponent ``alpha`` (None: left to a material), with the keys of ``chain`` added to
    ``[chain]`` (masses, stiffnesses, materials...) and those of ``top`` (``units``)
    at the top level; ``t_end`` and ``rtol`` go to ``[solver]``."""
    lines = [f'name = "{name}"']
    lines += [f"{key} = {_toml(v)}" for key, v in (top or {}).items()]
    lines += ["[chain]", f"n = {n}", f"k = {k}"]
    if alpha is not None:
        lines.append(f"alpha = {alpha!r}")
    lines += [f"{key} = {_toml(v)}" for key, v in (chain or {}).items()]
    if times is not None:
        lines += ["[output]", "times = [" + ", ".join(repr(float(t)) for t in times) + "]"]
    solver = {key: float(v) for key, v in (("t_end", t_end), ("rtol", rtol)) if v is not None}
    if solver:
        lines += ["[solver]"] + [f"{key} = {v!r}" for key, v in solver.items()]
    return "\n".join(lines) + "\n"


@dataclass
class ProcessRun:
    wall: float | None
    cpu: float | None
    maxrss_mb: float | None
    final_velocity: np.ndarray | None = None
    error: str | None = None
    diagnostics: dict | None = None       # the run file's /diagnostics and outcome


class Processes:
    """Runs ``chainrun simulate`` on generated configs in a scratch folder."""

    def __init__(self, scratch: Path):
        self.scratch = scratch
        self.count = 0

    def run(self, text: str, *, env: dict | None = None, timeout: float | None = None,
            read_velocity: bool = True, read_diagnostics: bool = False) -> ProcessRun:
        self.count += 1
        folder = self.scratch / f"proc{self.count}"
        folder.mkdir()
        cfg = folder / "run.toml"
        cfg.write_text(text)
        out = folder / "out"
        cmd = [sys.executable, "-c", _WRAPPER, str(folder / "log.txt"), *chainrun_command(),
               "simulate", str(cfg), "-o", str(out)]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, cwd=folder,
                                env=env, start_new_session=True)
        try:
            stdout, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)       # the wrapper's session: ours
            proc.communicate()
            shutil.rmtree(folder, ignore_errors=True)
            return ProcessRun(None, None, None, error=f"timed out after {timeout:.0f} s")
        except BaseException:                         # interrupted: leave no run behind
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
            raise
        try:
            report = json.loads(stdout.strip().splitlines()[-1])
        except (IndexError, json.JSONDecodeError):
            report = {"rc": -1}
        result = ProcessRun(report.get("wall"), report.get("cpu"),
                            report.get("maxrss_kb", 0) / 1024 or None)
        if report.get("rc") != 0:
            tail = (folder / "log.txt").read_text()[-400:] if (folder / "log.txt").exists() else ""
            result.error = f"exit status {report.get('rc')}: {tail.strip()}"
        elif read_velocity or read_diagnostics:
            import h5py
            with h5py.File(out / "run.h5", "r") as f:
                if read_velocity:
                    result.final_velocity = f["results/final_velocity"][:]
                if read_diagnostics:
                    d = {k: v.item() if isinstance(v, np.generic) else v
                         for k, v in f["diagnostics"].attrs.items()}
                    r = f["results"].attrs
                    d.update(outcome=str(r["outcome"]), end_time=float(r["end_time"]))
                    result.diagnostics = d
        shutil.rmtree(folder, ignore_errors=True)
        return result

    def timed(self, text: str, **kwargs) -> tuple[ProcessRun, list[float]]:
        """Repeat a short process run; the fastest (wall) and all wall times."""
        runs = []
        while True:
            r = self.run(text, **kwargs)
            runs.append(r)
            walls = [x.wall for x in runs if x.wall is not None]
            if r.error or not walls or min(walls) >= SHORT or len(runs) >= 3:
                break
        ok = [x for x in runs if x.error is None]
        best = min(ok, key=lambda x: x.wall) if ok else runs[-1]
        return best, [x.wall for x in runs if x.wall is not None]


# --- chainrun in-process -------------------------------------------------------------------


def simulate_until(n, k, alpha, *, t_end=None, rtol=None, timeout=None, times=()):
    """``chainrun.solver.simulate``, abandoned (``Deadline``) after ``timeout`` seconds."""
    from chainrun.solver import DEFAULT_RTOL, Line, simulate

    start = time.perf_counter()
    last_t = [0.0]

    def progress(t):
        last_t[0] = t
        if timeout is not None and time.perf_counter() - start > timeout:
            raise Deadline(f"not finished after {timeout:.0f} s (reached t = {t:.4g})")

    return simulate(Line.paper(n, k, alpha), times, t_end=t_end,
                    rtol=DEFAULT_RTOL if rtol is None else rtol, on_progress=progress)


def chainrun_point(n, k, alpha, *, t_end=None, timeout=None, short=SHORT) -> dict:
    """One in-process chainrun run (repeated when short): time, counts, final state."""
    try:
        sol, best, times = timed(lambda: simulate_until(n, k, alpha, t_end=t_end,
                                                        timeout=timeout), short=short)
    except Deadline as exc:
        return {"n": n, "time": None, "error": str(exc)}
    d = sol.diagnostics
    return {"n": n, "time": best, "times": times, "steps": d.steps, "events": d.events,
            "closed_form": d.closed_form_collisions,
            "end_time": sol.end_time, "outcome": sol.outcome.value,
            "max_window": d.max_window, "energy_error": d.energy_error,
            "momentum_error": d.momentum_error, "final_velocity": sol.final_velocity}


# --- the sections --------------------------------------------------------------------------


def section_compile(procs: Processes) -> dict:
    """Cold (fresh numba cache) and warm runs of the same small config, as processes."""
    log("compile: chainrun simulate with an empty numba cache (the first run)...")
    cache = Path(tempfile.mkdtemp(prefix="numba-cold-", dir=procs.scratch))
    env = dict(os.environ, NUMBA_CACHE_DIR=str(cache))
    text = config_text("compile", 250, 1, 1.5, t_end=50.0, times=[0.0, 25.0, 50.0])
    cold = procs.run(text, env=env)
    warm, walls = procs.timed(text, env=env)
    shutil.rmtree(cache, ignore_errors=True)
    out = {"case": "N=250, K=1, alpha=1.5, t_end=50, 3 snapshots",
           "cold_wall": cold.wall, "cold_cpu": cold.cpu, "warm_wall": warm.wall,
           "warm_cpu": warm.cpu, "warm_walls": walls, "error": cold.error or warm.error}
    if cold.wall is not None and warm.wall is not None:
        out["compile_wall"] = cold.wall - warm.wall
        out["compile_cpu"] = cold.cpu - warm.cpu
    log(f"  cold {fmt_t(cold.wall)} s (cpu {fmt_t(cold.cpu)} s), warm {fmt_t(warm.wall)} s")
    out["numba_floor"] = _numba_floor(procs.scratch)
    log(f"  numba's own start-up: {fmt_t(min(out['numba_floor']))} s at best")
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


def _numba_floor(scratch: Path, runs: int = 5) -> list[float]:
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


def _peer_runners(mode: Mode, notes: list[str]) -> dict:
    """The available peers: name -> solve(n, k, alpha, t_stop)."""
    from benchmarks.peers import heyoka_peer, rk4_paper, scipy_dop853

    runners = {"scipy": scipy_dop853.solve, "rk4": rk4_paper.solve}
    ok, why = heyoka_peer.available()
    if ok:
        runners["heyoka"] = heyoka_peer.solve
    else:
        notes.append(f"heyoka skipped: {why}")
        log(f"  heyoka skipped: {why}")
    return runners


def _run_peer(name, solve, n, k, alpha, t_stop) -> dict:
    """One peer run, repeated when short; the fastest solve, compilation apart."""
    runs: list[PeerResult] = []
    try:
        while True:
            runs.append(solve(n, k, alpha, t_stop))
            best = min(runs, key=lambda r: r.solve_time)
            limit = 5 if best.solve_time < SHORT / 10 else 3
            if best.solve_time >= SHORT or len(runs) >= limit:
                break
    except PeerUnavailable as exc:
        return {"tool": name, "n": n, "error": str(exc)}
    except Exception as exc:                       # a peer failing is a result too
        return {"tool": name, "n": n, "error": f"{type(exc).__name__}: {exc}"}
    return {"tool": name, "n": n, "time": best.solve_time,
            "times": [r.solve_time for r in runs], "compile_time": runs[0].compile_time,
            "steps": best.steps, "events": best.events, "settings": best.settings,
            "final_velocity": best.final_velocity}


def _predict(points: list[tuple[int, float]], n_next: int) -> float:
    """Time at n_next from the last points, assuming at least linear growth."""
    (n1, t1) = points[-1]
    slope = 2.0
    if len(points) >= 2:
        n0, t0 = points[-2]
        if t0 > 0.05 and t1 > 0:
            slope = max(1.0, math.log(t1 / t0) / math.log(n1 / n0))
    return t1 * (n_next / n1) ** slope


def section_peers(mode: Mode, procs: Processes, notes: list[str]) -> dict:
    """The peers' case: Hertz, K = 1, until t = 1.25 N + 20."""
    runners = _peer_runners(mode, notes)
    rows = []
    history: dict[str, list] = {name: [] for name in runners}
    for n in mode.peers_n:
        t_stop = 1.25 * n + 20
        log(f"peers: N = {n}, t = {t_stop:g}")
        ref = simulate_until(n, 1, 1.5, t_end=t_stop, rtol=REFERENCE_RTOL)
        v_ref = ref.final_velocity
        case = {"n": n, "t_stop": t_stop, "reference_end_time": ref.end_time,
                "reference_outcome": ref.outcome.value, "tools": []}
        run = chainrun_point(n, 1, 1.5, t_end=t_stop)
        run["tool"] = "chainrun"
        proc, walls = procs.timed(config_text(f"peers-n{n}", n, 1, 1.5, t_end=t_stop))
        run.update(process_time=proc.wall, process_times=walls, process_cpu=proc.cpu,
                   process_maxrss_mb=proc.maxrss_mb, process_error=proc.error)
        case["tools"].append(run)
        if proc.final_velocity is not None:
            case["tools"].append({"tool": "chainrun-cli", "n": n,
                                  "final_velocity": proc.final_velocity})
        log(f"  chainrun: process {fmt_t(proc.wall)} s, solver {fmt_t(run['time'])} s, "
            f"error {fmt_e(max_error(run['final_velocity'], v_ref))}")
        for name, solve in runners.items():
            if name == "scipy" and n > mode.scipy_max_n:
                case["tools"].append({"tool": name, "n": n,
                                      "skipped": f"N > {mode.scipy_max_n} (--full for more)"})
                continue
            if history[name] and _predict(history[name], n) > mode.peers_cap:
                case["tools"].append({"tool": name, "n": n, "skipped":
                                      f"predicted {fmt_t(_predict(history[name], n))} s "
                                      f"(--full for more)"})
                continue
            r = _run_peer(name, solve, n, 1, 1.5, t_stop)
            case["tools"].append(r)
            if r.get("time") is not None:
                history[name].append((n, r["time"]))
            log(f"  {name}: {fmt_t(r.get('time'))} s"
                + (f" (+{fmt_t(r['compile_time'])} s compile)" if r.get("compile_time") else "")
                + (f", error {fmt_e(max_error(r['final_velocity'], v_ref))}"
                   if "final_velocity" in r else f" {r.get('error', '')}"))
        for r in case["tools"]:
            if "final_velocity" in r:
                r["error_vs_reference"] = max_error(r["final_velocity"], v_ref)
        case["agreement"] = agreement(case["tools"])
        rows.append(case)
    return {"cases": rows}


def agreement(tools: list[dict]) -> dict:
    """Pairwise max differences of the final velocities, checked against the tools'
    claimed accuracies (``ACCURACY``): a pair disagrees when its difference exceeds
    the sum of the two; a tool is off when its error exceeds its own claim."""
    have = [t for t in tools if "final_velocity" in t]
    pairs = []
    for i, a in enumerate(have):
        for b in have[i + 1:]:
            diff = max_error(a["final_velocity"], b["final_velocity"])
            allowed = ACCURACY[a["tool"]] + ACCURACY[b["tool"]]
            pairs.append({"a": a["tool"], "b": b["tool"], "max_diff": diff,
                          "allowed": allowed, "ok": diff <= allowed})
    off = [{"tool": t["tool"], "error": t["error_vs_reference"],
            "claimed": ACCURACY[t["tool"]]}
           for t in have if t.get("error_vs_reference", 0.0) > ACCURACY[t["tool"]]]
    return {"pairs": pairs, "off": off, "ok": all(p["ok"] for p in pairs) and not off}


def _series(label, alpha, ns, budget, timeout_cap) -> list[dict]:
    """chainrun in-process to the terminal state over ``ns``, within ``budget`` seconds."""
    points = []
    spent = 0.0
    done: list[tuple[int, float]] = []
    for n in ns:
        if done:
            guess = _predict(done, n)
            if guess > budget - spent:
                points.append({"n": n, "time": None,
                               "skipped": f"predicted {fmt_t(guess)} s > budget left "
                                          f"{fmt_t(max(budget - spent, 0))} s"})
                log(f"  {label} N = {n}: skipped, predicted {fmt_t(guess)} s")
                continue
        left = budget - spent
        p = chainrun_point(n, 1, alpha, timeout=min(left, timeout_cap) if math.isfinite(left)
                           else None, short=SERIES_SHORT)
        p.pop("final_velocity", None)
        spent += sum(p.get("times", [])) if p.get("time") is not None else left
        points.append(p)
        if p.get("time") is None:
            log(f"  {label} N = {n}: {p.get('error')}")
            break
        done.append((n, p["time"]))
        log(f"  {label} N = {n}: {fmt_t(p['time'])} s, terminal t = {p['end_time']:.6g}, "
            f"{p['steps']} steps, {p['events']} events, window {p['max_window']}")
    return points


def section_scaling(mode: Mode, peers: dict | None, notes: list[str]) -> dict:
    log("scaling: Hertz, K = 1, to the terminal state (chainrun in-process)")
    hertz = _series("Hertz", 1.5, mode.hertz_n, mode.hertz_budget, 3600.0)
    log("scaling: linear, K = 1, to the terminal state (chainrun in-process)")
    linear = _series("linear", 1.0, mode.linear_n, mode.linear_budget, 3600.0)
    out = {"hertz": {"chainrun": hertz}, "linear": {"chainrun": linear}}

    # Hertz peers: the peers' case (t = 1.25 N + 20 is after chainrun's terminal time
    # there, checked below), so the same runs give their scaling.
    if peers:
        for case in peers["cases"]:
            for r in case["tools"]:
                if r["tool"] in ("chainrun", "chainrun-cli") or r.get("time") is None:
                    continue
                out["hertz"].setdefault(r["tool"], []).append(
                    {"n": case["n"], "time": r["time"], "steps": r.get("steps"),
                     "events": r.get("events"), "until": case["t_stop"]})
            if case["reference_end_time"] > case["t_stop"] or case["reference_outcome"] != "terminal":
                notes.append(f"Hertz N = {case['n']}: chainrun's terminal state comes after "
                             f"t = {case['t_stop']:g}; the peers' scaling points stop before it")

    # Linear peers: run until chainrun's terminal time.
    log("scaling: linear peers, until chainrun's terminal time")
    runners = _peer_runners(mode, [])
    history: dict[str, list] = {name: [] for name in runners}
    for n in mode.linear_peer_n:
        ref = simulate_until(n, 1, 1.0, rtol=REFERENCE_RTOL)
        t_stop = ref.end_time
        for name, solve in runners.items():
            if history[name] and _predict(history[name], n) > mode.peer_point_cap:
                continue
            r = _run_peer(name, solve, n, 1, 1.0, t_stop)
            if r.get("time") is None:
                log(f"  linear {name} N = {n}: {r.get('error')}")
                continue
            history[name].append((n, r["time"]))
            err = max_error(r["final_velocity"], ref.final_velocity)
            out["linear"].setdefault(name, []).append(
                {"n": n, "time": r["time"], "steps": r["steps"], "events": r["events"],
                 "until": t_stop, "error_vs_reference": err,
                 "ok": err <= ACCURACY[name]})
            log(f"  linear {name} N = {n}: {fmt_t(r['time'])} s, error {fmt_e(err)}")

    fits = {}
    for kind in ("hertz", "linear"):
        fits[kind] = {tool: fit_exponent([p["n"] for p in pts], [p.get("time") for p in pts])
                      for tool, pts in out[kind].items()}
    out["fits"] = fits
    return out


def section_targets(mode: Mode, procs: Processes) -> list[dict]:
    """The timed targets: whole ``chainrun simulate`` processes, K = 1, to the terminal
    state, each run ``target_runs`` times (every time is kept: the machine's speed
    moves, and a target met only by the fastest run is not met)."""
    out = []
    for label, n, alpha, limit in mode.targets:
        log(f"targets: {label} N = {n}, K = 1, to the terminal state, as a process "
            f"(limit {limit:g} s), {mode.target_runs} runs")
        walls, cpus, errors = [], [], []
        for _ in range(mode.target_runs):
            r = procs.run(config_text(f"target-{label.lower()}-{n}", n, 1, alpha),
                          timeout=10 * limit + 60, read_velocity=False)
            if r.error:
                errors.append(r.error)
                log(f"  {r.error}")
                break
            walls.append(r.wall)
            cpus.append(r.cpu)
            log(f"  {fmt_t(r.wall)} s (cpu {fmt_t(r.cpu)} s, peak RSS {fmt_t(r.maxrss_mb)} MB)")
        met = sum(w <= limit for w in walls)
        out.append({"label": label, "n": n, "alpha": alpha, "limit": limit, "walls": walls,
                    "cpus": cpus, "errors": errors, "runs_within_limit": met,
                    "met": bool(walls) and not errors and met == len(walls)})
    return out


def section_k80(mode: Mode, procs: Processes) -> dict:
    log(f"k80: N = 2000, K = 80, Hertz, to the terminal state (limit {fmt_t(mode.k80_timeout)} s)")
    p = chainrun_point(2000, 80, 1.5, timeout=mode.k80_timeout)
    p.pop("final_velocity", None)
    if p.get("time") is not None:
        if mode.k80_process:
            proc = procs.run(config_text("k80", 2000, 80, 1.5),
                             timeout=mode.k80_timeout * 3 + 60, read_velocity=False)
            p.update(process_time=proc.wall, process_error=proc.error)
        log(f"  {fmt_t(p['time'])} s in-process, {fmt_t(p.get('process_time'))} s process, "
            f"terminal t = {p['end_time']:.6g}, {p['events']} events, {p['steps']} steps, "
            f"{p['closed_form']} collisions in closed form")
    else:
        log(f"  {p.get('error')}")
    return p


def section_memory(mode: Mode, procs: Processes) -> dict:
    n = mode.memory_n
    t_last = mode.memory_t_end if mode.memory_t_end is not None else 1.25 * n + 20
    out = {"n": n, "t_end": mode.memory_t_end, "runs": []}
    for count in (200, 2):
        times = np.linspace(0.0, t_last, count)
        log(f"memory: N = {n}, {count} snapshots until t = {t_last:g}"
            + ("" if mode.memory_t_end is not None else " (run to the terminal state)"))
        r = procs.run(config_text(f"memory-{count}", n, 1, 1.5, t_end=mode.memory_t_end,
                                  times=times),
                      timeout=None if mode.full else 600.0, read_velocity=False)
        out["runs"].append({"snapshots": count, "maxrss_mb": r.maxrss_mb, "wall": r.wall,
                            "error": r.error})
        log(f"  peak RSS {fmt_t(r.maxrss_mb)} MB, {fmt_t(r.wall)} s {r.error or ''}")
    return out


def median(xs) -> float | None:
    return float(np.median(xs)) if len(xs) else None


def alternate(procs: Processes, jobs: dict[str, dict], runs: int, *,
              read_diagnostics: bool = False) -> dict:
    """Run each job ``runs`` times, alternating (a, b, a, b, ...): this host's speed
    drifts by several per cent over minutes, and alternating spreads the drift over
    both. ``jobs`` maps a name to ``dict(text=config, env=..., timeout=...)``. Returns
    name -> walls, cpus, errors, and the first run's diagnostics when asked; the first
    failure ends every job's runs (a comparison with one side missing is none)."""
    out = {name: {"walls": [], "cpus": [], "errors": [], "diagnostics": None}
           for name in jobs}
    for _ in range(runs):
        for name, job in jobs.items():
            r = procs.run(job["text"], env=job.get("env"), timeout=job.get("timeout"),
                          read_velocity=False, read_diagnostics=read_diagnostics)
            if r.error:
                out[name]["errors"].append(r.error)
                log(f"  {name}: {r.error}")
                return out
            out[name]["walls"].append(r.wall)
            out[name]["cpus"].append(r.cpu)
            if out[name]["diagnostics"] is None:
                out[name]["diagnostics"] = r.diagnostics
            log(f"  {name}: {fmt_t(r.wall)} s (cpu {fmt_t(r.cpu)} s)")
    return out


def _ratio(a: dict, b: dict, stat=median) -> float | None:
    """stat(a's walls) / stat(b's walls), None unless both have times."""
    if not a or not b or not a["walls"] or not b["walls"]:
        return None
    return stat(a["walls"]) / stat(b["walls"])


def section_general(mode: Mode, procs: Processes) -> dict:
    """The paper's Hertz line against a random line (RANDOM_LINE) of the same N, K = 1,
    to the terminal state, as whole processes, runs alternating; then the steel line in
    SI units against the paper's line of ``units_n`` balls.

    The random line's terminal state costs far more than the paper's line's (the wave
    scatters, and its fragments collide until the velocities are sorted): a size
    whose predicted time is over ``general_cap`` is skipped, with the prediction."""
    out = {"random_line": RANDOM_LINE, "limit": GENERAL_LIMIT,
           "requirement_n": max(mode.general_n), "runs": mode.general_runs, "series": []}
    done: list[tuple[int, float]] = []       # (N, solver time) of the random line
    stopped = None
    for n in mode.general_n:
        log(f"general: N = {n}, the paper's line and the random line, K = 1, to the "
            f"terminal state, as processes")
        jobs = {"uniform": {"text": config_text(f"general-uniform-{n}", n, 1, 1.5),
                            "timeout": 600.0}}
        point = {"n": n}
        # the random line's solver time, predicted from its smaller sizes
        guess = _predict(done, n) if done else None
        if stopped:
            point["random_skipped"] = stopped
        elif guess is not None and guess > mode.general_cap:
            point["random_skipped"] = (f"predicted solver time {fmt_t(guess)} s > "
                                       f"{fmt_t(mode.general_cap)} s"
                                       + ("" if mode.full else " (--full for more)"))
        else:
            budget = mode.general_cap if guess is None else max(guess, mode.general_cap)
            jobs["random"] = {"text": config_text(f"general-random-{n}", n, 1, 1.5,
                                                  chain=RANDOM_LINE),
                              "timeout": 4 * budget + 60}
        if "random_skipped" in point:
            log(f"  random: skipped, {point['random_skipped']}")
        point.update(alternate(procs, jobs, mode.general_runs, read_diagnostics=True))
        point["ratio"] = _ratio(point.get("random"), point["uniform"])
        uni, rnd = point["uniform"], point.get("random")
        if guess is not None and uni["walls"]:
            # and the process's start-up and file: the paper's line's whole time, at most
            point["random_predicted"] = guess + median(uni["walls"])
        if rnd and rnd["walls"] and not rnd["errors"] and rnd["diagnostics"]:
            done.append((n, rnd["diagnostics"]["wall_time"]))
        elif rnd:
            stopped = f"the random line failed at N = {n}"
        out["series"].append(point)
    last = out["series"][-1]
    out["requirement"] = _general_verdict(last)

    n = mode.units_n
    log(f"general: N = {n}, the steel line in SI units against the paper's line")
    jobs = {"paper": {"text": config_text(f"units-paper-{n}", n, 1, 1.5), "timeout": 600.0},
            "si": {"text": config_text(f"units-si-{n}", n, 1, None, top={"units": "si"},
                                       chain=SI_LINE), "timeout": 600.0}}
    units = {"n": n, "si_line": SI_LINE}
    units.update(alternate(procs, jobs, mode.general_runs, read_diagnostics=True))
    units["ratio"] = _ratio(units["si"], units["paper"])
    dp, ds = units["paper"]["diagnostics"], units["si"]["diagnostics"]
    units["same_work"] = (None if not dp or not ds else
                          (dp["events"], dp["steps"]) == (ds["events"], ds["steps"]))
    out["units"] = units
    return out


def _general_verdict(point: dict) -> dict:
    """The requirement (random / paper line <= GENERAL_LIMIT) at the largest N:
    measured, or, where the random line was skipped, its prediction."""
    uni = point["uniform"]
    if point.get("ratio") is not None:
        return {"n": point["n"], "ratio": point["ratio"], "measured": True,
                "met": point["ratio"] <= GENERAL_LIMIT}
    guess = point.get("random_predicted")
    if guess is not None and uni["walls"]:
        ratio = guess / median(uni["walls"])
        return {"n": point["n"], "ratio": ratio, "measured": False,
                "met": ratio <= GENERAL_LIMIT}
    return {"n": point["n"], "ratio": None, "measured": False, "met": None}


# --- the previous version ------------------------------------------------------------------


def git(root: Path, *args: str) -> str:
    """``git -C root args``; its output, stripped. RuntimeError (with git's message)
    when it fails."""
    r = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"git {' '.join(args)}: {(r.stderr or r.stdout).strip()}")
    return r.stdout.strip()


def resolve_against(rev: str | None, root: Path = ROOT, environ=None) -> dict:
    """The revision the previous section compares with, as a commit.

    ``rev`` (``--against``), else ``$CHAINRUN_BENCH_AGAINST``, else the solver as it
    was before its latest change: with uncommitted changes under ``chainrun/solver``,
    HEAD; otherwise the first parent of the newest commit on HEAD's first-parent
    history that changed it (a merge counts as one change). Returns dict(commit,
    asked, why, subject); ValueError when it cannot be resolved.
    """
    environ = os.environ if environ is None else environ
    asked, source = rev, "--against"
    if not asked:
        asked, source = environ.get(AGAINST_ENV) or None, f"${AGAINST_ENV}"
    try:
        if asked:
            commit = git(root, "rev-parse", "--verify", "--quiet", f"{asked}^{{commit}}")
            why = f"{asked} ({source})"
        elif git(root, "status", "--porcelain", "--", SOLVER_PATH):
            commit = git(root, "rev-parse", "--verify", "HEAD")
            why = f"HEAD: {SOLVER_PATH}/ has uncommitted changes"
        else:
            last = git(root, "log", "--first-parent", "-n", "1", "--format=%H", "HEAD",
                       "--", SOLVER_PATH)
            if not last:
                raise ValueError(f"no commit changed {SOLVER_PATH}/: name a revision "
                                 f"with --against or ${AGAINST_ENV}")
            try:
                commit = git(root, "rev-parse", "--verify", "--quiet", f"{last}^1")
            except RuntimeError:
                raise ValueError(f"{last[:12]}, the latest change to {SOLVER_PATH}/, has "
                                 f"no parent: name a revision with --against") from None
            why = (f"{last[:12]}^, the solver before its latest change "
                   f"(\"{git(root, 'log', '-1', '--format=%s', last)}\")")
        subject = git(root, "log", "-1", "--format=%s", commit)
    except RuntimeError as exc:
        raise ValueError(f"cannot resolve the previous version"
                         f"{f' {asked!r}' if asked else ''}: {exc}") from None
    return {"commit": commit, "asked": asked, "why": why, "subject": subject}


def _pythonpath(first: Path) -> str:
    rest = os.environ.get("PYTHONPATH")
    return str(first) + (os.pathsep + rest if rest else "")


def section_previous(mode: Mode, procs: Processes, against: str | None) -> dict:
    """This version against a previous one (``resolve_against``) on the targets' paper
    lines, in the same run: the previous revision is checked out into a temporary
    worktree with a numba cache of its own (its first run compiles, and is left out),
    and the two versions' ``chainrun simulate`` processes alternate."""
    out: dict = {"cases": [], "runs": mode.previous_runs}
    try:
        out.update(resolve_against(against))
    except ValueError as exc:
        out["error"] = str(exc)
        log(f"previous: {exc}")
        return out
    tree = procs.scratch / f"previous-{out['commit'][:12]}"
    log(f"previous: {out['commit'][:12]} ({out['why']}) into {tree}")
    try:
        dirty = bool(git(ROOT, "status", "--porcelain", "--", SOLVER_PATH))
        out["new"] = {"commit": git_commit(), "solver_changes_uncommitted": dirty}
        git(ROOT, "worktree", "add", "--detach", str(tree), out["commit"])
        envs = {"new": dict(os.environ, PYTHONPATH=_pythonpath(ROOT)),
                "old": dict(os.environ, PYTHONPATH=_pythonpath(tree),
                            NUMBA_CACHE_DIR=str(procs.scratch / "numba-previous"))}
        warm = config_text("previous-warmup", 50, 1, 1.5, times=[0.0, 10.0])
        log("  old: its first run, compiling into its own numba cache...")
        cold = procs.run(warm, env=envs["old"], timeout=900.0, read_velocity=False)
        again = procs.run(warm, env=envs["old"], timeout=300.0, read_velocity=False)
        out["old_first_run"] = {"wall": cold.wall, "cpu": cold.cpu, "warm_wall": again.wall,
                                "error": cold.error or again.error}
        if cold.error or again.error:
            out["error"] = f"the previous version does not run: {cold.error or again.error}"
            log(f"  {out['error']}")
            return out
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
            case["ratio_median"] = _ratio(case["new"], case["old"])
            case["ratio_min"] = _ratio(case["new"], case["old"], min)
            out["cases"].append(case)
    except RuntimeError as exc:                   # git failing
        out["error"] = str(exc)
        log(f"  {exc}")
    finally:
        if tree.exists():
            try:
                git(ROOT, "worktree", "remove", "--force", str(tree))
            except RuntimeError as exc:
                log(f"  could not remove the worktree {tree}: {exc}; "
                    f"`git worktree prune` forgets it once the folder is gone")
    return out


# --- the report ----------------------------------------------------------------------------


def _times(walls) -> str:
    return ", ".join(fmt_t(w) for w in walls) or "-"


def _ratio_text(r: float | None) -> str:
    if r is None:
        return "-"
    return f"{r:.2f}" if r < 100 else f"{r:.3g}"


def report_general(g: dict) -> list[str]:
    """The general section's lines of the report."""
    out = ["General line: the paper's Hertz line (uniform) against a random line (masses "
           "and stiffnesses uniform in [1, 10), fixed seeds), K = 1, to the terminal state; "
           f"whole chainrun simulate processes, {g['runs']} runs each, alternating; "
           "x uniform = median / the uniform line's median; events, steps (accepted), "
           "rejected steps and the widest window of the first run:"]
    rows, skips = [], []
    for p in g["series"]:
        first = True
        for line in ("uniform", "random"):
            r = p.get(line)
            n = str(p["n"]) if first else ""
            first = False
            if r is None:
                guess = p.get("random_predicted")
                uni = p["uniform"]["walls"]
                rows.append([n, line, "skip", "-",
                             f"~{guess / median(uni):.2g} (pred.)" if guess and uni else "-",
                             "", "", "", ""])
                skips.append(f"{line} N = {p['n']}: {p.get('random_skipped')}")
                continue
            d = r.get("diagnostics") or {}
            rows.append([n, line, _times(r["walls"]), fmt_t(median(r["walls"]))
                         if r["walls"] else "-",
                         _ratio_text(p.get("ratio")) if line == "random" else "",
                         str(d.get("events", "-")), str(d.get("steps", "-")),
                         str(d.get("rejected_steps", "-")), str(d.get("max_window", "-"))])
            if r["errors"]:
                skips.append(f"{line} N = {p['n']}: {r['errors'][0]}")
            elif d and d.get("outcome") != "terminal":
                skips.append(f"{line} N = {p['n']}: ended {d.get('outcome')}, not terminal")
    out.append("  " + table(["N", "line", "times s", "median", "x uniform", "events", "steps",
                             "rejected", "window"], rows, "llrrrrrrr").replace("\n", "\n  "))
    out += [f"  {s}" for s in skips]
    v = g["requirement"]
    head = f"  Requirement random <= {g['limit']:g} x uniform at N = {v['n']}: "
    if v["ratio"] is None:
        out.append(head + "not measured")
    elif v["measured"]:
        out.append(head + ("MET" if v["met"] else "NOT MET") + f" ({v['ratio']:.3g} x)")
    else:
        out.append(head + ("not measured" if v["met"] else "NOT MET by prediction")
                   + f": the random line was not run, predicted {v['ratio']:.2g} x")
    u = g.get("units")
    if u:
        out.append(f"  Units: the steel line in SI units (diameter {u['si_line']['diameter']:g} m, "
                   f"{u['si_line']['speed']:g} m/s) against the paper's line, N = {u['n']}, "
                   "to the terminal state:")
        for name in ("paper", "si"):
            r = u[name]
            out.append(f"    {name:5s} {_times(r['walls'])} s (median "
                       f"{fmt_t(median(r['walls'])) if r['walls'] else '-'})"
                       + (f"  [{r['errors'][0]}]" if r["errors"] else ""))
        same = {None: "not compared", True: "the same", False: "DIFFERENT"}[u["same_work"]]
        d = u["paper"].get("diagnostics") or {}
        out.append(f"    si / paper: {_ratio_text(u['ratio'])} x; events and steps {same}"
                   + (f" ({d['events']} and {d['steps']})" if u["same_work"] else ""))
    return out


def report_previous(p: dict) -> list[str]:
    """The previous section's lines of the report."""
    if "commit" not in p:
        return [f"Previous version: {p.get('error')}"]
    new = p.get("new") or {}
    out = [f"Previous version: {p['commit'][:12]} \"{p['subject']}\", chosen as {p['why']}; "
           f"this version: commit {(new.get('commit') or '?')[:12]}"
           + (" with uncommitted solver changes" if new.get("solver_changes_uncommitted")
              else "")]
    f = p.get("old_first_run")
    if f and f.get("wall") is not None:
        out.append(f"  Its first run (a numba cache of its own, empty) took {fmt_t(f['wall'])} s "
                   f"(cpu {fmt_t(f['cpu'])} s), {fmt_t(f['warm_wall'])} s warm: left out of the "
                   "times below.")
    if p.get("error"):
        out.append(f"  {p['error']}")
    if p["cases"]:
        out.append(f"  Whole chainrun simulate processes, K = 1, to the terminal state; "
                   f"{p['runs']} runs of each version, alternating new, old, new, old, ...:")
        rows = []
        for c in p["cases"]:
            new_w, old_w = c["new"]["walls"], c["old"]["walls"]
            rows.append([f"{c['label']} {c['n']}",
                         fmt_t(min(new_w)) if new_w else "-",
                         fmt_t(median(new_w)) if new_w else "-",
                         fmt_t(min(old_w)) if old_w else "-",
                         fmt_t(median(old_w)) if old_w else "-",
                         _ratio_text(c["ratio_median"]), _ratio_text(c["ratio_min"])])
        out.append("  " + table(["case", "new min", "new median", "old min", "old median",
                                 "new/old median", "new/old min"], rows)
                   .replace("\n", "\n  "))
        for c in p["cases"]:
            line = (f"  {c['label']} N = {c['n']}: new {_times(c['new']['walls'])} s; "
                    f"old {_times(c['old']['walls'])} s")
            errors = c["new"]["errors"] + c["old"]["errors"]
            out.append(line + (f"  [{errors[0]}]" if errors else ""))
    return out


def report(res: dict) -> str:
    out = []
    m = res["machine"]
    kind = "smoke" if res.get("smoke") else ("full" if res["full"] else "default")
    out.append(f"chainrun benchmark, {res['date']} ({kind} mode)")
    out.append(f"{m.get('cpu', m['machine'])}, {m['cpus']} cores, {m.get('memory_gb')} GB; "
               f"commit {(res['git_commit'] or '?')[:12]}; load average "
               f"{res['load_start'][0]:.1f} at start, {res['load_end'][0]:.1f} at end")
    out.append(f"Times are wall seconds; runs under {SHORT:g} s are repeated (3 times, 5 under "
               f"{SHORT / 10:g} s) and the minimum kept, as the machine may be shared.")
    c = res.get("compile")
    if c:
        out.append("")
        out.append("First-run numba compilation (chainrun simulate, empty NUMBA_CACHE_DIR, "
                   f"{c['case']}):")
        out.append(f"  cold {fmt_t(c['cold_wall'])} s (cpu {fmt_t(c['cold_cpu'])} s), warm "
                   f"{fmt_t(c['warm_wall'])} s (cpu {fmt_t(c['warm_cpu'])} s): compilation "
                   f"{fmt_t(c.get('compile_wall'))} s wall, {fmt_t(c.get('compile_cpu'))} s cpu"
                   + (f"  [{c['error']}]" if c.get("error") else ""))
        if c.get("numba_floor"):
            walls = c["numba_floor"]
            out.append(f"  numba's own start-up, a process loading one cached one-line function: "
                       f"{fmt_t(min(walls))} s at best, median {fmt_t(median(walls))} s "
                       "(the warm run's floor)")
    p = res.get("peers")
    if p:
        out.append("")
        out.append("Peers' case: Hertz line, K = 1, until t = 1.25 N + 20; error = max |v - v_ref| "
                   f"of the final velocities, v_ref from chainrun at rtol = {REFERENCE_RTOL:g}")
        rows = []
        for case in p["cases"]:
            cr = next(t for t in case["tools"] if t["tool"] == "chainrun")
            proc_t, solv_t = cr.get("process_time"), cr.get("time")
            rows.append([str(case["n"]), "chainrun process", fmt_t(proc_t), "1", "-",
                         str(cr.get("events", "-")), str(cr.get("steps", "-")),
                         fmt_e(cr.get("error_vs_reference")), ""])
            rows.append(["", "chainrun solver", fmt_t(solv_t), "-", "1", "", "", "", ""])
            for t in case["tools"]:
                if t["tool"] in ("chainrun", "chainrun-cli"):
                    continue
                if t.get("time") is None:
                    rows.append(["", t["tool"], "-", "", "", "", "", "",
                                 t.get("skipped") or t.get("error", "")])
                    continue
                e = t.get("error_vs_reference")
                flag = " !" if e is not None and e > ACCURACY[t["tool"]] else ""
                rows.append(["", t["tool"], fmt_t(t["time"]),
                             f"{t['time'] / proc_t:.3g}" if proc_t else "-",
                             f"{t['time'] / solv_t:.3g}" if solv_t else "-",
                             str(t["events"]), str(t["steps"]), fmt_e(e) + flag,
                             f"+{fmt_t(t['compile_time'])} s compile" if t["tool"] == "heyoka"
                             else ""])
        out.append(table(["N", "tool", "time s", "x proc", "x solver", "events", "steps",
                          "error", "note"], rows, "llrrrrrrl"))
        out.append("")
        out.append("Agreement (pairwise max |v_a - v_b| within the sum of claimed accuracies "
                   + ", ".join(f"{k} {v:g}" for k, v in ACCURACY.items() if k != "chainrun-cli")
                   + "):")
        for case in p["cases"]:
            ag = case["agreement"]
            bad = [f"{q['a']}~{q['b']} {q['max_diff']:.1e} > {q['allowed']:.0e}"
                   for q in ag["pairs"] if not q["ok"]]
            bad += [f"{o['tool']} error {o['error']:.1e} > claimed {o['claimed']:.0e}"
                    for o in ag["off"]]
            worst = max(ag["pairs"], key=lambda q: q["max_diff"] / q["allowed"], default=None)
            line = f"  N = {case['n']}: " + ("all agree" if ag["ok"] else "DISAGREE: " + "; ".join(bad))
            if worst and ag["ok"]:
                line += (f" (closest to its bound: {worst['a']}~{worst['b']} "
                         f"{worst['max_diff']:.1e} <= {worst['allowed']:.0e})")
            out.append(line)
    s = res.get("scaling")
    if s:
        out.append("")
        out.append("Scaling to the terminal state (chainrun: in-process solver time; peers: as "
                   "above for Hertz, until chainrun's terminal time for linear):")
        for kind, title in (("hertz", "Hertz"), ("linear", "linear")):
            series = s[kind]
            ns = sorted({pt["n"] for pts in series.values() for pt in pts})
            tools = list(series)
            rows = []
            for n in ns:
                row = [str(n)]
                for tool in tools:
                    pt = next((q for q in series[tool] if q["n"] == n), None)
                    if pt is None:
                        row.append("")
                    elif pt.get("time") is None:
                        row.append("skip" if pt.get("skipped") else "limit")
                    else:
                        row.append(fmt_t(pt["time"]))
                rows.append(row)
            fits = s["fits"][kind]
            rows.append(["exponent"] + [f"{fits[t]['exponent']:.2f}" if fits.get(t) else "-"
                                        for t in tools])
            rows.append(["(last pair)"] + [f"{fits[t]['local_exponent']:.2f}" if fits.get(t)
                                           else "-" for t in tools])
            out.append(f"  {title}, K = 1: time s")
            out.append("    " + table(["N"] + tools, rows).replace("\n", "\n    "))
        lin_errs = [(tool, pt["n"], pt["error_vs_reference"]) for tool, pts in s["linear"].items()
                    if tool != "chainrun" for pt in pts if "error_vs_reference" in pt]
        if lin_errs:
            out.append("  linear peers' errors: " + ", ".join(
                f"{t} N={n} {e:.1e}{' !' if e > ACCURACY[t] else ''}" for t, n, e in lin_errs))
        for kind in ("hertz", "linear"):
            for pt in s[kind]["chainrun"]:
                if pt.get("skipped") or pt.get("error"):
                    out.append(f"  {kind} N = {pt['n']}: {pt.get('skipped') or pt.get('error')}")
    tg = res.get("targets")
    if tg:
        out.append("")
        out.append("Targets: whole chainrun simulate process (start-up, imports, numba cache "
                   "load, solver, HDF5 file), K = 1, to the terminal state:")
        for t in tg:
            times = ", ".join(fmt_t(w) for w in t["walls"]) or "-"
            verdict = (f"met in {t['runs_within_limit']} of {len(t['walls'])} runs"
                       if t["walls"] else "no run finished")
            if t["errors"]:
                verdict += f"  [{t['errors'][0]}]"
            out.append(f"  {t['label']} N = {t['n']}: {times} s (limit {t['limit']:g} s): "
                       + ("MET, " if t["met"] else "NOT MET, ") + verdict)
    k = res.get("k80")
    if k:
        out.append("")
        if k.get("time") is not None:
            out.append(f"N = 2000, K = 80, Hertz, to the terminal state: {fmt_t(k['time'])} s "
                       f"in-process, {fmt_t(k.get('process_time'))} s as a process (--full); "
                       f"terminal t = {k['end_time']:.6g}, {k['events']} events, "
                       f"{k['steps']} steps, {k.get('closed_form', 0)} collisions in "
                       f"closed form")
        else:
            out.append(f"N = 2000, K = 80, Hertz, to the terminal state: {k.get('error')}")
    mem = res.get("memory")
    if mem:
        out.append("")
        until = (f"t_end = {mem['t_end']:g}" if mem["t_end"] is not None
                 else "the terminal state")
        out.append(f"Peak resident memory of chainrun simulate, N = {mem['n']}, until {until}:")
        for r in mem["runs"]:
            out.append(f"  {r['snapshots']:4d} snapshots: {fmt_t(r['maxrss_mb'])} MB, "
                       f"{fmt_t(r['wall'])} s" + (f"  [{r['error']}]" if r["error"] else ""))
    if res.get("general"):
        out.append("")
        out.extend(report_general(res["general"]))
    if res.get("previous"):
        out.append("")
        out.extend(report_previous(res["previous"]))
    if res.get("lammps"):
        from benchmarks import against_lammps

        out.append("")
        out.extend(against_lammps.report(res["lammps"]))
    if res["notes"]:
        out.append("")
        out.extend(f"Note: {n}" for n in res["notes"])
    out.append("")
    out.append(f"Total {res['total_time']:.0f} s. JSON: {res['json']}")
    return "\n".join(out)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items() if k != "final_velocity"}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--full", action="store_true",
                        help="the largest cases too (N = 10^6 Hertz and 10^5 linear to the "
                             "terminal state, scipy to N = 4000, heyoka and RK4 to N = 10^4, "
                             "memory to the terminal state); hours, not minutes")
    parser.add_argument("--smoke", action="store_true",
                        help="tiny sizes, to check the harness itself in about two minutes")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS),
                        help="run only these sections")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "bench",
                        help="folder of the JSON and text reports [default: results/bench]")
    parser.add_argument("--against", metavar="REV", default=None,
                        help="the previous version the section 'previous' compares with, any "
                             f"git revision [default: ${AGAINST_ENV} if set, else the solver "
                             f"before its latest change: HEAD if {SOLVER_PATH}/ has uncommitted "
                             "changes, otherwise the first parent of the newest commit on "
                             "HEAD's first-parent history that changed it]")
    args = parser.parse_args(argv)
    mode = Mode.make(args.full, args.smoke)
    # a TERM unwinds like an interrupt: the running process is killed, the previous
    # version's worktree and the scratch folder removed
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    started = time.perf_counter()
    now = dt.datetime.now()
    res = {"date": now.isoformat(timespec="seconds"), "full": mode.full, "smoke": args.smoke,
           "argv": sys.argv[1:] if argv is None else list(argv), "machine": machine_info(),
           "versions": versions(), "git_commit": git_commit(), "load_start": os.getloadavg(),
           "accuracy_claims": ACCURACY, "notes": []}
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f"bench-{now:%Y-%m-%d-%H%M%S}"
    res["json"] = str(args.out / f"{stem}.json")
    scratch = Path(tempfile.mkdtemp(prefix="chainrun-bench-"))
    procs = Processes(scratch)
    try:
        # warm numba's cache (chainrun's kernels, the RK4 peer) before anything is timed
        log("warm-up: chainrun simulate and the in-process solver, numba cache warm")
        procs.run(config_text("warmup", 50, 1, 1.5, times=[0.0, 10.0]), read_velocity=False)
        simulate_until(50, 1, 1.5, times=[0.0, 10.0])
        if "compile" in args.only:
            res["compile"] = section_compile(procs)
        if "peers" in args.only:
            res["peers"] = section_peers(mode, procs, res["notes"])
        if "scaling" in args.only:
            res["scaling"] = section_scaling(mode, res.get("peers"), res["notes"])
        if "targets" in args.only:
            res["targets"] = section_targets(mode, procs)
        if "k80" in args.only:
            res["k80"] = section_k80(mode, procs)
        if "memory" in args.only:
            res["memory"] = section_memory(mode, procs)
        if "general" in args.only:
            res["general"] = section_general(mode, procs)
        if "previous" in args.only:
            res["previous"] = section_previous(mode, procs, args.against)
        if "lammps" in args.only:
            from benchmarks import against_lammps

            res["lammps"] = against_lammps.section(mode, procs, res["notes"])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    res["load_end"] = os.getloadavg()
    res["total_time"] = time.perf_counter() - started
    text = report(res)
    Path(res["json"]).write_text(json.dumps(_jsonable(res), indent=1) + "\n")
    (args.out / f"{stem}.txt").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
