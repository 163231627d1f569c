"""How many contact events a random line needs to reach its terminal state.

``make bench``'s section ``general`` times the random line (masses and stiffnesses
uniform in [1, 10), ``run.RANDOM_LINE``) against the paper's line. Its cost is set by its
events: struck by one ball, the paper's line has N - 1 of them, the random line far
more, as its fragments collide until their velocities are sorted. This counts them
with chainrun and, for the smaller lines, with the tests' reference solver
(``tests/reference.py``, scipy's DOP853 event by event, no code shared with the
kernels), so that the count is the model's, not an artefact of one solver::

    .venv/bin/python -m benchmarks.random_events            # N = 30, 60, 120, 240
    .venv/bin/python -m benchmarks.random_events 30 60 --reference-up-to 60

The reference solver takes about a minute at N = 120 and is skipped above
``--reference-up-to`` (default 60).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from benchmarks.run import RANDOM_LINE


def random_line(n: int):
    """The bench's random line of n balls, Hertz contacts, the first ball at velocity 1."""
    from chainrun.generators import check, expand
    from chainrun.solver import Line

    mass = expand(check(RANDOM_LINE["mass"]), n)
    stiffness = expand(check(RANDOM_LINE["stiffness"]), n - 1)
    return Line.make(n, alpha=1.5, mass=mass, stiffness=stiffness)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sizes", nargs="*", type=int, default=[30, 60, 120, 240])
    parser.add_argument("--reference-up-to", type=int, default=60)
    args = parser.parse_args(argv)
    from chainrun.solver import load_kernels, simulate

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from reference import reference_line

    load_kernels()
    print(f"{'N':>6} {'chainrun events':>16} {'s':>7} {'reference events':>17} {'s':>7}"
          f" {'events / N^2':>13}")
    for n in args.sizes:
        line = random_line(n)
        t0 = time.perf_counter()
        events = simulate(line).diagnostics.events
        t1 = time.perf_counter()
        ref, dt = "-", "-"
        if n <= args.reference_up_to:
            ref = len(reference_line(line, max_events=10**8).event_time)
            dt = f"{time.perf_counter() - t1:.1f}"
        print(f"{n:>6} {events:>16} {t1 - t0:>7.2f} {ref!s:>17} {dt:>7}"
              f" {events / n**2:>13.3f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
