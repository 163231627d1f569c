"""The bench's section ``general``: the paper's Hertz line against a random one, and a
steel line in SI units against the paper's.

The paper's line (``uniform``) and a ``random`` line of the same N (``RANDOM_LINE``:
masses and stiffnesses uniform in [1, 10), fixed seeds), K = 1, to the terminal state,
as whole processes, runs alternating; the requirement is read at the largest N: the
random line within ``GENERAL_LIMIT`` times the uniform one. The random line's terminal
state costs far more (the wave scatters, and its fragments collide until the
velocities are sorted): a size whose predicted time is over ``mode.general_cap`` is
skipped, with the prediction. Then the steel line in SI units (``SI_LINE``) against the
paper's line of ``mode.units_n`` balls: the solver works in the line's own scales, so
the two should cost the same.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from benchmarks.harness import (RANDOM_LINE, SI_LINE, Context, alternate, config_text,
                                fmt_t, log, median, predict, ratio, ratio_text, table,
                                times_text)
from benchmarks.sections import Result

#: The requirement on the random line: at most this many times the paper's line's time,
#: at the section's largest N.
GENERAL_LIMIT = 2.0


@dataclass
class GeneralResult(Result):
    """``series``: per N, each line's runs (``alternate``), their ratio and any skip or
    prediction; ``requirement``: the verdict at the largest N (``verdict``);
    ``units``: the SI line against the paper's."""

    random_line: dict = field(default_factory=lambda: dict(RANDOM_LINE))
    limit: float = GENERAL_LIMIT
    requirement_n: int = 0
    runs: int = 0
    series: list = field(default_factory=list)
    requirement: dict = field(default_factory=dict)
    units: dict | None = None

    def lines(self) -> list[str]:
        out = ["General line: the paper's Hertz line (uniform) against a random line (masses "
               "and stiffnesses uniform in [1, 10), fixed seeds), K = 1, to the terminal "
               f"state; whole chainrun simulate processes, {self.runs} runs each, "
               "alternating; x uniform = median / the uniform line's median; events, steps "
               "(accepted), rejected steps and the widest window of the first run:"]
        rows, skips = [], []
        for p in self.series:
            first = True
            for line in ("uniform", "random"):
                r = p.get(line)
                n = str(p["n"]) if first else ""
                first = False
                if r is None:
                    guess = p.get("random_predicted")
                    uni = p["uniform"]["walls"]
                    rows.append([n, line, "skip", "-",
                                 f"~{guess / median(uni):.2g} (pred.)" if guess and uni
                                 else "-", "", "", "", ""])
                    skips.append(f"{line} N = {p['n']}: {p.get('random_skipped')}")
                    continue
                d = r.get("diagnostics") or {}
                rows.append([n, line, times_text(r["walls"]), fmt_t(median(r["walls"]))
                             if r["walls"] else "-",
                             ratio_text(p.get("ratio")) if line == "random" else "",
                             str(d.get("events", "-")), str(d.get("steps", "-")),
                             str(d.get("rejected_steps", "-")), str(d.get("max_window", "-"))])
                if r["errors"]:
                    skips.append(f"{line} N = {p['n']}: {r['errors'][0]}")
                elif d and d.get("outcome") != "terminal":
                    skips.append(f"{line} N = {p['n']}: ended {d.get('outcome')}, "
                                 "not terminal")
        out.append("  " + table(["N", "line", "times s", "median", "x uniform", "events",
                                 "steps", "rejected", "window"], rows, "llrrrrrrr")
                   .replace("\n", "\n  "))
        out += [f"  {s}" for s in skips]
        v = self.requirement
        head = f"  Requirement random <= {self.limit:g} x uniform at N = {v['n']}: "
        if v["ratio"] is None:
            out.append(head + "not measured")
        elif v["measured"]:
            out.append(head + ("MET" if v["met"] else "NOT MET") + f" ({v['ratio']:.3g} x)")
        else:
            out.append(head + ("not measured" if v["met"] else "NOT MET by prediction")
                       + f": the random line was not run, predicted {v['ratio']:.2g} x")
        u = self.units
        if u:
            out.append(f"  Units: the steel line in SI units (diameter "
                       f"{u['si_line']['diameter']:g} m, {u['si_line']['speed']:g} m/s) "
                       f"against the paper's line, N = {u['n']}, to the terminal state:")
            for name in ("paper", "si"):
                r = u[name]
                out.append(f"    {name:5s} {times_text(r['walls'])} s (median "
                           f"{fmt_t(median(r['walls'])) if r['walls'] else '-'})"
                           + (f"  [{r['errors'][0]}]" if r["errors"] else ""))
            same = {None: "not compared", True: "the same", False: "DIFFERENT"}[u["same_work"]]
            d = u["paper"].get("diagnostics") or {}
            out.append(f"    si / paper: {ratio_text(u['ratio'])} x; events and steps {same}"
                       + (f" ({d['events']} and {d['steps']})" if u["same_work"] else ""))
        return out


RESULT = GeneralResult


def verdict(point: dict) -> dict:
    """The requirement (random / paper line <= GENERAL_LIMIT) at the largest N:
    measured, or, where the random line was skipped, its prediction."""
    uni = point["uniform"]
    if point.get("ratio") is not None:
        return {"n": point["n"], "ratio": point["ratio"], "measured": True,
                "met": point["ratio"] <= GENERAL_LIMIT}
    guess = point.get("random_predicted")
    if guess is not None and uni["walls"]:
        r = guess / median(uni["walls"])
        return {"n": point["n"], "ratio": r, "measured": False, "met": r <= GENERAL_LIMIT}
    return {"n": point["n"], "ratio": None, "measured": False, "met": None}


def run(ctx: Context) -> GeneralResult:
    mode, procs = ctx.mode, ctx.procs
    out = GeneralResult(requirement_n=max(mode.general_n), runs=mode.general_runs)
    done: list[tuple[int, float]] = []       # (N, solver time) of the random line
    stopped = None
    for n in mode.general_n:
        log(f"general: N = {n}, the paper's line and the random line, K = 1, to the "
            f"terminal state, as processes")
        jobs = {"uniform": {"text": config_text(f"general-uniform-{n}", n, 1, 1.5),
                            "timeout": 600.0}}
        point = {"n": n}
        # the random line's solver time, predicted from its smaller sizes
        guess = predict(done, n) if done else None
        if stopped:
            point["random_skipped"] = stopped
        elif guess is not None and guess > mode.general_cap:
            point["random_skipped"] = (f"predicted solver time {fmt_t(guess)} s > "
                                       f"{fmt_t(mode.general_cap)} s"
                                       + ("" if mode.full else " (--full for more)"))
        else:
            budget = mode.general_cap if guess is None else max(guess, mode.general_cap)
            jobs["random"] = {"text": config_text(f"general-random-{n}", n, 1, 1.5,
                                                  chain=RANDOM_LINE),
                              "timeout": 4 * budget + 60}
        if "random_skipped" in point:
            log(f"  random: skipped, {point['random_skipped']}")
        point.update(alternate(procs, jobs, mode.general_runs, read_diagnostics=True))
        point["ratio"] = ratio(point.get("random"), point["uniform"])
        uni, rnd = point["uniform"], point.get("random")
        if guess is not None and uni["walls"]:
            # and the process's start-up and file: the paper's line's whole time, at most
            point["random_predicted"] = guess + median(uni["walls"])
        if rnd and rnd["walls"] and not rnd["errors"] and rnd["diagnostics"]:
            done.append((n, rnd["diagnostics"]["wall_time"]))
        elif rnd:
            stopped = f"the random line failed at N = {n}"
        out.series.append(point)
    out.requirement = verdict(out.series[-1])

    n = mode.units_n
    log(f"general: N = {n}, the steel line in SI units against the paper's line")
    jobs = {"paper": {"text": config_text(f"units-paper-{n}", n, 1, 1.5), "timeout": 600.0},
            "si": {"text": config_text(f"units-si-{n}", n, 1, None, top={"units": "si"},
                                       chain=SI_LINE), "timeout": 600.0}}
    units = {"n": n, "si_line": SI_LINE}
    units.update(alternate(procs, jobs, mode.general_runs, read_diagnostics=True))
    units["ratio"] = ratio(units["si"], units["paper"])
    dp, ds = units["paper"]["diagnostics"], units["si"]["diagnostics"]
    units["same_work"] = (None if not dp or not ds else
                          (dp["events"], dp["steps"]) == (ds["events"], ds["steps"]))
    out.units = units
    return out
