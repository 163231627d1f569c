"""What a line's moving part is made of over its run: clusters and their sizes.

The solver integrates the balls joined by compressed contacts, cluster by cluster, on one
clock: every event ends the step of every cluster, so an event's cost is the whole
window's. This runs a line to its terminal state, then again with snapshots spread over
that time, and at each snapshot counts the clusters (runs of balls joined by contacts
compressed beyond ``--floor`` of the impact speed's length scale, from the snapshot's
positions) and their sizes, and the speeds of the balls in them::

    .venv/bin/python -m benchmarks.window random --n 1000     # the bench's random line
    .venv/bin/python -m benchmarks.window damped --n 1000     # the damped steel line
    .venv/bin/python -m benchmarks.window hertz --n 2000 --k 80

Read from the snapshots, not the solver's state: a contact pressed below the floor (a
fresh one at a wave's front, a slow press) is not counted, so the numbers describe the
clusters a step must integrate, not the solver's bookkeeping bit for bit.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks.harness import DAMPED_LINE, config_text, paper_line, solve
from benchmarks.random_events import random_line


def make_line(kind: str, n: int, k: int):
    """The line of ``kind`` (random, damped, hertz, linear) with n balls (k strikers
    for the paper's lines)."""
    if kind == "random":
        return random_line(n)
    if kind == "damped":
        from chainrun.config import parse_experiment

        text = config_text(f"window-damped-{n}", n, 1, None, top={"units": "si"},
                           chain=dict(DAMPED_LINE))
        (spec,) = parse_experiment(text, "toml").runs()
        return spec.line
    return paper_line(n, k, 1.5 if kind == "hertz" else 1.0)


def clusters(compressed: np.ndarray) -> np.ndarray:
    """Sizes (in balls) of the runs of contacts compressed, from a boolean per contact."""
    c = np.concatenate(([False], compressed, [False])).astype(np.int8)
    starts = np.flatnonzero(np.diff(c) == 1)
    ends = np.flatnonzero(np.diff(c) == -1)
    return ends - starts + 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=("random", "damped", "hertz", "linear"))
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--k", type=int, default=1)
    parser.add_argument("--snapshots", type=int, default=24)
    parser.add_argument("--floor", type=float, default=1e-9,
                        help="compression counted as a contact, over the line's length scale")
    args = parser.parse_args(argv)
    from chainrun.solver import load_kernels

    load_kernels()
    line = make_line(args.kind, args.n, args.k)
    t0 = time.perf_counter()
    first = solve(line)
    wall = time.perf_counter() - t0
    d = first.diagnostics
    end = float(first.end_time)
    if end <= 0.0:
        print("nothing moves")
        return 0
    print(f"{args.kind} N = {args.n}, K = {args.k}: terminal at t = {end:.6g} "
          f"({wall:.1f} s); {d.events:,} events, {d.steps:,} steps "
          f"({d.rejected_steps:,} rejected), window up to {d.max_window:,} balls")
    # most of a run's events come early (a random line's last collisions come 1e5 times
    # later than its busy part): snapshots spread in the logarithm of time, from ten of
    # the line's time units
    times = np.geomspace(min(10.0 * line.scales().time, end), end, args.snapshots)
    sol = solve(line, times)
    length = line.scales().length
    speed = line.scales().velocity
    print(f"{'t':>11}  {'clusters':>8}  {'balls':>6}  {'largest sizes':<22}  "
          f"{'median |v|':>10}  {'max |v|':>8}  (speeds over the impact's)")
    for t, x, v in zip(times, sol.positions, sol.velocities):
        c = x[:-1] - x[1:] - line.gap  # each contact between two balls
        sizes = clusters(c > args.floor * length)
        inside = np.zeros(line.n, bool)
        edges = np.concatenate(([False], c > args.floor * length, [False]))
        inside[edges[:-1] | edges[1:]] = True
        top = ", ".join(str(s) for s in np.sort(sizes)[::-1][:4])
        u = np.abs(v[inside]) / speed if inside.any() else np.zeros(1)
        print(f"{t:11.4g}  {sizes.size:8d}  {int(sizes.sum()):6d}  {top:<22}  "
              f"{np.median(u):10.2e}  {u.max():8.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
