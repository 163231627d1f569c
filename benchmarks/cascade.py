"""How far a collision cascade's outcome is determined: K impacting balls at N.

Many impacting balls break the line into fragments that keep colliding slowly, about
a million times for N = 2000, K = 80, many of the collisions crowded by a third ball.
The order and outcome of those crowded collisions depend on their timing to the last
digits, so the final velocities move with anything that moves a step's rounding.
This runs one line three ways and compares their final velocities:

* ``closed form``: the default, isolated binary collisions taken whole (exact);
* ``integrated``: every collision integrated (``closed_form=False``), at the same
  tolerance;
* ``integrated, rtol/10``: the same at a tenth of the tolerance.

The spread between the two integrated runs is the solver's own accuracy on this line;
the closed form's distance from either is to be read against it::

    .venv/bin/python -m benchmarks.cascade                 # N = 2000, K = 80 (~10 min)
    .venv/bin/python -m benchmarks.cascade --n 400 --k 40  # seconds

``--damping ETA --damping-exponent BETA`` damps every contact (isolated damped
collisions are taken whole too), and ``--random`` gives the line the bench's random
masses and stiffnesses (``random_events.random_line``), struck by its first ball::

    .venv/bin/python -m benchmarks.cascade --n 1000 --k 80 --damping 0.01 --damping-exponent 0.5
    .venv/bin/python -m benchmarks.cascade --n 300 --random --damping 0.01 --damping-exponent 0.25
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=2000)
    parser.add_argument("--k", type=int, default=80)
    parser.add_argument("--alpha", type=float, default=1.5)
    parser.add_argument("--rtol", type=float, default=None)
    parser.add_argument("--damping", type=float, default=0.0)
    parser.add_argument("--damping-exponent", type=float, default=0.0)
    parser.add_argument("--random", action="store_true",
                        help="the bench's random masses and stiffnesses, K = 1")
    args = parser.parse_args(argv)
    from chainrun.solver import DEFAULT_RTOL, Line, load_kernels, simulate

    from benchmarks.random_events import random_line

    rtol = DEFAULT_RTOL if args.rtol is None else args.rtol
    k = 1 if args.random else args.k
    if args.random:
        base = random_line(args.n)
        line = Line.make(args.n, alpha=args.alpha, mass=base.mass, stiffness=base.stiffness,
                         damping=args.damping, damping_exponent=args.damping_exponent)
    else:
        line = Line.make(args.n, k=k, alpha=args.alpha, damping=args.damping,
                         damping_exponent=args.damping_exponent)
    load_kernels()
    runs = {}
    print(f"N = {args.n}, K = {k}, alpha = {args.alpha:g}, rtol = {rtol:g}"
          + (", random masses and stiffnesses" if args.random else "")
          + (f", damping {args.damping:g}, exponent {args.damping_exponent:g}"
             if args.damping else ""))
    print(f"{'run':<22} {'s':>8} {'terminal t':>12} {'events':>9} {'closed form':>12}"
          f" {'steps':>9} {'rejected':>9} {'window':>7}")
    for name, kw in (("closed form", dict(rtol=rtol)),
                     ("integrated", dict(rtol=rtol, closed_form=False)),
                     ("integrated, rtol/10", dict(rtol=rtol / 10, closed_form=False))):
        t0 = time.perf_counter()
        sol = simulate(line, **kw)
        dt = time.perf_counter() - t0
        d = sol.diagnostics
        runs[name] = sol.final_velocity
        print(f"{name:<22} {dt:8.2f} {sol.end_time:12.4g} {d.events:9d}"
              f" {d.closed_form_collisions:12d} {d.steps:9d} {d.rejected_steps:9d}"
              f" {d.max_window:7d}")
    print(f"\n{'final velocities':<44} {'max |dv|':>10} {'median':>10}")
    names = list(runs)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            dv = np.abs(runs[a] - runs[b])
            print(f"{a + ' vs ' + b:<44} {dv.max():10.3g} {np.median(dv):10.3g}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
