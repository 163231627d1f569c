"""The bench's shared helpers: the one call of chainrun's solver, timing with repeats,
chainrun as a whole process, generated configs, the machine, and the report's formats.

Every section of ``benchmarks.sections`` (and ``benchmarks.against_lammps``) measures
through these, so that a repeat, a time limit or a process run means the same in all
of them. ``solve`` is the only place the benchmarks call the solver: a change of its
entry point is adapted there.
"""

from __future__ import annotations

import json
import math
import os
import platform
import shutil
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

#: The accuracy each tool claims for the final velocities (max abs error, paper
#: units): chainrun's target, the scipy and heyoka settings' measured accuracy with a
#: margin, and the paper's RK4 at dt = 0.02 (about 1e-7).
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
#: A steel line in SI units: beads of one inch, the first striking at 0.5 m/s.
SI_LINE = {"speed": 0.5, "diameter": 0.0254, "material": "steel"}
#: The damped line: the steel line with Tsuji damping for a restitution of 0.9 (the
#: lammps section's damped line, and the targets').
DAMPED_LINE = dict(SI_LINE, restitution=0.9, damping_law="tsuji")


def log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


@dataclass
class Context:
    """What every section is given: its bounds (``benchmarks.run.Mode``), the process
    runner, the run's notes, the previous section's revision, the results of the
    sections run before it in this run (the scaling section reuses the peers' runs),
    and the results file's entries as they were before this run (``recorded``: the
    section ``steered`` judges by the tolerance it recorded)."""

    mode: object
    procs: "Processes"
    notes: list = field(default_factory=list)
    against: str | None = None
    results: dict = field(default_factory=dict)
    recorded: dict = field(default_factory=dict)


# --- the solver ----------------------------------------------------------------------------


class Deadline(Exception):
    """Raised from the solver's progress hook when a run exceeds its time limit."""


def paper_line(n: int, k: int, alpha: float):
    """The paper's line: ``n`` unit balls, the first ``k`` at velocity 1, ``alpha``."""
    from chainrun.solver import Line

    return Line.paper(n, k, alpha)


def solve(line, times=(), *, t_end=None, rtol=None, closed_form=True, timeout=None,
          on_progress=None):
    """Run ``line`` with chainrun's solver in this process: the benchmarks' one call
    of it. A run still going after ``timeout`` seconds raises ``Deadline``;
    ``on_progress(t)`` is called as the solver reports its time."""
    from chainrun.solver import DEFAULT_RTOL, simulate

    start = time.perf_counter()

    def progress(t):
        if timeout is not None and time.perf_counter() - start > timeout:
            raise Deadline(f"not finished after {timeout:.0f} s (reached t = {t:.4g})")
        if on_progress is not None:
            on_progress(t)

    return simulate(line, times, t_end=t_end, closed_form=closed_form,
                    rtol=DEFAULT_RTOL if rtol is None else rtol, on_progress=progress)


def solve_paper(n, k, alpha, *, t_end=None, rtol=None, timeout=None, times=()):
    """``solve`` on the paper's line of ``n`` balls, ``k`` strikers, ``alpha``."""
    return solve(paper_line(n, k, alpha), times, t_end=t_end, rtol=rtol, timeout=timeout)


def chainrun_point(n, k, alpha, *, t_end=None, timeout=None, short=SHORT) -> dict:
    """One in-process chainrun run of the paper's line (repeated when short): time,
    counts, final state."""
    try:
        sol, best, times = timed(lambda: solve_paper(n, k, alpha, t_end=t_end,
                                                     timeout=timeout), short=short)
    except Deadline as exc:
        return {"n": n, "time": None, "error": str(exc)}
    d = sol.diagnostics
    return {"n": n, "time": best, "times": times, "steps": d.steps, "events": d.events,
            "closed_form": d.closed_form_collisions,
            "end_time": sol.end_time, "outcome": sol.outcome.value,
            "max_window": d.max_window, "energy_error": d.energy_error,
            "momentum_error": d.momentum_error, "final_velocity": sol.final_velocity}


# --- timing and numbers --------------------------------------------------------------------


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


def median(xs) -> float | None:
    return float(np.median(xs)) if len(xs) else None


def ratio(a: dict, b: dict, stat=median) -> float | None:
    """stat(a's walls) / stat(b's walls), None unless both have times."""
    if not a or not b or not a["walls"] or not b["walls"]:
        return None
    return stat(a["walls"]) / stat(b["walls"])


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


def predict(points: list[tuple[int, float]], n_next: int) -> float:
    """Time at n_next from the last points, assuming at least linear growth."""
    (n1, t1) = points[-1]
    slope = 2.0
    if len(points) >= 2:
        n0, t0 = points[-2]
        if t0 > 0.05 and t1 > 0:
            slope = max(1.0, math.log(t1 / t0) / math.log(n1 / n0))
    return t1 * (n_next / n1) ** slope


def jsonable(obj):
    """``obj`` as JSON: numpy scalars as numbers, non-finite floats as null, tuples as
    lists, and no ``final_velocity`` arrays (they are compared, not kept)."""
    if isinstance(obj, dict):
        return {k: jsonable(v) for k, v in obj.items() if k != "final_velocity"}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


# --- the report's formats ------------------------------------------------------------------


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


def times_text(walls) -> str:
    return ", ".join(fmt_t(w) for w in walls) or "-"


def ratio_text(r: float | None) -> str:
    if r is None:
        return "-"
    return f"{r:.2f}" if r < 100 else f"{r:.3g}"


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


def pythonpath(first: Path) -> str:
    """$PYTHONPATH with ``first`` in front: a process that imports chainrun from it."""
    rest = os.environ.get("PYTHONPATH")
    return str(first) + (os.pathsep + rest if rest else "")


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


#: What a report says of each kind of line a ``Case`` names.
ABOUT = {"Hertz": "the paper's line, unit balls, the first K at velocity 1, alpha = 1.5",
         "linear": "the paper's line with alpha = 1",
         "random": "masses and stiffnesses uniform in [1, 10) (numpy seeds 1 and 2), Hertz, "
                   "K = 1",
         "damped": "steel beads of one inch in SI units, the first at 0.5 m/s, Tsuji "
                   "damping for a restitution of 0.9, K = 1"}


@dataclass(frozen=True)
class Case:
    """A line timed as whole ``chainrun simulate`` processes to its terminal state.

    ``label`` names its kind (``Hertz``, ``linear``: the paper's line; ``random``:
    ``RANDOM_LINE``; ``damped``: ``DAMPED_LINE``), with ``n`` balls, ``k`` strikers,
    ``alpha`` (None: the material's law), the keys ``chain`` adds to ``[chain]`` and
    ``top`` at the top level (``config_text``). As a target: ``limit``, its seconds,
    or ``no_slower``, read as new/old against the previous version (section
    ``previous``)."""

    label: str
    n: int
    k: int = 1
    alpha: float | None = 1.5
    chain: dict | None = None
    top: dict | None = None
    limit: float | None = None
    no_slower: bool = False

    @classmethod
    def random(cls, n: int, **kwargs) -> "Case":
        """The random line (``RANDOM_LINE``, Hertz) of ``n`` balls."""
        return cls("random", n, chain=dict(RANDOM_LINE), **kwargs)

    @classmethod
    def damped(cls, n: int, **kwargs) -> "Case":
        """The damped steel line (``DAMPED_LINE``, SI units) of ``n`` balls."""
        return cls("damped", n, alpha=None, chain=dict(DAMPED_LINE), top={"units": "si"},
                   **kwargs)

    @property
    def name(self) -> str:
        """As the report names it: ``Hertz N = 2000, K = 80``."""
        return f"{self.label} N = {self.n}" + (f", K = {self.k}" if self.k != 1 else "")

    def config(self, prefix: str) -> str:
        """Its experiment file, named ``prefix-label-n[-kK]``."""
        name = f"{prefix}-{self.label.lower()}-{self.n}" + (f"-k{self.k}" if self.k != 1
                                                             else "")
        return config_text(name, self.n, self.k, self.alpha, chain=self.chain, top=self.top)


@dataclass
class ProcessRun:
    wall: float | None
    cpu: float | None
    maxrss_mb: float | None
    final_velocity: np.ndarray | None = None
    error: str | None = None
    diagnostics: dict | None = None       # the run file's /diagnostics and outcome


class Processes:
    """Runs ``chainrun simulate`` on generated configs in a scratch folder.

    A process given no ``env`` imports chainrun from this checkout (``ROOT`` first on
    its ``PYTHONPATH``): each runs in a folder of the scratch, where a relative entry
    such as ``PYTHONPATH=.`` would name that folder and let the process import
    whichever chainrun the interpreter has installed."""

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
        if env is None:
            env = dict(os.environ, PYTHONPATH=pythonpath(ROOT))
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
