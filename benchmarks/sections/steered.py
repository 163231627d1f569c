"""The bench's section ``steered``: the lines whose end is steered by rounding, judged
by what does not depend on it (issue 34, "Accuracy").

The K = 80 cascade (Hertz N = 2000) and the random line (N = 1000, ``RANDOM_LINE``,
struck by ball 1) keep colliding long after the wave has passed, and the order of
their crowded collisions depends on the last digits of each step: a run at rtol and
one at rtol/10 end with final velocities up to 0.1 apart, ball by ball
(``benchmarks.cascade``). Each line runs in-process at both tolerances, and is judged
by what rounding does not move:

* each run's balances (the solver's ``Diagnostics``): momentum to ``MOMENTUM`` of the
  line's own (``momentum_relative``: the solver states it in one ball's momentum, and
  the cascade's strikers carry 80 of those), the energy balance to ``ENERGY``;
* each run's final state is terminal by the model's rule, checked here from the final
  positions and velocities: every contact open (compression at most ``open_tol``) and
  the velocities non-decreasing along the line (no pair approaching faster than the
  run's velocity floor);
* the statistics of the final velocities (``STATS``: the sorted profile's largest
  and mean difference, its percentiles, the kinetic energy's share in the fastest 1% and 10% of
  the balls, the balls moving backwards, the fastest ball) agree between the two runs
  within a tolerance: ``MARGIN`` times the spread the two runs showed when it was
  first measured, and no less than ``FLOOR``. The tolerance is kept in the results
  file: a later run reads it from there (``ctx.recorded``) for the same line, and also
  compares its own statistics at rtol with those recorded.

The ball-by-ball difference is reported beside them, to show the line is steered; it
is not judged. In a terminal state the velocities are sorted along the line, so the
sorted profile is the line's own order and its largest difference is the ball-by-ball
one: it is judged by the tolerance all the same, and the mean difference of the
profile (the distance between the two distributions of velocities) is the finer
measure.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from benchmarks.harness import Case, Context, Deadline, fmt_e, fmt_t, log, paper_line, solve
from benchmarks.sections import Result

#: Issue 34's balances: momentum (relative to the momentum the line is given) and energy
#: (relative to the initial kinetic energy), each run.
MOMENTUM, ENERGY = 1e-12, 1e-10
#: The tolerance of a statistic is its first measured spread times MARGIN. The spread
#: is one sample (one pair of runs); a future version's rounding steers the line as
#: differently again, and half the time by more than that sample's size, so a margin
#: of 2 leaves room for a sample about twice the one measured, while a statistic that
#: really moved (a lost collision, a broken balance) moves by far more.
MARGIN = 2.0
#: ... and no less than chainrun's claimed accuracy of a final velocity (a statistic
#: that rounding does not move at all would otherwise get a tolerance of zero); the
#: number of balls moving backwards, a count, no less than one ball (one whose final
#: velocity is within rounding's reach of 0 may cross it).
FLOOR = 1e-9
#: The statistics of the final velocities that should not depend on rounding: name ->
#: what the report calls it.
STATS = {"sorted_max": "sorted profile, max |dv|",
         "sorted_mean": "sorted profile, mean |dv|", "p10": "10th percentile",
         "p50": "median", "p90": "90th percentile", "share_1": "energy share, fastest 1%",
         "share_10": "energy share, fastest 10%", "backwards": "balls moving backwards",
         "fastest": "fastest ball's velocity"}


def line_of(case: Case):
    """The solver's line of a case: the paper's (Hertz, K strikers) or the random one."""
    if case.label == "random":
        from benchmarks.random_events import random_line
        return random_line(case.n)
    return paper_line(case.n, case.k, case.alpha)


def terminal_check(line, x, v, floor: float) -> dict:
    """Whether the final positions ``x`` and velocities ``v`` are terminal by the
    model's rule, computed here: every contact open (compression ``x_j - x_{j+1} -
    g_j`` at most ``open_tol``: the rounding of the positions, or a length rtol of the
    line's own) and no pair approaching faster than ``floor`` (in the line's velocity
    scale). An approach slower than the floor is not a collision (``velocity_floor``)."""
    s = line.scales()
    compression = x[:-1] - x[1:] - np.asarray(line.gap, dtype=float)
    open_tol = 1e-9 * s.length + 8 * np.finfo(float).eps * float(np.max(np.abs(x)))
    approach = float(np.max(v[:-1] - v[1:], initial=-math.inf))
    max_c = float(np.max(compression, initial=-math.inf))
    return {"max_compression": max_c, "open_tol": open_tol,
            "max_approach": approach, "approach_tol": floor * s.velocity,
            "terminal": bool(max_c <= open_tol and approach <= floor * s.velocity)}


def stats(v, mass, backwards_below: float) -> dict:
    """The statistics of final velocities ``v`` that should not depend on rounding."""
    v = np.asarray(v, dtype=float)
    ke = 0.5 * np.broadcast_to(mass, v.shape) * v * v
    order = np.argsort(-np.abs(v), kind="stable")
    share = {p: float(ke[order[:max(1, math.ceil(v.size * p / 100))]].sum() / ke.sum())
             for p in (1, 10)}
    p10, p50, p90 = (float(q) for q in np.percentile(v, [10, 50, 90]))
    return {"p10": p10, "p50": p50, "p90": p90, "share_1": share[1], "share_10": share[10],
            "backwards": int(np.sum(v < -backwards_below)), "fastest": float(v.max())}


def compare(a: dict, b: dict, va=None, vb=None) -> dict:
    """|a - b| of each statistic; with the velocities, the sorted profile's max
    difference too."""
    out = {k: abs(a[k] - b[k]) for k in STATS if k in a and k in b}
    if va is not None:
        dv = np.abs(np.sort(va) - np.sort(vb))
        out["sorted_max"], out["sorted_mean"] = float(dv.max()), float(dv.mean())
    return out


def one_run(case: Case, line, rtol: float, timeout: float | None) -> dict:
    """One in-process run to the terminal state: its counts, balances, terminal check
    and statistics (and its final velocities, which the JSON leaves out)."""
    t0 = time.perf_counter()
    try:
        sol = solve(line, rtol=rtol, timeout=timeout)
    except Deadline as exc:
        return {"rtol": rtol, "error": str(exc)}
    d = sol.diagnostics
    check = terminal_check(line, sol.final_position, sol.final_velocity,
                           d.velocity_floor)
    return {"rtol": rtol, "time": time.perf_counter() - t0, "events": d.events,
            "end_time": sol.end_time, "outcome": sol.outcome.value,
            "momentum_error": d.momentum_error, "energy_error": d.energy_error,
            "momentum_relative": momentum_relative(line, d.momentum_error),
            "balanced": bool(abs(momentum_relative(line, d.momentum_error)) <= MOMENTUM
                             and abs(d.energy_error) <= ENERGY),
            **check,
            "stats": stats(sol.final_velocity, line.mass,
                           d.velocity_floor * line.scales().velocity),
            "final_velocity": sol.final_velocity}


def momentum_relative(line, error: float) -> float:
    """The solver's momentum error (in its unit, the momentum of one ball of the line's
    mass scale at its velocity scale) over the momentum the line is given, sum |m v|."""
    s = line.scales()
    given = float(np.sum(np.abs(line.mass * line.velocity))) / (s.mass * s.velocity)
    return error / given if given > 0.0 else error


def _momentum(r: dict) -> float:
    """A run's momentum error over the line's momentum (a run recorded before that was
    kept: the solver's own)."""
    return r.get("momentum_relative", r["momentum_error"])


def judge(entry: dict, recorded: dict | None) -> dict:
    """``entry`` (a line's two runs) judged: the spread between them, the tolerance
    (the recorded one for the same line, else MARGIN x this spread), and whether the
    spread, and the rtol run's statistics against the recorded ones, are within it."""
    a, b = entry["runs"]
    entry["max_dv"] = float(np.max(np.abs(a["final_velocity"] - b["final_velocity"])))
    entry["spread"] = compare(a["stats"], b["stats"], a["final_velocity"],
                              b["final_velocity"])
    if recorded and recorded.get("tolerance"):
        entry["tolerance"] = dict(recorded["tolerance"])
        entry["tolerance_from"] = recorded.get("tolerance_from")
        entry["against_recorded"] = compare(a["stats"], recorded["runs"][0]["stats"])
    else:
        entry["tolerance"] = {k: max(MARGIN * s, FLOOR) if k != "backwards"
                              else max(math.ceil(MARGIN * s), 1)
                              for k, s in entry["spread"].items()}
        entry["tolerance_from"] = "this run"
        entry["against_recorded"] = None
    tol = entry["tolerance"]
    diffs = [entry["spread"]] + ([entry["against_recorded"]]
                                 if entry["against_recorded"] else [])
    entry["within"] = all(d[k] <= tol.get(k, math.inf) for d in diffs for k in d)
    entry["met"] = bool(entry["within"] and all(r["balanced"] and r["terminal"]
                                                 for r in entry["runs"]))
    return entry


def failures(entry: dict) -> list[str]:
    """What fails in a judged ``entry``, one phrase each (none when it is met)."""
    out = []
    for r in entry["runs"]:
        at = f"rtol {r['rtol']:.0e}"
        dp = _momentum(r)
        if abs(dp) > MOMENTUM:
            out.append(f"{at}: momentum {dp:.1e} > {MOMENTUM:g}")
        if abs(r["energy_error"]) > ENERGY:
            out.append(f"{at}: energy {r['energy_error']:.1e} > {ENERGY:g}")
        if not r["terminal"]:
            out.append(f"{at}: not terminal")
    tol = entry["tolerance"]
    for what, diffs in (("spread", entry["spread"]),
                        ("vs recorded", entry.get("against_recorded") or {})):
        out += [f"{STATS[k]} {what} {d:.2e} > {tol[k]:.2e}" for k, d in diffs.items()
                if d > tol.get(k, math.inf)]
    return out


@dataclass
class SteeredResult(Result):
    """Per line (``lines_run``): its name, label, n, k, its two runs, the spread,
    the tolerance and where it came from, the recorded run's differences, the verdict
    (``met``: both runs balanced and terminal, every difference within tolerance)."""

    lines_run: list = field(default_factory=list)

    def lines(self) -> list[str]:
        out = ["Lines steered by rounding, judged by what does not depend on it (the default "
               "rtol against rtol/10):",
               f"balances: momentum <= {MOMENTUM:g} of the line's, energy <= {ENERGY:g}; "
               "terminal checked "
               "from the final state; statistics within MARGIN x the spread first measured "
               f"(MARGIN = {MARGIN:g}, at least {FLOOR:g})"]
        for e in self.lines_run:
            out.append("")
            head = f"{e['name']}: "
            if e.get("error"):
                out.append(head + e["error"])
                continue
            why = failures(e)
            out.append(head + ("MET" if e["met"] else f"NOT MET ({'; '.join(why)})")
                       + f"; ball by ball the runs differ by up to {e['max_dv']:.3g} "
                       "(steered, not judged)")
            for r in e["runs"]:
                out.append(f"  rtol {r['rtol']:.0e}: {fmt_t(r['time'])} s, {r['events']:,} "
                           f"events, t = {r['end_time']:.4g}; momentum "
                           f"{fmt_e(_momentum(r))}, energy {fmt_e(r['energy_error'])}"
                           f"; terminal {'yes' if r['terminal'] else 'NO'} (largest "
                           f"compression {r['max_compression']:.1e}, largest approach "
                           f"speed {r['max_approach']:.1e})")
            a, b = (r["stats"] for r in e["runs"])
            rec = e.get("against_recorded")
            out.append(f"  {'statistic':<27} {'rtol':>10} {'rtol/10':>10} {'spread':>9} "
                       f"{'tolerance':>9}" + (f" {'vs recorded':>11}" if rec else ""))
            for k, name in STATS.items():
                va = "" if k not in a else (f"{a[k]:d}" if isinstance(a[k], int)
                                            else f"{a[k]:.6f}")
                vb = "" if k not in b else (f"{b[k]:d}" if isinstance(b[k], int)
                                            else f"{b[k]:.6f}")
                t = e["tolerance"].get(k)
                out.append(f"  {name:<27} {va:>10} {vb:>10} {e['spread'][k]:9.2e} "
                           + (f"{'-':>9}" if t is None else f"{t:9d}" if isinstance(t, int)
                              else f"{t:9.2e}")
                           + (f" {rec[k]:11.2e}" if rec and k in rec else ""))
            out.append(f"  tolerance from {e['tolerance_from']}")
        return out


RESULT = SteeredResult


def run(ctx: Context) -> SteeredResult:
    from chainrun.solver import DEFAULT_RTOL

    mode = ctx.mode
    before = (ctx.recorded or {}).get("steered") or {}
    recorded = {}
    for e in before.get("result", {}).get("lines_run", []):
        if not e.get("error") and e.get("tolerance"):
            if e.get("tolerance_from") in (None, "this run"):
                e = dict(e, tolerance_from=f"the run of {before.get('date')}, commit "
                                           f"{(before.get('commit') or '?')[:12]}")
            recorded[e["name"]] = e
    out = SteeredResult()
    for case in mode.steered:
        log(f"steered: {case.name}, rtol {DEFAULT_RTOL:g} and {DEFAULT_RTOL / 10:g}")
        line = line_of(case)
        entry = {"name": case.name, "label": case.label, "n": case.n, "k": case.k, "runs": []}
        for rtol in (DEFAULT_RTOL, DEFAULT_RTOL / 10):
            r = one_run(case, line, rtol, mode.steered_timeout)
            if "error" in r:
                entry["error"] = f"rtol {rtol:g}: {r['error']}"
                break
            log(f"  rtol {rtol:g}: {fmt_t(r['time'])} s, {r['events']} events")
            entry["runs"].append(r)
        if "error" not in entry:
            judge(entry, recorded.get(case.name))
        out.lines_run.append(entry)
    return out
