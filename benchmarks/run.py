"""``make bench``: chainrun against its peers, in one run.

This module owns the bench's command: it parses the arguments, runs the sections asked
for (``benchmarks.sections``, each within the bounds of ``Mode``), and writes the
report: printed, and with everything measured as JSON, into ``results/bench/`` (so runs
can be compared over time); each section's result also replaces its entry of
``benchmarks/results.json``, from which ``benchmarks/results.md`` and README.md's
measured numbers are written (``benchmarks.results``). See ``benchmarks/README.md``
for what each column means.

Sections (each bounded in time; ``--full`` lifts the bounds for the largest cases):

1. compile: the first run's numba compilation (a fresh ``NUMBA_CACHE_DIR``).
2. peers: Hertz line, K = 1, until t = 1.25 N + 20, N = 250, 1000, 4000; errors of
   the final velocities against chainrun at rtol = 1e-14 to the same time; the
   agreement check.
3. scaling: Hertz N = 250 ... 10^6 and linear N = 100 ... 10^5, to the terminal
   state; the fitted exponent of time versus N for each tool.
4. targets: the timed targets (issue 34's) as whole ``chainrun simulate`` processes,
   to the terminal state, each run three times, with each run's events and wall time
   per event: Hertz N = 2000, K = 80 (a cascade; limit 10 s), the random line N = 1000
   (3 s), the damped steel line N = 3000 (5 s), Hertz N = 10^6 (5 s) and linear
   N = 10^5 (3 s), K = 1; Hertz N = 10^4 no slower than the previous version is read
   in section previous.
5. k80: N = 2000, K = 80, Hertz, to the terminal state.
   steered: the K = 80 cascade and the random line N = 1000, whose ends rounding
   steers, at rtol and rtol/10: balances, the terminal state checked from the final
   state, and statistics of the final velocities within the spread first measured.
6. memory: peak resident memory of ``chainrun simulate``, N = 10^6, 200 snapshots
   (and 2, to show it does not depend on their number).
7. general: the paper's Hertz line against a random one (masses and stiffnesses
   uniform in [1, 10), fixed seeds), K = 1, to the terminal state, as processes, and
   the ratio (the requirement: within 2x at N = 10^6); a random-line size predicted
   over its cap is skipped. The steel line in SI units against the paper's, N = 10^5.
8. previous: this version against a previous one (``--against REV``; by default the
   solver before its latest change), checked out into a temporary git worktree, on
   Hertz N = 10^4 and 10^6, linear N = 10^5, the random line N = 1000 and the damped
   line N = 3000, the two versions' runs alternating; Hertz N = 10^4 is a target (no
   slower).
9. lammps: chainrun against LAMMPS (optional) on lines of steel spheres, elastic and
   damped: two-ball checks and restitutions, accuracy against the time step and rtol
   (N = 20), and whole-process times at N = 2000, 10^4 (elastic) and 3000 (damped)
   (``benchmarks.against_lammps``).

Examples::

    python -m benchmarks.run                 # default, about 50 minutes
    python -m benchmarks.run --full          # everything, the largest cases too
    python -m benchmarks.run --only peers scaling
    python -m benchmarks.run --only previous --against main~3
    python -m benchmarks.run --smoke         # the harness itself, two minutes
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import shutil
import signal
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks import results
from benchmarks.harness import (ACCURACY, ROOT, SHORT, Case, Context, Processes, config_text,
                                git_commit, jsonable, log, machine_info, solve_paper,
                                versions)
from benchmarks.sections import SECTIONS, module
from benchmarks.worktree import AGAINST_ENV, SOLVER_PATH


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
    # steered: lines whose end rounding steers, in-process at rtol and rtol/10, each run
    # stopped after steered_timeout seconds
    steered: tuple = (Case("Hertz", 2000, k=80), Case.random(1000))
    steered_timeout: float | None = 1800.0
    memory_t_end: float | None = 1000.0
    memory_n: int = 1_000_000
    # targets (issue 34's): whole processes to the terminal state, each within its limit
    # (seconds); a run over target_over x its limit is not repeated; each run is stopped
    # after the larger of target_timeout and 10 x its limit
    targets: tuple = (Case("Hertz", 2000, k=80, limit=10.0),
                      Case.random(1000, limit=3.0),
                      Case.damped(3000, limit=5.0),
                      Case("Hertz", 1_000_000, limit=5.0),
                      Case("linear", 100_000, alpha=1.0, limit=3.0))
    target_runs: int = 3
    target_over: float = 3.0
    target_timeout: float = 900.0
    # general: the paper's Hertz line against RANDOM_LINE, to the terminal state; a
    # random-line size predicted over general_cap seconds is skipped (the requirement is
    # read at the largest N)
    general_n: tuple = (300, 1000, 10_000, 1_000_000)
    general_cap: float = 60.0
    general_runs: int = 3
    units_n: int = 100_000            # the SI steel line against the paper's
    # previous: lines to the terminal state, both versions alternating; no_slower marks
    # a target read as new/old, met where the ratio of the medians is at most
    # 1 + previous_slack (the drift alternating leaves)
    previous_cases: tuple = (Case("Hertz", 10_000, no_slower=True),
                             Case("Hertz", 1_000_000), Case("linear", 100_000, alpha=1.0),
                             Case.random(1000), Case.damped(3000))
    previous_runs: int = 5
    previous_slack: float = 0.05
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
                       steered=(Case("Hertz", 200, k=8), Case.random(60)),
                       steered_timeout=60.0,
                       memory_t_end=20.0, memory_n=10_000,
                       targets=(Case("Hertz", 200, k=8, limit=10.0),
                                Case.random(100, limit=3.0), Case.damped(100, limit=5.0),
                                Case("Hertz", 2000, limit=5.0),
                                Case("linear", 500, alpha=1.0, limit=3.0)),
                       target_runs=2, target_timeout=120.0,
                       general_n=(30, 100, 300), general_cap=10.0,
                       general_runs=2, units_n=1000,
                       previous_cases=(Case("Hertz", 200, no_slower=True),
                                       Case("Hertz", 2000), Case("linear", 500, alpha=1.0),
                                       Case.random(100), Case.damped(100)),
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
                   steered_timeout=None,
                   general_cap=4 * 3600.0, lammps_cap=math.inf)


def report(meta: dict, done: dict, notes: list[str]) -> str:
    """The report: the run's circumstances, each section's lines, the notes."""
    m = meta["machine"]
    out = [f"chainrun benchmark, {meta['date']} ({meta['mode']} mode)",
           f"{m.get('cpu', m['machine'])}, {m['cpus']} cores, {m.get('memory_gb')} GB; "
           f"commit {(meta['git_commit'] or '?')[:12]}; load average "
           f"{meta['load_start'][0]:.1f} at start, {meta['load_end'][0]:.1f} at end",
           f"Times are wall seconds; runs under {SHORT:g} s are repeated (3 times, 5 under "
           f"{SHORT / 10:g} s) and the minimum kept, as the machine may be shared."]
    for name in SECTIONS:
        if name in done:
            out += ["", *done[name].lines()]
    if notes:
        out.append("")
        out.extend(f"Note: {n}" for n in notes)
    out.append("")
    out.append(f"Total {meta['total_time']:.0f} s. JSON: {meta['json']}")
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.run", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--full", action="store_true",
                        help="the largest cases too (N = 10^6 Hertz and 10^5 linear to the "
                             "terminal state, scipy to N = 4000, heyoka and RK4 to N = 10^4, "
                             "memory to the terminal state); hours, not minutes")
    parser.add_argument("--smoke", action="store_true",
                        help="tiny sizes, to check the harness itself in about two minutes "
                             "(its results go to --out, not to benchmarks/results.json)")
    parser.add_argument("--only", nargs="+", choices=list(SECTIONS), default=list(SECTIONS),
                        help="run only these sections")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "bench",
                        help="folder of the JSON and text reports [default: results/bench]")
    parser.add_argument("--results", type=Path, default=None,
                        help="the results file each section updates [default: "
                             "benchmarks/results.json, whose numbers README.md quotes; "
                             "with --smoke, results.json in --out]")
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
    meta = {"date": now.isoformat(timespec="seconds"),
            "mode": "smoke" if args.smoke else ("full" if mode.full else "default"),
            "argv": sys.argv[1:] if argv is None else list(argv), "machine": machine_info(),
            "versions": versions(), "git_commit": git_commit(),
            "load_start": os.getloadavg()}
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f"bench-{now:%Y-%m-%d-%H%M%S}"
    meta["json"] = str(args.out / f"{stem}.json")
    results_file = args.results or (args.out / "results.json" if args.smoke
                                    else results.RESULTS)
    scratch = Path(tempfile.mkdtemp(prefix="chainrun-bench-"))
    ctx = Context(mode, Processes(scratch), against=args.against,
                  recorded=results.load(results_file)["sections"])
    data = None
    try:
        # warm numba's cache (chainrun's kernels, the RK4 peer) before anything is timed
        log("warm-up: chainrun simulate and the in-process solver, numba cache warm")
        ctx.procs.run(config_text("warmup", 50, 1, 1.5, times=[0.0, 10.0]),
                      read_velocity=False)
        solve_paper(50, 1, 1.5, times=[0.0, 10.0])
        for name in SECTIONS:
            if name not in args.only:
                continue
            load_start, t0, noted = os.getloadavg(), time.perf_counter(), len(ctx.notes)
            date = dt.datetime.now().isoformat(timespec="seconds")
            ctx.results[name] = module(name).run(ctx)
            data = results.update(results_file, name, results.entry(
                ctx.results[name], meta=meta, date=date, load_start=load_start,
                load_end=os.getloadavg(), wall=time.perf_counter() - t0,
                notes=ctx.notes[noted:]))
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    if data is not None and results_file.resolve() == results.RESULTS.resolve():
        results.rewrite_readme(data)
    meta["load_end"] = os.getloadavg()
    meta["total_time"] = time.perf_counter() - started
    text = report(meta, ctx.results, ctx.notes)
    everything = dict(meta, notes=ctx.notes, accuracy_claims=ACCURACY,
                      **{name: r.to_json() for name, r in ctx.results.items()})
    Path(meta["json"]).write_text(json.dumps(jsonable(everything), indent=1) + "\n")
    (args.out / f"{stem}.txt").write_text(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
