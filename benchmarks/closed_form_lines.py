"""Isolated collisions taken whole against every collision integrated, on random gases.

Draws lines of 3-29 balls (random masses, stiffnesses, exponents, gaps and velocities;
some against walls, a Hertz one on the left and a linear one on the right), runs each
with ``closed_form=True`` and ``False`` (37 snapshots up to t = 50; t_end = 200 for a
line with no terminal state), and reports any run that fails, stalls (60 s without
progress) or breaks the momentum or energy balance by more than 1e-9, then the lines
whose final velocities, dissipated energies or dissipated-energy snapshots differ
most between the two. ``--damped`` damps 70% of the contacts and the walls (random
dampings in [0, 1), one law per line: dashpot, Kuwabara-Kono or Tsuji)::

    .venv/bin/python -m benchmarks.closed_form_lines --damped --seed 7 --draws 150
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def draw_line(rng, damped: bool):
    from chainrun.solver.model import Line, Wall

    n = int(rng.integers(3, 30))
    alpha = float(rng.choice([1.0, 1.5, 2.0]))
    kw = dict(mass=10 ** rng.uniform(-1, 1, n), alpha=alpha,
              stiffness=10 ** rng.uniform(-1, 1, n - 1),
              gap=rng.uniform(0, 2, n - 1) * (rng.random(n - 1) < 0.8),
              velocity=rng.uniform(-1, 1, n))
    left_damping = right_damping = 0.0
    if damped:
        kw["damping"] = rng.uniform(0, 1, n - 1) * (rng.random(n - 1) < 0.7)
        kw["damping_exponent"] = float(rng.choice([0.0, 0.5, (alpha - 1) / 2]))
        left_damping, right_damping = rng.uniform(0, 1, 2)
    kw["left"] = Wall(1.0, 1.5, 0.2, float(left_damping), 0.5 if damped else 0.0) \
        if rng.random() < 0.3 else None
    kw["right"] = Wall(2.0, 1.0, 0.0, float(right_damping), 0.0) \
        if rng.random() < 0.3 else None
    return Line.make(n, **kw)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--draws", type=int, default=150)
    parser.add_argument("--damped", action="store_true")
    parser.add_argument("--show", type=int, default=12, help="lines of the table")
    args = parser.parse_args(argv)
    from chainrun.solver import load_kernels, simulate

    load_kernels()
    rng = np.random.default_rng(args.seed)
    times = np.linspace(0.0, 50.0, 37)
    wall = {True: 0.0, False: 0.0}
    rows, bad = [], 0
    for draw in range(args.draws):
        line = draw_line(rng, args.damped)
        t_end = None if line.has_terminal_state else 200.0
        sols = {}
        for closed_form in (True, False):
            start = time.perf_counter()

            def deadline(_t):
                if time.perf_counter() - start > 60.0:
                    raise TimeoutError("no progress in 60 s")

            try:
                sol = simulate(line, times, t_end=t_end, closed_form=closed_form,
                               on_progress=deadline)
            except TimeoutError as e:
                print(f"draw {draw}, closed_form={closed_form}: {e}")
                bad += 1
                continue
            wall[closed_form] += time.perf_counter() - start
            d = sol.diagnostics
            if not sol.outcome.ok or d.momentum_error > 1e-9 or d.energy_error > 1e-9:
                print(f"draw {draw}, closed_form={closed_form}: {sol.outcome.name}, "
                      f"|dP| {d.momentum_error:.2g}, |dE|/E {d.energy_error:.2g}")
                bad += 1
            sols[closed_form] = sol
        if len(sols) == 2:
            a, b = sols[True], sols[False]
            rows.append((float(np.abs(a.final_velocity - b.final_velocity).max()),
                         abs(a.dissipated_energy - b.dissipated_energy),
                         float(np.abs(a.dissipated - b.dissipated).max()), draw, line.n,
                         a.diagnostics.closed_form_collisions, a.diagnostics.events))
    rows.sort(reverse=True)
    print(f"{args.draws} lines (seed {args.seed}{', damped' if args.damped else ''}): "
          f"{bad} runs failed, stalled or off balance; "
          f"{sum(r[5] for r in rows)} collisions taken whole; solver time "
          f"{wall[True]:.2f} s taken whole, {wall[False]:.2f} s integrated")
    print(f"lines whose final velocities differ by more than 1e-8: "
          f"{sum(r[0] > 1e-8 for r in rows)}")
    print(f"{'max |dv|':>10} {'|d diss|':>10} {'snapshots':>10} {'draw':>5} {'N':>3}"
          f" {'whole':>6} {'events':>7}")
    for r in rows[:args.show]:
        print(f"{r[0]:10.3g} {r[1]:10.3g} {r[2]:10.3g} {r[3]:5d} {r[4]:3d} {r[5]:6d} {r[6]:7d}")
    return 0 if bad == 0 else 1


if __name__ == "__main__":
    raise SystemExit(main())
