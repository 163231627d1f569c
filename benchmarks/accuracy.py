"""Accuracy of the default tolerance against the line length N.

For Hertz lines (K = 1) of growing N, prints the largest difference of the final
velocities from the same line at rtol = 1e-14, for rtol = 1e-12 (the default) and
1e-13, with the energy error and steps per ball. Run: python -m benchmarks.accuracy
[N ...] (default 1000 10000 100000).
"""

from __future__ import annotations

import sys

import numpy as np

from chainrun.solver import Line, simulate


def main(sizes: list[int]) -> None:
    print(f"{'N':>8}  {'rtol':>7}  {'max |dv|':>9}  {'ball':>7}  {'|dE|/E':>8}  {'steps/ball':>10}")
    for n in sizes:
        ref = simulate(Line.paper(n, 1, 1.5), rtol=1e-14)
        for rtol in (1e-12, 1e-13):
            sol = simulate(Line.paper(n, 1, 1.5), rtol=rtol)
            d = np.abs(sol.final_velocity - ref.final_velocity)
            print(f"{n:>8}  {rtol:>7.0e}  {d.max():>9.2e}  {d.argmax() + 1:>7}  "
                  f"{sol.diagnostics.energy_error:>8.1e}  {sol.diagnostics.steps / n:>10.1f}",
                  flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [1000, 10000, 100000])
