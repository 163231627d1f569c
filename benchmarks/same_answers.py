"""Whether this version gives the same answers as another: eight lines, both versions.

A change meant to keep the solver's results (a faster loop, a tidier kernel) should
keep them to the bit, or move them by no more than the rounding it changes. This runs
eight lines in this tree and in a revision checked out into a temporary worktree (its
own numba cache: its first run compiles), and prints, for each line, whether the final
velocities, event times and snapshots are the same bits, the two step counts, and the
largest difference of the final velocities. With ``--spread``, the other revision also
runs each line at a tenth of the tolerance: on a line whose outcome is steered by
rounding, the difference between the versions is to be read against that one::

    .venv/bin/python -m benchmarks.same_answers --against 9b0746c
    .venv/bin/python -m benchmarks.same_answers --against HEAD --spread

The lines: the paper's Hertz line of 10^5 balls, linear lines of 20000 and 10^5, alpha
= 2 at N = 2000, K = 40 at N = 400, and three lines with a cascade of collisions (random
masses and stiffnesses with Hertz contacts, N = 300; alternating linear and Hertz
contacts, N = 500; random masses with linear contacts, N = 300). Each takes 11
snapshots up to t = 50. The other revision needs ``Line.make``.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
TIMES = np.linspace(0.0, 50.0, 11)


def lines():
    """The eight lines, by name (built with whichever chainrun is imported)."""
    from chainrun.solver import Line

    rng = np.random.default_rng(3)
    n = 300
    mass = rng.uniform(0.5, 2.0, n)
    stiffness = rng.uniform(0.5, 2.0, n - 1)
    return {
        "Hertz 10^5": Line.make(100_000, k=1, alpha=1.5),
        "linear 20000": Line.make(20_000, k=1, alpha=1.0),
        "linear 10^5": Line.make(100_000, k=1, alpha=1.0),
        "alpha 2, 2000": Line.make(2000, k=1, alpha=2.0),
        "K 40, 400": Line.make(400, k=40, alpha=1.5),
        "random Hertz 300": Line.make(n, alpha=1.5, mass=mass, stiffness=stiffness),
        "mixed 500": Line.make(500, k=1, alpha=np.where(np.arange(499) % 2 == 0, 1.0, 1.5)),
        "random linear 300": Line.make(n, k=1, alpha=1.0, mass=rng.uniform(0.5, 2.0, n)),
    }


def emit(out: str, rtol_factor: float) -> None:
    """Run the lines with the chainrun on sys.path; save their results into ``out``."""
    from chainrun.solver import DEFAULT_RTOL, load_kernels, simulate

    load_kernels()
    saved = {}
    for i, (name, line) in enumerate(lines().items()):
        t = time.perf_counter()
        sol = simulate(line, times=TIMES, rtol=DEFAULT_RTOL * rtol_factor)
        print(f"  {name}: {time.perf_counter() - t:.2f} s", file=sys.stderr, flush=True)
        saved[f"{i}_v"] = sol.final_velocity
        saved[f"{i}_t"] = sol.event_time
        saved[f"{i}_x"] = sol.positions
        saved[f"{i}_steps"] = np.array(sol.diagnostics.steps)
    np.savez(out, **saved)


def run_version(tree: Path, out: Path, cache: Path | None, rtol_factor: float = 1.0):
    env = dict(os.environ, PYTHONPATH=str(tree))
    if cache is not None:
        env["NUMBA_CACHE_DIR"] = str(cache)
    subprocess.run([sys.executable, str(Path(__file__).resolve()), "--emit", str(out),
                    "--rtol-factor", repr(rtol_factor)], env=env, check=True)
    return np.load(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", help="the other revision (a commit, tag or branch)")
    parser.add_argument("--spread", action="store_true",
                        help="run the other revision at a tenth of the tolerance too")
    parser.add_argument("--emit", help=argparse.SUPPRESS)
    parser.add_argument("--rtol-factor", type=float, default=1.0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.emit:
        emit(args.emit, args.rtol_factor)
        return 0
    if not args.against:
        parser.error("--against REVISION is required")
    sys.path.insert(0, str(ROOT))
    from benchmarks.run import git

    commit = git(ROOT, "rev-parse", "--verify", f"{args.against}^{{commit}}")
    with tempfile.TemporaryDirectory(prefix="chainrun-same-") as scratch:
        scratch = Path(scratch)
        tree = scratch / "other"
        git(ROOT, "worktree", "add", "--detach", str(tree), commit)
        try:
            print(f"this tree ({ROOT})", file=sys.stderr)
            new = run_version(ROOT, scratch / "new.npz", None)
            print(f"{commit[:12]} (its first run compiles into its own cache)",
                  file=sys.stderr)
            old = run_version(tree, scratch / "old.npz", scratch / "numba")
            fine = None
            if args.spread:
                print(f"{commit[:12]} at a tenth of the tolerance", file=sys.stderr)
                fine = run_version(tree, scratch / "fine.npz", scratch / "numba", 0.1)
        finally:
            git(ROOT, "worktree", "remove", "--force", str(tree))
        print(f"this tree against {commit[:12]}:")
        head = f"{'line':18s} {'same bits':9s} {'steps new':>10s} {'steps old':>10s} " \
               f"{'max |dv|':>9s}"
        print(head + (f" {'old vs old at rtol/10':>22s}" if fine is not None else ""))
        for i, name in enumerate(lines()):
            same = all(np.array_equal(new[f"{i}_{k}"], old[f"{i}_{k}"]) for k in "vtx")
            dv = float(np.max(np.abs(new[f"{i}_v"] - old[f"{i}_v"])))
            row = (f"{name:18s} {'yes' if same else 'no':9s} {int(new[f'{i}_steps']):10d} "
                   f"{int(old[f'{i}_steps']):10d} {dv:9.2g}")
            if fine is not None:
                row += f" {float(np.max(np.abs(old[f'{i}_v'] - fine[f'{i}_v']))):22.2g}"
            print(row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
