"""Where a line's steps go: steps, rejections, events and the window, over its run.

A step costs every ball of the window (one clock), so a run's cost is its steps times
the window they stepped. This runs a line to its terminal state (the length of the run
from a first run), then again, returning to Python in equal intervals of time (or of
its logarithm), and reads the solver's own counters there: the steps taken and
rejected and the events logged in each interval, the window and its clusters at the
interval's end, and each interval's share of the ball-steps (steps times the window,
read ``READS`` times in each interval)::

    .venv/bin/python -m benchmarks.steps damped --n 3000   # the bench's damped line
    .venv/bin/python -m benchmarks.steps random --n 1000 --log
    .venv/bin/python -m benchmarks.steps hertz --n 2000 --k 80 --intervals 20

A wave crossing a long cluster shows as many steps and few events (the step is the
front's, the window the whole cluster: the case for multirate steps); a line breaking
up shows as about one step per event (the case for clocks per cluster).
"""

from __future__ import annotations

import argparse

import numpy as np

from benchmarks.harness import solve
from benchmarks.window import make_line


#: the counters are read this many times in each interval shown, so that its ball-steps
#: (steps times the window, which changes only at events) are summed finely
READS = 20


def trace(line, intervals: int, log: bool = False):
    """The run of ``line`` to its terminal state, in ``intervals`` intervals of its
    length (equal, or equal in the logarithm of time over its last six decades):
    rows of (t, steps, rejected, events, window, clusters, ball-steps) at each
    interval's end, counts since the start, t in the line's units. The second run
    drives the kernels' loop (``_loop.advance``) itself, as ``_driver`` does, to read
    the counters between its returns."""
    from chainrun.solver import DEFAULT_RTOL, _loop, _setup, _state, load_kernels

    load_kernels()
    end = solve(line).end_time
    P = _setup._Prepared(line)
    S = _setup._line_state(P, DEFAULT_RTOL, None, None)
    ends = (np.geomspace(1e-6 * end, end, intervals) if log
            else np.linspace(0.0, end, intervals + 1)[1:])
    starts = np.concatenate(([0.0], ends[:-1]))
    marks = np.concatenate([np.linspace(a, b, READS + 1)[1:] for a, b in zip(starts, ends)])
    rows = []
    last = (0, 0)  # the steps and window at the last read
    ball_steps = 0.0

    def ask(i):
        S.fs[_state.F_TOUT] = marks[i] / P.scales.time
        S.ints[_state.I_HAVEOUT] = 2  # a sample: the kernel only returns there

    def row(t):
        nonlocal ball_steps, last
        steps, window = int(S.ints[_state.I_STEPS]), int(S.ints[_state.I_M])
        ball_steps += (steps - last[0]) * 0.5 * (window + last[1])
        last = (steps, window)
        return (t, steps, int(S.ints[_state.I_REJ]), int(S.ints[_state.I_EVTOTAL]), window,
                int(S.ints[_state.I_NCL]), ball_steps)

    read = 0
    ask(0)
    while True:
        status = _loop.advance(S)
        if status == _state.ST_FLUSH:
            S.ints[_state.I_NEV] = 0
        elif status == _state.ST_GROW:
            S = _setup._grow(S, int(S.ints[_state.I_NEED]))
        elif status == _state.ST_OUTPUT:
            now = row(marks[read])
            read += 1
            if read % READS == 0:
                rows.append(now)
            if read < marks.size:
                ask(read)
        elif status != _state.ST_YIELD:
            break
    if rows:  # (what the run did at its last instant, after the last read)
        rows[-1] = row(rows[-1][0])
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("kind", choices=("random", "damped", "hertz", "linear"))
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--k", type=int, default=1)
    parser.add_argument("--intervals", type=int, default=40)
    parser.add_argument("--log", action="store_true",
                        help="intervals equal in the logarithm of time")
    args = parser.parse_args(argv)
    rows = trace(make_line(args.kind, args.n, args.k), args.intervals, args.log)
    if not rows:
        print("the run ended before its first interval")
        return 1
    counts = np.array([r[1:] for r in rows], dtype=float)
    deltas = np.diff(np.vstack([np.zeros(counts.shape[1]), counts]), axis=0)
    cost = deltas[:, 5]
    share = cost / cost.sum() if cost.sum() > 0 else cost
    steps, rejected, events = rows[-1][1:4]
    print(f"{args.kind} N = {args.n}, K = {args.k}: {steps:,} steps ({rejected:,} "
          f"rejected), {events:,} events, {rows[-1][6]:.3g} ball-steps to t = "
          f"{rows[-1][0]:.6g}")
    print(f"{'t':>11}  {'steps':>6}  {'rejected':>8}  {'events':>6}  {'window':>6}  "
          f"{'clusters':>8}  {'ball-steps':>10}")
    for r, d, s in zip(rows, deltas, share):
        print(f"{r[0]:11.4g}  {d[0]:6.0f}  {d[1]:8.0f}  {d[2]:6.0f}  {r[4]:6d}  {r[5]:8d}  "
              f"{100 * s:9.1f}%")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
