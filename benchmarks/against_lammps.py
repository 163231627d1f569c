"""The bench's section ``lammps``: chainrun against LAMMPS on the same lines of spheres.

This module owns the comparison with LAMMPS (``benchmarks.peers.lammps_peer``): a
line of one-inch steel balls, the first striking the others at 0.5 m/s (the bench's
``SI_LINE``), elastic, and damped by the Tsuji law with e = 0.9, as chainrun solves it
and as LAMMPS's ``pair_style granular`` does. What it measures:

1. Two balls: that LAMMPS's Hertz law is chainrun's (the stiffness from the same
   constants; the contact time against the closed form; the velocities inside the
   collision at a small step), and the restitution LAMMPS gives for the damping
   settings a user would write for e = 0.9, beside chainrun's.
2. Accuracy, N = 20: the largest velocity error of LAMMPS at dt = t_c/20 ...
   t_c/1000 (t_c the two-ball contact time), mid-wave and at the end, against
   chainrun at rtol = 1e-14; chainrun's own at rtol 1e-6, 1e-9, 1e-12. Then LAMMPS's
   mid-wave error against N at one step (it grows with the distance the wave has
   run: the wave's lag).
3. Cost: whole processes on the timed lines (elastic N = 2000 and 10^4, damped
   N = 3000), to chainrun's terminal time; LAMMPS at the step where its largest error
   on that line is 1e-3 of the impact speed, predicted from 2. A LAMMPS run predicted
   over ``Mode.lammps_cap`` seconds is timed on two fractions of its steps and
   extrapolated linearly (and says so). The ratios to chainrun's time, against the
   targets (200x elastic N = 10^4, 20x damped N = 3000).

Mid-wave is half the elastic line's terminal time (the wave is half-way along);
the end is the line's terminal time (chainrun's, at rtol = 1e-14 for the accuracy
runs, at the default for the timed ones).
"""

from __future__ import annotations

import math
import os
from dataclasses import asdict, dataclass

import numpy as np

from benchmarks.harness import (DAMPED_LINE, REFERENCE_RTOL, SI_LINE, Context, Processes,
                                config_text, fmt_e, fmt_t, log, solve, table)
from benchmarks.peers import lammps_peer as lp
from benchmarks.sections import Result

#: The lines: chainrun's keys of ``[chain]`` beside n and k.
LINES = {"elastic": dict(SI_LINE),
         "damped": dict(DAMPED_LINE)}
#: LAMMPS's time steps, as fractions of the two-ball contact time: dt = t_c / f.
STEP_FRACTIONS = (20, 50, 100, 200, 400, 1000)
#: chainrun's tolerances (its reference's is the bench's ``REFERENCE_RTOL``).
RTOLS = (1e-6, 1e-9, 1e-12)
#: The time steps of the timed runs: LAMMPS's largest error is this fraction of the
#: impact speed.
TARGET_ERROR = 1e-3
#: The step (t_c / f) at which the mid-wave error is measured against N.
GROWTH_FRACTION = 100
#: The largest N whose error at the end is measured at that step too (to the terminal
#: time: a damped line's is long).
GROWTH_WHOLE_N = 200
#: The small step of the two-ball checks, t_c / f.
TWO_BALL_FRACTION = 10_000


# --- the lines -----------------------------------------------------------------------------


def lines(kind: str, n: int):
    """The line ``kind`` of ``n`` balls as chainrun and as LAMMPS see it.

    LAMMPS's line is built from the material's constants (``chainrun.materials``)
    alone; its damping coefficient is the one that gives chainrun's ``eta``
    (``lammps_peer.coeff_restitution_for``), with the force kept from pulling.

    Returns
    -------
    line : chainrun.solver.Line
    spheres : lammps_peer.SphereLine
    contact_time : float
        Closed-form duration of an elastic collision of two balls at the impact speed.
    same : float
        Largest relative difference of the masses and Hertz stiffnesses of the two.
    """
    from chainrun.config import parse_experiment
    from chainrun.materials import material

    chain = LINES[kind]
    (spec,) = parse_experiment(config_text(f"lammps-{kind}-{n}", n, 1, None,
                                           top={"units": "si"}, chain=chain), "toml").runs()
    line = spec.line
    mat = material(chain["material"])
    d, v = chain["diameter"], chain["speed"]
    mass = float(lp.sphere_mass(d, mat.density))
    kappa = float(lp.hertz_stiffness(d, d, mat.young, mat.poisson))
    same = max(float(np.max(np.abs(line.mass / mass - 1))),
               float(np.max(np.abs(line.stiffness / kappa - 1))))
    damping = {}
    if line.damping is not None and np.any(line.damping > 0):
        eta = float(line.damping[0])
        assert np.all(line.damping == eta) and np.all(line.damping_exponent == 0.25)
        damping = dict(damping="coeff_restitution", limit_damping=True,
                       coefficient=lp.coeff_restitution_for(eta / math.sqrt(mass / 2 * kappa)))
    spheres = lp.SphereLine.uniform(n, 1, v, d, mat.density, mat.young, mat.poisson,
                                    **damping)
    return line, spheres, lp.contact_time(mass / 2, kappa, v), same


def grid(t_end: float, t_mid: float, t_c: float, fraction: float) -> tuple[float, int, int]:
    """A step near t_c / fraction that lands on t_end: (dt, steps to mid-wave, to the end)."""
    n_end = max(2, math.ceil(fraction * t_end / t_c))
    dt = t_end / n_end
    return dt, min(max(1, round(t_mid / dt)), n_end - 1), n_end


def _chainrun_at(line, times, rtol=REFERENCE_RTOL) -> np.ndarray:
    """chainrun's velocities at ``times`` (the last is the end), shape (T, N)."""
    return solve(line, times, t_end=times[-1], rtol=rtol).velocities


def _terminal_time(line, rtol=REFERENCE_RTOL) -> float:
    sol = solve(line, rtol=rtol)
    if not sol.terminal:
        raise RuntimeError(f"chainrun did not reach the terminal state: {sol.message}")
    return sol.end_time


# --- 1. two balls --------------------------------------------------------------------------


def two_ball() -> dict:
    """The Hertz law and the restitution of two balls, LAMMPS against chainrun."""
    from chainrun.solver import EventKind

    out = {}
    line, spheres, t_c, same = lines("elastic", 2)
    v0 = float(line.velocity[0])
    dt = t_c / TWO_BALL_FRACTION
    marks = (TWO_BALL_FRACTION // 4, 3 * TWO_BALL_FRACTION // 2)
    sol = solve(line, [m * dt for m in marks], rtol=REFERENCE_RTOL)
    opened = sol.event_time[sol.event_kind == EventKind.OPEN]
    r = lp.run(spheres, dt, marks, contact=True)
    v = r.velocities[marks[-1]]
    out["elastic"] = {
        "t_c": t_c, "same_constants": same, "chainrun_contact_time": float(opened[0]),
        "chainrun_restitution": float((sol.velocities[-1, 1] - sol.velocities[-1, 0]) / v0),
        "dt": dt, "lammps_contact_steps": r.contact_steps,
        "lammps_restitution": float((v[1] - v[0]) / v0),
        "quarter_diff": float(np.max(np.abs(r.velocities[marks[0]] - sol.velocities[0]))),
        "end_diff": float(np.max(np.abs(v - sol.velocities[-1])))}

    line, matched, _, _ = lines("damped", 2)
    sol = solve(line, [m * dt for m in marks], rtol=REFERENCE_RTOL)
    out["chainrun_damped"] = float((sol.velocities[-1, 1] - sol.velocities[-1, 0]) / v0)
    settings = []
    for damping, e, limit in (("tsuji", 0.9, False), ("tsuji", 0.9, True),
                              ("coeff_restitution", 0.9, False),
                              ("coeff_restitution", 0.9, True),
                              ("coeff_restitution", matched.coefficient, True)):
        s = lp.SphereLine(matched.diameter, matched.density, matched.velocity,
                          matched.young, matched.poisson, damping, e, limit)
        r = lp.run(s, dt, marks)
        v = r.velocities[marks[-1]]
        settings.append({"damping": damping, "coefficient": e, "limit_damping": limit,
                         "restitution": float((v[1] - v[0]) / v0),
                         "matched": e == matched.coefficient,
                         "quarter_diff": float(np.max(np.abs(r.velocities[marks[0]]
                                                             - sol.velocities[0])))})
        log(f"  two balls, LAMMPS damping {damping} {e:.6g}"
            f"{' limit_damping' if limit else ''}: e = {settings[-1]['restitution']:.6f}")
    out["damped"] = settings
    return out


# --- 2. accuracy ---------------------------------------------------------------------------


def _slope(xs, ys) -> float | None:
    """Least-squares slope of log y against log x (None with fewer than 2 points)."""
    pts = [(x, y) for x, y in zip(xs, ys) if y is not None and y > 0]
    if len(pts) < 2:
        return None
    return float(np.polyfit(np.log([p[0] for p in pts]), np.log([p[1] for p in pts]), 1)[0])


def accuracy(kind: str, n: int, fractions, growth_n) -> dict:
    """LAMMPS's errors at each step and chainrun's at each rtol on the line ``kind`` of
    ``n`` balls; LAMMPS's mid-wave error against N at t_c / GROWTH_FRACTION."""
    line, spheres, t_c, same = lines(kind, n)
    v0 = float(line.velocity[0])
    t_end = _terminal_time(line)
    t_mid = _terminal_time(lines("elastic", n)[0]) / 2
    out = {"kind": kind, "n": n, "t_c": t_c, "t_end": t_end, "t_mid": t_mid,
           "impact_speed": v0, "same_constants": same, "lammps": [], "chainrun": []}
    if kind == "damped":
        out["coefficient"] = spheres.coefficient
    for f in fractions:
        dt, n_mid, n_end = grid(t_end, t_mid, t_c, f)
        ref = _chainrun_at(line, [n_mid * dt, t_end])
        r = lp.run(spheres, dt, (n_mid, n_end))
        row = {"fraction": f, "dt": dt, "steps": n_end,
               "mid": float(np.max(np.abs(r.velocities[n_mid] - ref[0]))),
               "end": float(np.max(np.abs(r.velocities[n_end] - ref[1]))), "wall": r.wall}
        row["worst"] = max(row["mid"], row["end"]) / v0
        out["lammps"].append(row)
        log(f"  {kind} N = {n}, LAMMPS dt = t_c/{f}: errors {fmt_e(row['mid'])} mid-wave, "
            f"{fmt_e(row['end'])} at the end (m/s)")
    ref = _chainrun_at(line, [t_mid, t_end])
    for rtol in RTOLS:
        v = _chainrun_at(line, [t_mid, t_end], rtol)
        row = {"rtol": rtol, "mid": float(np.max(np.abs(v[0] - ref[0]))),
               "end": float(np.max(np.abs(v[1] - ref[1])))}
        row["worst"] = max(row["mid"], row["end"]) / v0
        out["chainrun"].append(row)
    # the order in dt: the slope of the finest half of the steps
    fine = out["lammps"][len(out["lammps"]) // 2 - 1:] if len(out["lammps"]) > 2 else out["lammps"]
    slope = _slope([r["fraction"] for r in fine], [r["worst"] for r in fine])
    out["order"] = None if slope is None else -slope
    out["growth"] = []
    for m in growth_n:
        # mid-wave; to the end too while that is cheap (N <= GROWTH_WHOLE_N)
        g_line, g_spheres, _, _ = lines(kind, m)
        g_mid = _terminal_time(lines("elastic", m)[0]) / 2
        g_end = _terminal_time(g_line) if m <= GROWTH_WHOLE_N else None
        if g_end is None:
            dt = t_c / GROWTH_FRACTION
            n_mid = max(1, round(g_mid / dt))
            marks, times = (n_mid,), [n_mid * dt]
        else:
            dt, n_mid, n_end = grid(g_end, g_mid, t_c, GROWTH_FRACTION)
            marks, times = (n_mid, n_end), [n_mid * dt, g_end]
        r = lp.run(g_spheres, dt, marks)
        ref = _chainrun_at(g_line, times)
        errors = [float(np.max(np.abs(r.velocities[k] - v))) for k, v in zip(marks, ref)]
        out["growth"].append({"n": m, "t_mid": n_mid * dt, "mid": errors[0],
                              "end": errors[1] if len(errors) > 1 else None})
        log(f"  {kind}, LAMMPS dt = t_c/{GROWTH_FRACTION}, N = {m}: errors "
            f"{fmt_e(errors[0])} mid-wave, {fmt_e(out['growth'][-1]['end'])} at the end (m/s)")
    last = out["growth"][-2:]
    out["growth_exponent"] = _slope([g["n"] for g in last], [g["mid"] for g in last])
    return out


def step_for(acc: dict, n: int) -> dict:
    """The step t_c / f at which LAMMPS's largest error on the line of ``n`` balls is
    TARGET_ERROR of the impact speed, predicted from ``accuracy``'s measurements.

    Its mid-wave error at t_c / GROWTH_FRACTION is the measured one at the nearest
    measured N, times (N / that N)^q (q from the two largest measured N; at least 0);
    its error at the end the largest measured at that step (N = 20 and the growth
    series' N <= GROWTH_WHOLE_N: it does not grow with N on the elastic line, whose
    balls leave at the same speeds). The larger of the two scales with the step to the
    order measured at N = 20.
    """
    g = min(acc["growth"], key=lambda p: abs(math.log(n / p["n"])))
    q = max(acc["growth_exponent"] or 0.0, 0.0)
    mid = g["mid"] * (n / g["n"]) ** q
    at = next(r for r in acc["lammps"] if r["fraction"] == GROWTH_FRACTION)
    end = max([at["end"]] + [p["end"] for p in acc["growth"] if p.get("end") is not None])
    worst = max(mid, end) / acc["impact_speed"]
    order = acc["order"] or 1.0
    f = GROWTH_FRACTION * (worst / TARGET_ERROR) ** (1.0 / order)
    return {"fraction": f, "predicted_mid": mid, "predicted_end": end,
            "from_n": g["n"], "growth_exponent": q, "order": order}


# --- 3. cost -------------------------------------------------------------------------------


def _lammps_time(spheres, dt, n_end, *, cap: float, fraction_seconds: float,
                 n_mid: int | None = None) -> dict:
    """LAMMPS's whole-process time for ``n_end`` steps: measured when predicted under
    ``cap`` seconds (with the velocities at ``n_mid`` and the end), else extrapolated
    linearly from two runs of a fraction of the steps (the longer about
    ``fraction_seconds``), the second twice the first."""
    one = lp.run(spheres, dt, (1,), dumps=False)
    probe = min(n_end, 2000)
    p = lp.run(spheres, dt, (probe,), dumps=False)
    per_step = max((p.wall - one.wall) / max(probe - 1, 1), 1e-9)
    predicted = one.wall + per_step * (n_end - 1)
    out = {"steps": n_end, "dt": dt, "start_up": one.wall, "predicted": predicted}
    if predicted <= cap or n_end <= 2 * probe:
        marks = (n_end,) if n_mid is None else (n_mid, n_end)
        r = lp.run(spheres, dt, marks)
        out.update(time=r.wall, cpu=r.cpu, loop_time=r.loop_time, measured=True,
                   velocities=r.velocities, per_step=(r.wall - one.wall) / max(n_end - 1, 1))
        return out
    n1 = int(min(max((fraction_seconds / 2 - one.wall) / per_step, probe), n_end // 4))
    a = lp.run(spheres, dt, (n1,), dumps=False)
    b = lp.run(spheres, dt, (2 * n1,), dumps=False)
    slope = (b.wall - a.wall) / n1
    out.update(time=b.wall + slope * (n_end - 2 * n1), measured=False, per_step=slope,
               fraction_steps=(n1, 2 * n1), fraction_walls=(a.wall, b.wall),
               fraction_cpus=(a.cpu, b.cpu))
    return out


def cost(kind: str, n: int, target: float | None, acc: dict, procs: Processes, *,
         cap: float, fraction_seconds: float) -> dict:
    """chainrun (whole processes, each rtol) and LAMMPS (at ``step_for``) on the line
    ``kind`` of ``n`` balls to chainrun's terminal time."""
    line, spheres, t_c, _ = lines(kind, n)
    v0 = float(line.velocity[0])
    out = {"kind": kind, "n": n, "target": target, "chainrun": []}
    reference = None
    timeout = 3600.0
    # the default tolerance first; a looser one should be faster, and is stopped after
    # twice the default's time (at least 30 s): on a damped line it may take far longer
    for rtol in (RTOLS[-1], *RTOLS[:-1]):
        log(f"lammps: {kind} N = {n}, chainrun simulate at rtol {rtol:g}")
        text = config_text(f"lammps-{kind}-{n}", n, 1, None, top={"units": "si"},
                           chain=LINES[kind], rtol=rtol)
        best, walls = procs.timed(text, read_diagnostics=True, read_velocity=True,
                                  timeout=timeout)
        row = {"rtol": rtol, "walls": walls, "time": min(walls) if walls else None,
               "error": best.error, "timeout": timeout}
        if best.error is None:
            row["end_time"] = best.diagnostics["end_time"]
        if rtol == RTOLS[-1]:
            if best.error is not None:
                out["chainrun"].append(row)
                out["error"] = f"chainrun failed: {best.error}"
                return out
            reference = best
            timeout = max(30.0, 2 * row["time"])
        out["chainrun"].append(row)
        log(f"  {fmt_t(row['time'])} s" + (f"  [{best.error}]" if best.error else ""))
    out["chainrun"].sort(key=lambda r: r["rtol"], reverse=True)
    default = next(r for r in out["chainrun"] if r["rtol"] == RTOLS[-1])
    t_end = default["end_time"]
    step = step_for(acc, n)
    out["step"] = step
    t_mid = _terminal_time(lines("elastic", n)[0], 1e-12) / 2 if kind == "damped" else t_end / 2
    dt, n_mid, n_end = grid(t_end, t_mid, t_c, step["fraction"])
    log(f"lammps: {kind} N = {n}, LAMMPS at dt = t_c/{step['fraction']:.0f}, {n_end} steps")
    lam = _lammps_time(spheres, dt, n_end, cap=cap, fraction_seconds=fraction_seconds,
                       n_mid=n_mid)
    velocities = lam.pop("velocities", None)
    if velocities is not None:
        mid_ref = _chainrun_at(line, [n_mid * dt], 1e-12)[0]
        lam["mid"] = float(np.max(np.abs(velocities[n_mid] - mid_ref)))
        lam["end"] = float(np.max(np.abs(velocities[n_end] - reference.final_velocity)))
        lam["worst"] = max(lam["mid"], lam["end"]) / v0
    # the other steps' times at this N, from the same cost per step (keyed by the
    # fraction as text, as JSON keeps it)
    lam["at_fraction"] = {str(r["fraction"]): lam["start_up"] + lam["per_step"]
                          * (grid(t_end, t_mid, t_c, r["fraction"])[2] - 1)
                          for r in acc["lammps"]}
    out["lammps"] = lam
    out["ratio"] = lam["time"] / default["time"]
    out["met"] = None if target is None else out["ratio"] >= target
    log(f"  LAMMPS {fmt_t(lam['time'])} s ({'measured' if lam['measured'] else 'extrapolated'})"
        f", chainrun {fmt_t(default['time'])} s: {out['ratio']:.3g}x")
    return out


# --- the section and its report ------------------------------------------------------------


@dataclass
class LammpsResult(Result):
    """What ``run`` measured (each part a dict, as ``report`` reads it), or why LAMMPS
    was skipped."""

    skipped: str | None = None
    version: str | None = None
    load_start: tuple | None = None
    load_end: tuple | None = None
    target_error: float = TARGET_ERROR
    cap: float | None = None
    two_ball: dict | None = None
    accuracy: dict | None = None
    cost: list | None = None

    def lines(self) -> list[str]:
        return report({k: v for k, v in asdict(self).items() if v is not None})


RESULT = LammpsResult


def run(ctx: Context) -> LammpsResult:
    """Sections 1-3 above for the bench, within the bounds of ``ctx.mode``."""
    mode = ctx.mode
    ok, why = lp.available()
    if not ok:
        ctx.notes.append(f"LAMMPS skipped: {why}")
        log(f"lammps: skipped, {why}")
        return LammpsResult(skipped=why)
    out = LammpsResult(version=lp.version(), load_start=os.getloadavg(), cap=mode.lammps_cap)
    log("lammps: two balls")
    out.two_ball = two_ball()
    out.accuracy = {}
    for kind in LINES:
        log(f"lammps: accuracy, {kind} line, N = {mode.lammps_accuracy_n}")
        out.accuracy[kind] = accuracy(kind, mode.lammps_accuracy_n, mode.lammps_fractions,
                                      mode.lammps_growth_n)
    out.cost = [cost(kind, n, target, out.accuracy[kind], ctx.procs, cap=mode.lammps_cap,
                     fraction_seconds=mode.lammps_fraction_seconds)
                for kind, n, target in mode.lammps_cost]
    out.load_end = os.getloadavg()
    return out


def _us(t: float) -> str:
    return f"{t * 1e6:.6g} us"


def report(res: dict) -> list[str]:
    """The section's lines of the report."""
    if "skipped" in res:
        return [f"LAMMPS: skipped ({res['skipped']})"]
    tb = res["two_ball"]
    e = tb["elastic"]
    out = [f"Against LAMMPS {res['version']} (its lmp, one process, one thread): one-inch steel "
           "balls, the first striking at 0.5 m/s; whole processes; load average "
           f"{res['load_start'][0]:.1f} at the start, {res['load_end'][0]:.1f} at the end.",
           f"  Two balls, elastic: the same Hertz law (mass and kappa from the same constants "
           f"differ by {e['same_constants']:.0e}); contact time {_us(e['t_c'])} in closed form, "
           f"chainrun's {e['chainrun_contact_time'] / e['t_c'] - 1:+.0e} of it, restitution "
           f"{e['chainrun_restitution']:.12f}; LAMMPS at dt = t_c/{TWO_BALL_FRACTION}: in contact "
           f"{e['lammps_contact_steps']:.0f} steps, restitution {e['lammps_restitution']:.9f}, "
           f"velocities {fmt_e(e['quarter_diff'])} m/s from chainrun's at t_c/4."]
    rows = [["chainrun", "restitution 0.9, damping_law tsuji", f"{tb['chainrun_damped']:.6f}",
             "the force never pulls"]]
    for s in tb["damped"]:
        rows.append(["LAMMPS", f"damping {s['damping']} {s['coefficient']:.6g}"
                     + (" limit_damping" if s["limit_damping"] else ""),
                     f"{s['restitution']:.6f}",
                     "chainrun's law (the damped line's setting); velocities "
                     f"{fmt_e(s['quarter_diff'])} m/s from chainrun's at t_c/4" if s["matched"]
                     else ("a user's setting for e = 0.9" if s["coefficient"] == 0.9 else "")])
    out.append(f"  Two balls, damped for e = 0.9: the restitution each gives (LAMMPS at "
               f"dt = t_c/{TWO_BALL_FRACTION}):")
    out.append("    " + table(["tool", "setting", "e", "note"], rows, "llrl")
               .replace("\n", "\n    "))
    costs = {c["kind"]: [c2 for c2 in res["cost"] if c2["kind"] == c["kind"]]
             for c in res["cost"]}
    for kind, acc in res["accuracy"].items():
        timed = costs.get(kind, [])
        out.append("")
        out.append(f"  {kind.capitalize()} line, N = {acc['n']}: largest |v - v_chainrun(rtol "
                   f"{REFERENCE_RTOL:g})| over the balls, mid-wave (t = "
                   f"{acc['t_mid'] * 1e3:.4g} ms) and at the end (terminal, "
                   f"{acc['t_end'] * 1e3:.4g} ms), m/s; t_c = {_us(acc['t_c'])}"
                   + (f"; LAMMPS damping coeff_restitution {acc['coefficient']:.6g} "
                      "limit_damping, chainrun's law" if kind == "damped" else "")
                   + "; times: whole processes at the larger N to the terminal time, "
                   "LAMMPS's from its cost per step there (~):")
        heads = ["tool", "setting", "mid", "end", "worst / v0"]
        heads += [f"N = {c['n']} s" for c in timed]
        rows = []
        for r in acc["lammps"]:
            row = ["LAMMPS", f"dt = t_c/{r['fraction']}", fmt_e(r["mid"]), fmt_e(r["end"]),
                   fmt_e(r["worst"])]
            for c in timed:
                t = (c.get("lammps") or {}).get("at_fraction", {}).get(str(r["fraction"]))
                row.append("-" if t is None else "~" + fmt_t(t))
            rows.append(row)
        for r in acc["chainrun"]:
            row = ["chainrun", f"rtol {r['rtol']:g}", fmt_e(r["mid"]), fmt_e(r["end"]),
                   fmt_e(r["worst"])]
            for c in timed:
                x = next((x for x in c["chainrun"] if x["rtol"] == r["rtol"]), None)
                if x is not None and x["time"] is None and "timed out" in (x["error"] or ""):
                    row.append(f"> {x['timeout']:.0f}")
                else:
                    row.append(fmt_t(None if x is None else x["time"]))
            rows.append(row)
        out.append("    " + table(heads, rows).replace("\n", "\n    "))
        growth = ", ".join(f"N = {g['n']} {fmt_e(g['mid'])}"
                           + (f" / {fmt_e(g['end'])}" if g.get("end") is not None else "")
                           for g in acc["growth"])
        out.append(f"    LAMMPS's order in dt {acc['order']:.2f}; its error at "
                   f"dt = t_c/{GROWTH_FRACTION} against N, mid-wave / at the end: {growth} m/s "
                   f"(mid-wave, the last two: ~N^{acc['growth_exponent']:.2f})")
    out.append("")
    out.append(f"  Timed lines, to chainrun's terminal time, whole processes; LAMMPS at the step "
               f"where its largest error on that line is {TARGET_ERROR:g} of the impact speed "
               "(predicted from the errors above); chainrun at rtol 1e-12:")
    rows, notes = [], []
    for c in res["cost"]:
        label = f"{c['kind']} {c['n']}"
        if c.get("error"):
            rows.append([label] + ["-"] * 9)
            notes.append(f"{label}: {c['error']}")
            continue
        lam, st = c["lammps"], c["step"]
        default = next(r for r in c["chainrun"] if r["rtol"] == RTOLS[-1])
        how = "measured" if lam["measured"] else (
            f"extrapolated from {lam['fraction_steps'][0]} and {lam['fraction_steps'][1]} "
            f"steps ({100 * lam['fraction_steps'][1] / lam['steps']:.2g}%)")
        errors = ("-" if "mid" not in lam else f"{fmt_e(lam['mid'])} / {fmt_e(lam['end'])}")
        verdict = "" if c["target"] is None else (
            f"{'MET' if c['met'] else 'NOT MET'} (>= {c['target']:g}x)")
        rows.append([label, f"{default['end_time'] * 1e3:.4g}", f"t_c/{st['fraction']:.0f}",
                     str(lam["steps"]),
                     fmt_t(lam["time"]), how, errors, fmt_t(default["time"]),
                     f"{c['ratio']:.3g}", verdict])
        notes.append(f"{label}: step from predicted errors of {fmt_e(st['predicted_mid'])} "
                     f"m/s mid-wave (measured at N = {st['from_n']}, x (N/{st['from_n']})^"
                     f"{st['growth_exponent']:.2f}) and {fmt_e(st['predicted_end'])} m/s at "
                     f"the end at t_c/{GROWTH_FRACTION}, "
                     f"order {st['order']:.2f}; chainrun times {', '.join(fmt_t(w) for w in default['walls'])} s")
    out.append("    " + table(["line N", "t_end ms", "LAMMPS dt", "steps", "LAMMPS s", "how",
                               "its error mid / end m/s", "chainrun s", "LAMMPS/chainrun",
                               "target"], rows, "lrlrrlrrrl").replace("\n", "\n    "))
    out += [f"    {n}" for n in notes]
    return out
