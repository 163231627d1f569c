"""Recipes for the linear contact force (alpha = 1): Figs 1-7 and the numbers of section 4.

This module owns what is derived from the linear runs, one function per artefact of
``chainrun.artefacts``. Each takes the ``Inputs`` of its artefact and returns a
``Result``: the arrays its figure draws (already scaled as the paper plots them) and the
named values the comparison table uses.
"""

from __future__ import annotations

import numpy as np

from chainrun.analysis import Inputs, Result
from chainrun.analysis import derived, similarity

__all__ = ["fig01", "fig02", "fig03", "fig04", "fig05", "fig06", "fig07", "sec4"]

#: The balls whose loss of contact sets the times of Figs 3-5.
LOSS_BALLS = (10, 20, 30, 40)
#: The shift of Fig 5 (section 4e).
FIG5_SHIFT = 0.25


def _time_label(t: float) -> str:
    return f"t = {t:.1f}"


def fig01(inputs: Inputs) -> Result:
    """x_n(t) + n for the 7 balls; the dashed line of slope 1; who rebounds, who flies."""
    run = inputs.run("fig01")
    r = Result()
    t = np.asarray(run.times)
    x = np.asarray(run.positions)
    for n in range(1, run.n + 1):
        r.series("series", f"n={n}", t, x[:, n - 1] + n, label=f"n = {n}")
    guide_t = np.array([0.0, float(run.n - 1)])
    r.series("series", "slope-1", guide_t, guide_t + 1.0, role="guide",
             label="slope 1 (the disturbance reaches ball n at t = n - 1)")
    v = run.final_velocity
    for n in range(1, run.n + 1):
        r.value(f"v_{n}", v[n - 1], f"final velocity of ball {n}")
    r.value("rebound_count", np.sum(v < 0), "balls with a negative final velocity")
    r.value("forward_significant", derived.count_significant(v, +1, derived.impact_speed(run)),
            "balls moving forward faster than 1% of the impact velocity")
    r.value("forward_fast", np.sum(v > 0.1), "balls moving forward faster than 0.1")
    r.value("slow_forward", np.sum((v > 0) & (v <= 0.1)),
            "balls moving forward, but slower than 0.1")
    r.value("terminal_time", run.end_time, "time of the terminal state")
    r.setting("shift", "x_n(t) + n")
    return r


def fig02(inputs: Inputs) -> Result:
    """Rebound velocities -v_n of 25 balls on log-log axes, with a guide of slope -3/4."""
    run = inputs.run("fig02")
    r = Result()
    v = run.final_velocity
    n = np.arange(1, run.n + 1)
    back = v < 0
    r.series("series", "rebound", n[back], -v[back], label="rebound velocity")
    fit_range = (5, 20)
    sel = back & (n >= fit_range[0]) & (n <= fit_range[1])
    # the dashed guide: slope -3/4 through the geometric mean of the data it guides
    c = float(np.exp(np.mean(np.log(-v[sel] * n[sel] ** 0.75))))
    gn = np.array([1.0, float(run.n)])
    r.series("series", "slope", gn, c * gn**-0.75, role="guide", label="slope -3/4")
    r.value("guide_coefficient", c, "coefficient C of the dashed guide C n^(-3/4)")
    r.value("slope_fit", derived.loglog_slope(n[sel], v[sel]),
            "least-squares log-log slope of the rebound velocities, balls 5..20")
    r.value("rebound_significant", derived.count_significant(v, -1, derived.impact_speed(run)),
            "balls rebounding faster than 1% of the impact velocity")
    r.value("rebound_count", np.sum(back), "balls with a negative final velocity")
    r.value("rebound_energy_percent",
            100 * derived.rebound_energy_share(v, run.line.mass, run.impact_energy),
            "kinetic energy of the rebounding balls, % of the impact energy")
    r.setting("guide_fit_balls", list(fit_range))
    return r


def _loss_snapshots(inputs: Inputs, experiment: str):
    """The run of Figs 3-5 and, for each snapshot, the last ball not touching others."""
    run = inputs.run(experiment)
    t = np.asarray(run.times)
    sep = run.separation_time
    last = []
    for ti in t:
        gone = np.flatnonzero(sep <= ti)
        last.append(int(gone.max()) + 1 if len(gone) else 0)
    return run, t, np.array(last)


def _loss_values(r: Result, run, t, last) -> None:
    for i, ball in enumerate(LOSS_BALLS):
        r.value(f"loss_time_{ball}", run.separation_time[ball - 1],
                f"time at which ball {ball} loses contact (from the event log)")
        r.value(f"snapshot_{i}_time", t[i], f"time of snapshot {i}")
        r.value(f"snapshot_{i}_last_free", last[i],
                f"last ball not touching others at snapshot {i} (expected {ball})")


def fig03(inputs: Inputs) -> Result:
    """Velocity v_n against n at the four loss-of-contact times."""
    run, t, last = _loss_snapshots(inputs, "fig03")
    r = Result()
    v = np.asarray(run.velocities)
    n = np.arange(1, run.n + 1)
    for i, ti in enumerate(t):
        r.series("series", _time_label(ti), n, v[i], label=_time_label(ti))
    _loss_values(r, run, t, last)
    return r


def fig04(inputs: Inputs) -> Result:
    """Displacement x_n against n at the four loss-of-contact times."""
    run, t, last = _loss_snapshots(inputs, "fig04")
    r = Result()
    x = np.asarray(run.positions)
    n = np.arange(1, run.n + 1)
    for i, ti in enumerate(t):
        r.series("series", _time_label(ti), n, x[i], label=_time_label(ti))
        r.value(f"peak_displacement_{i}", x[i].max(), f"largest displacement at snapshot {i}")
    _loss_values(r, run, t, last)
    return r


def _similarity_values(r: Result, prefix: str = "") -> similarity.AirySolution:
    """Both solutions of (4.9) with the paper's normalization, and how well they agree."""
    exact = similarity.airy()
    shot = similarity.shoot()
    r.value(f"{prefix}xi0_airy", exact.xi0, "rear of the wave xi0 = a1/2^(1/3) (Airy form)")
    r.value(f"{prefix}xi0_shooting", shot.xi0,
            "rear of the wave, shooting backwards from xi_inf = 3")
    r.value(f"{prefix}f0_airy", exact.f0, "f(xi0), Airy form, wave energy 96.2% of 1/2")
    r.value(f"{prefix}f0_shooting", shot.f0, "f(xi0), shooting from xi_inf = 3")
    r.value(f"{prefix}peak_airy", exact.peak, "largest -f' (Airy form)")
    r.value(f"{prefix}peak_shooting", shot.peak, "largest -f' (shooting)")
    r.value(f"{prefix}rebound_coefficient", -exact.f0 / 6, "-f(xi0)/6 (Airy form)")
    r.value(f"{prefix}shooting_max_error",
            max(np.max(np.abs(shot.f - exact.f(shot.xi))),
                np.max(np.abs(shot.df - exact.df(shot.xi)))),
            "largest |f - f_Airy| or |f' - f'_Airy| on the shooting grid")
    return exact


def fig05(inputs: Inputs) -> Result:
    """The self-similar wave: v_n a against (n - n1 - 0.25)/a^2, and -f' f(xi0)."""
    run, t, last = _loss_snapshots(inputs, "fig05")
    r = Result()
    x = np.asarray(run.positions)
    v = np.asarray(run.velocities)
    n = np.arange(1, run.n + 1)
    exact = _similarity_values(r)
    f0 = exact.f0

    def theory(X):
        return -exact.df(X * f0**2 + exact.xi0) * f0

    for i, ti in enumerate(t):
        n1 = last[i]
        a = x[i, n1 - 1]
        X = (n - n1 - FIG5_SHIFT) / a**2
        keep = (X >= -0.5) & (X <= 4.0)
        r.series("series", _time_label(ti), X[keep], v[i, keep] * a, label=_time_label(ti))
        r.value(f"amplitude_{i}", a, f"a = x_n1 at snapshot {i}")
        r.value(f"last_free_{i}", n1, f"n1, the last ball not touching others, snapshot {i}")
        # the shift that best aligns this snapshot's wave (n >= n1) with the theory
        wave = n >= n1
        shifts = np.linspace(-1.0, 1.0, 2001)
        errors = [np.sum((v[i, wave] * a - theory((n[wave] - n1 + s) / a**2)) ** 2)
                  for s in shifts]
        r.value(f"best_shift_{i}", -shifts[int(np.argmin(errors))],
                f"shift s in (n - n1 - s)/a^2 that best fits the theory, snapshot {i}")
    xi = np.linspace(exact.xi0, exact.xi0 + 4.0 * f0**2, 801)
    r.series("series", "theory", (xi - exact.xi0) / f0**2, -exact.df(xi) * f0, role="theory",
             label="solution of (4.9)")
    r.setting("shift", FIG5_SHIFT)
    r.setting("energy_share", similarity.PAPER_ENERGY_SHARE)
    return r


def fig06(inputs: Inputs) -> Result:
    """v_n n^(5/6) and v_n n^(3/4) against 1/n for the rebounding balls of 200."""
    run = inputs.run("fig06")
    r = Result()
    v = run.final_velocity
    n = np.arange(1, run.n + 1)
    # rebounding balls the far end does not reach: its reflection spans ~ N^(1/3) balls
    shown = n <= run.n - 3 * run.n ** (1 / 3)
    back = (v < 0) & shown
    r.series("series", "n^5:6", 1.0 / n[back], v[back] * n[back] ** (5 / 6),
             label=r"$\dot x_n(\infty)\, n^{5/6}$")
    r.series("series", "n^3:4", 1.0 / n[back], v[back] * n[back] ** 0.75,
             label=r"$\dot x_n(\infty)\, n^{3/4}$")
    lo, hi = run.n // 2, int(0.9 * run.n)
    sel = back & (n >= lo) & (n <= hi)
    y = v[sel] * n[sel] ** (5 / 6)
    r.value("limit_linear", derived.polynomial_extrapolation(1.0 / n[sel], y),
            f"v n^(5/6) extrapolated to 1/n = 0 by a straight line in 1/n through balls "
            f"{lo}..{hi} (how the limit reads off Fig 6)")
    c = derived.power_series_fit(n[sel], y, (2 / 3, 1))
    r.value("limit_fit", c[0], f"limit of v n^(5/6) from a fit c0 + c1 n^(-2/3) + c2/n, "
            f"balls {lo}..{hi}")
    r.value("last_value", y[-1], f"v n^(5/6) at ball {hi}")
    r.value("v_1", v[0], "rebound velocity of the impacting ball")
    r.setting("fit_balls", [lo, hi])
    r.setting("balls_shown", int(n[shown].max()))
    return r


def fig07(inputs: Inputs) -> Result:
    """v_n N^(1/6) against (N - n)/N^(1/3) near the far end, for each N."""
    r = Result()
    lengths, coefficients, counts = [], [], []
    for run in inputs.runs("fig07"):
        big_n = run.n
        v = run.final_velocity
        n = np.arange(1, big_n + 1)
        X = (big_n - n) / big_n ** (1 / 3)
        keep = X <= 3.0
        r.series("series", f"N={big_n}", X[keep], v[keep] * big_n ** (1 / 6),
                 label=f"N = {big_n}")
        coefficient = v[-1] * big_n ** (1 / 6)
        count = derived.count_significant(v, +1, derived.impact_speed(run)) / big_n ** (1 / 3)
        r.value(f"coefficient_N{big_n}", coefficient, f"v_N N^(1/6) for N = {big_n}")
        r.value(f"significant_N{big_n}", count,
                f"balls flying off faster than 1% of V, over N^(1/3), N = {big_n}")
        lengths.append(big_n)
        coefficients.append(coefficient)
        counts.append(count)
    r.value("significant_mean", np.mean(counts),
            "mean over the four lines of (balls faster than 1% of V)/N^(1/3)")
    c = derived.power_series_fit(np.array(lengths, float), coefficients, (2 / 3,))
    r.value("coefficient_limit", c[0], "v_N N^(1/6) extrapolated to N -> inf "
                                       "(fit c0 + c1 N^(-2/3) through the four lines)")
    r.value("coefficient_largest_N", coefficients[int(np.argmax(lengths))],
            "v_N N^(1/6) for the longest line")
    return r


def sec4(inputs: Inputs) -> Result:
    """The long linear line: energy shares, the rebound law's limit, the theory of 4d-4e."""
    run = inputs.run("sec4-long-line")
    r = Result()
    v = run.final_velocity
    big_n = run.n
    n = np.arange(1, big_n + 1)

    # energy share of the rebounding balls: partial sums, extrapolated in M^(-2/3), 1/M
    lo, hi = big_n // 10, int(0.9 * big_n)
    partial = np.cumsum(run.line.mass * np.where(v < 0, v, 0.0) ** 2) / (2 * run.impact_energy)
    m = np.arange(lo, hi + 1)
    c = derived.power_series_fit(m, partial[m - 1], (2 / 3, 1))
    share = c[0]
    r.value("rebound_energy_percent", 100 * share,
            f"energy of the rebounding balls of an infinite line, % of the impact energy "
            f"(partial sums over balls 1..M, M = {lo}..{hi}, extrapolated in M^(-2/3), 1/M)")
    r.value("wave_energy_percent", 100 * (1 - share), "100% minus the rebounding share")
    r.value("rebound_energy_percent_N",
            100 * derived.rebound_energy_share(v, run.line.mass, run.impact_energy),
            f"energy of the rebounding balls of this line of {big_n}, %")
    # when does the share of the balls separated so far reach the paper's 3.78%?
    order = np.argsort(run.separation_time)
    ts = run.separation_time[order]
    cum = np.cumsum(np.where(v[order] < 0, v[order], 0.0) ** 2)
    reach = int(np.searchsorted(cum, 0.0378))
    r.value("time_share_378", ts[reach],
            "time at which the balls separated so far carry 3.78% of the impact energy")
    r.value("ball_share_378", order[reach] + 1, "the ball separating then")

    sel = (n >= lo) & (n <= hi) & (v < 0)
    cc = derived.power_series_fit(n[sel], v[sel] * n[sel] ** (5 / 6), (2 / 3, 1))
    r.value("rebound_limit", cc[0], f"limit of v_n n^(5/6) (fit c0 + c1 n^(-2/3) + c2/n, "
                                    f"balls {lo}..{hi})")
    r.value("v_1", v[0], "rebound velocity of the impacting ball")
    sel = (n >= big_n // 2) & (n <= hi)
    r.value("rear_speed", np.polyfit(run.separation_time[sel], n[sel], 1)[0],
            f"balls per unit time passed by the rear of the wave, balls {big_n // 2}..{hi}")

    # the theory: (4.9) with the paper's normalization, by both methods
    _similarity_values(r)
    r.value("wkb_exponent", similarity.wkb_exponent(), "(4/3) sqrt 2 of the WKB decay")
    # the wave's decay rate measured on the Airy form: -d log(f xi)/d xi^(3/2) at large xi
    exact = similarity.airy()
    xi = np.array([6.0, 8.0])
    r.value("wkb_exponent_airy",
            -np.diff(np.log(exact.f(xi) * xi))[0] / np.diff(xi**1.5)[0],
            "decay rate of f xi against xi^(3/2) on the Airy form, between xi = 6 and 8")
    own = similarity.airy(1 - share)
    r.value("f0_own_share", own.f0, "f(xi0) normalized with this run's infinite-line share")
    r.value("rebound_coefficient_own_share", -own.f0 / 6, "-f(xi0)/6 with that normalization")
    delta, beta = similarity.shift_and_beta()
    r.value("delta", float(delta), "delta from the two equations of section 4e (-1/4)")
    r.value("beta", float(beta), "beta from the two equations of section 4e (7/24)")
    r.setting("fit_balls", [lo, hi])
    r.setting("energy_share", similarity.PAPER_ENERGY_SHARE)
    r.setting("xi_inf", similarity.PAPER_XI_INF)
    return r
