"""The bench's section ``scaling``: how the time to the terminal state grows with N.

chainrun in-process, Hertz N = 250 ... 10^6 and linear N = 100 ... 10^5, within a
time budget; the peers' Hertz points are the peers' case (``sections.peers``, when it
ran: t = 1.25 N + 20 is past chainrun's terminal time there, which is checked), their
linear points run until chainrun's terminal time. For each tool the least-squares
exponent of time against N, and that of the last pair.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from benchmarks.harness import (ACCURACY, REFERENCE_RTOL, SERIES_SHORT, Context,
                                chainrun_point, fit_exponent, fmt_e, fmt_t, log, max_error,
                                predict, solve_paper, table)
from benchmarks.sections import Result
from benchmarks.sections.peers import peer_runners, run_peer


@dataclass
class ScalingResult(Result):
    """Per kind (Hertz, linear): tool -> its points (dicts with n, time, ...); and
    the fitted exponents, kind -> tool -> ``fit_exponent``."""

    hertz: dict = field(default_factory=dict)
    linear: dict = field(default_factory=dict)
    fits: dict = field(default_factory=dict)

    def lines(self) -> list[str]:
        out = ["Scaling to the terminal state (chainrun: in-process solver time; peers: as "
               "above for Hertz, until chainrun's terminal time for linear):"]
        for kind, title in (("hertz", "Hertz"), ("linear", "linear")):
            series = getattr(self, kind)
            ns = sorted({pt["n"] for pts in series.values() for pt in pts})
            tools = list(series)
            rows = []
            for n in ns:
                row = [str(n)]
                for tool in tools:
                    pt = next((q for q in series[tool] if q["n"] == n), None)
                    if pt is None:
                        row.append("")
                    elif pt.get("time") is None:
                        row.append("skip" if pt.get("skipped") else "limit")
                    else:
                        row.append(fmt_t(pt["time"]))
                rows.append(row)
            fits = self.fits[kind]
            rows.append(["exponent"] + [f"{fits[t]['exponent']:.2f}" if fits.get(t) else "-"
                                        for t in tools])
            rows.append(["(last pair)"] + [f"{fits[t]['local_exponent']:.2f}" if fits.get(t)
                                           else "-" for t in tools])
            out.append(f"  {title}, K = 1: time s")
            out.append("    " + table(["N"] + tools, rows).replace("\n", "\n    "))
        lin_errs = [(tool, pt["n"], pt["error_vs_reference"])
                    for tool, pts in self.linear.items()
                    if tool != "chainrun" for pt in pts if "error_vs_reference" in pt]
        if lin_errs:
            out.append("  linear peers' errors: " + ", ".join(
                f"{t} N={n} {e:.1e}{' !' if e > ACCURACY[t] else ''}" for t, n, e in lin_errs))
        for kind in ("hertz", "linear"):
            for pt in getattr(self, kind)["chainrun"]:
                if pt.get("skipped") or pt.get("error"):
                    out.append(f"  {kind} N = {pt['n']}: {pt.get('skipped') or pt.get('error')}")
        return out


RESULT = ScalingResult


def series(label, alpha, ns, budget, timeout_cap) -> list[dict]:
    """chainrun in-process to the terminal state over ``ns``, within ``budget`` seconds."""
    points = []
    spent = 0.0
    done: list[tuple[int, float]] = []
    for n in ns:
        if done:
            guess = predict(done, n)
            if guess > budget - spent:
                points.append({"n": n, "time": None,
                               "skipped": f"predicted {fmt_t(guess)} s > budget left "
                                          f"{fmt_t(max(budget - spent, 0))} s"})
                log(f"  {label} N = {n}: skipped, predicted {fmt_t(guess)} s")
                continue
        left = budget - spent
        p = chainrun_point(n, 1, alpha, timeout=min(left, timeout_cap) if math.isfinite(left)
                           else None, short=SERIES_SHORT)
        p.pop("final_velocity", None)
        spent += sum(p.get("times", [])) if p.get("time") is not None else left
        points.append(p)
        if p.get("time") is None:
            log(f"  {label} N = {n}: {p.get('error')}")
            break
        done.append((n, p["time"]))
        log(f"  {label} N = {n}: {fmt_t(p['time'])} s, terminal t = {p['end_time']:.6g}, "
            f"{p['steps']} steps, {p['events']} events, window {p['max_window']}")
    return points


def run(ctx: Context) -> ScalingResult:
    mode = ctx.mode
    log("scaling: Hertz, K = 1, to the terminal state (chainrun in-process)")
    hertz = series("Hertz", 1.5, mode.hertz_n, mode.hertz_budget, 3600.0)
    log("scaling: linear, K = 1, to the terminal state (chainrun in-process)")
    linear = series("linear", 1.0, mode.linear_n, mode.linear_budget, 3600.0)
    out = ScalingResult(hertz={"chainrun": hertz}, linear={"chainrun": linear})

    # Hertz peers: the peers' case (t = 1.25 N + 20 is after chainrun's terminal time
    # there, checked below), so the same runs give their scaling.
    peers = ctx.results.get("peers")
    if peers:
        for case in peers.cases:
            for r in case["tools"]:
                if r["tool"] in ("chainrun", "chainrun-cli") or r.get("time") is None:
                    continue
                out.hertz.setdefault(r["tool"], []).append(
                    {"n": case["n"], "time": r["time"], "steps": r.get("steps"),
                     "events": r.get("events"), "until": case["t_stop"]})
            if (case["reference_end_time"] > case["t_stop"]
                    or case["reference_outcome"] != "terminal"):
                ctx.notes.append(f"Hertz N = {case['n']}: chainrun's terminal state comes "
                                 f"after t = {case['t_stop']:g}; the peers' scaling points "
                                 "stop before it")

    # Linear peers: run until chainrun's terminal time.
    log("scaling: linear peers, until chainrun's terminal time")
    runners = peer_runners(mode, [])
    history: dict[str, list] = {name: [] for name in runners}
    for n in mode.linear_peer_n:
        ref = solve_paper(n, 1, 1.0, rtol=REFERENCE_RTOL)
        t_stop = ref.end_time
        for name, solve in runners.items():
            if history[name] and predict(history[name], n) > mode.peer_point_cap:
                continue
            r = run_peer(name, solve, n, 1, 1.0, t_stop)
            if r.get("time") is None:
                log(f"  linear {name} N = {n}: {r.get('error')}")
                continue
            history[name].append((n, r["time"]))
            err = max_error(r["final_velocity"], ref.final_velocity)
            out.linear.setdefault(name, []).append(
                {"n": n, "time": r["time"], "steps": r["steps"], "events": r["events"],
                 "until": t_stop, "error_vs_reference": err,
                 "ok": err <= ACCURACY[name]})
            log(f"  linear {name} N = {n}: {fmt_t(r['time'])} s, error {fmt_e(err)}")

    for kind in ("hertz", "linear"):
        out.fits[kind] = {tool: fit_exponent([p["n"] for p in pts],
                                             [p.get("time") for p in pts])
                          for tool, pts in getattr(out, kind).items()}
    return out
