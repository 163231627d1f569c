"""Recipes for the Hertz contact force (alpha = 3/2): Figs 8-13, Table 1, sections 5a-5c.

This module owns what is derived from the Hertz runs, one function per artefact of
``chainrun.artefacts``. A wave of "equivalent single-impact velocity" V is a scaled copy
of the K = 1 solitary wave: by the scaling of section 2, its displacement is
``D1 V^(4/5)`` and its speed ``c1 V^(1/5)``, and a single ball struck at V ejects balls at
exactly V times the K = 1 ejection velocities. D1, c1 and those ejection velocities come
from the ``sec5a`` analysis.
"""

from __future__ import annotations

import numpy as np

from chainrun.analysis import Inputs, Result
from chainrun.analysis import derived, nesterenko

__all__ = ["fig08", "fig09", "fig10", "fig11", "fig12", "fig13", "sec5a", "sec5b", "sec5c",
           "table1"]

#: Dimensional speed: d (k^2 V/m^2)^(1/5) = (4/pi^2)^(1/5) [E^2 V/(rho^2 (1-nu^2)^2)]^(1/5)
#: for solid spheres, k = d^(1/2) E/(3(1-nu^2)) and m = pi rho d^3/6 (section 5a).
DIMENSIONAL_FACTOR = (4.0 / np.pi**2) ** 0.2

#: Table 1 as printed (rows n = 1..5, columns K = 1..4).
TABLE1_PRINTED = (
    ("-0.0711", "-0.1126", "-0.1397", "0.0112"),
    ("-0.0303", "-0.0420", "0.1996", "0.8729"),
    ("-0.0145", "0.2145", "0.7855", "1.015"),
    ("0.1270", "0.8004", "1.042", "1.030"),
    ("0.9888", "1.140", "1.113", "1.071"),
)

#: How close the displacement at separation must be to the saturated one for the wave to
#: count as saturated ("after a period of adjustment to t = 15").
SATURATION = 1e-3


def _rebound(r: Result, run, fit=(2, 15)) -> None:
    """The rebound numbers of section 5a from a K = 1 line's final velocities."""
    v = run.final_velocity
    n = np.arange(1, len(v) + 1)
    for i in (1, 2, 3):
        r.value(f"v_{i}", v[i - 1], f"rebound velocity of ball {i}")
    r.value("rebound_significant", derived.count_significant(v, -1, derived.impact_speed(run)),
            "balls rebounding faster than 1% of the impact velocity")
    r.value("rebound_energy_percent",
            100 * derived.rebound_energy_share(v, run.line.mass, run.impact_energy),
            "kinetic energy of the rebounding balls, % of the impact energy")
    r.value("rebound_momentum", derived.rebound_momentum(v, run.line.mass),
            "total momentum of the rebounding balls")
    for lo, hi in (fit, (3, fit[1])):
        sel = (n >= lo) & (n <= hi)
        a, b = derived.exponential_fit(n[sel], v[sel])
        r.value(f"fit_{lo}_{hi}_a", a, f"a of |v_n| = a exp(-b n), least squares in log, "
                                       f"balls {lo}..{hi}")
        r.value(f"fit_{lo}_{hi}_b", b, f"b of the same fit, balls {lo}..{hi}")
    sel = (n >= fit[0]) & (n <= fit[1])
    printed = 0.084 * np.exp(-0.55 * n[sel])
    r.value("printed_line_error", np.max(np.abs(-v[sel] / printed - 1)),
            f"largest relative distance of 0.084 exp(-0.55 n) from |v_n|, balls {fit[0]}..{fit[1]}")
    seg = v[fit[0] - 1:fit[1] + 1]
    rate = np.log(seg[:-1] / seg[1:])      # log(v_n/v_(n+1)) for n in the fit range
    r.value("decay_rate_min", rate.min(),
            f"smallest local rate log(v_n/v_(n+1)), balls {fit[0]}..{fit[1]}")
    r.value("decay_rate_max", rate.max(),
            f"largest local rate log(v_n/v_(n+1)), balls {fit[0]}..{fit[1]}")
    r.setting("rebound_fit_balls", list(fit))


def _ejected(r: Result, v: np.ndarray, count: int = 3, prefix: str = "ejected") -> None:
    for i in range(1, count + 1):
        r.value(f"{prefix}_{i}", v[-i], f"final velocity of ball N - {i - 1} (ejected)")


def sec5a(inputs: Inputs) -> Result:
    """The steady solitary wave, the rebound and the ejection for one impacting ball."""
    run = inputs.run("sec5a-solitary-wave")
    r = Result()
    window, balls = (40.0, 80.0), (30, 80)
    wave = derived.solitary_wave(run, window, balls)
    r.value("speed", wave.speed, f"speed of the wave: balls per unit time between the "
                                 f"velocity peaks of balls {balls[0]}..{balls[1]}")
    r.value("dimensional_speed", wave.speed * DIMENSIONAL_FACTOR,
            "coefficient of [E^2 V/(rho^2 (1-nu^2)^2)]^(1/5) in the dimensional speed")
    r.value("displacement", wave.displacement,
            "saturated displacement: median displacement at separation, same balls")
    r.value("max_velocity", wave.max_velocity, "peak velocity of a ball as the wave passes")
    r.value("max_force", wave.max_force, "peak contact force (compression^(3/2))")
    r.value("momentum", wave.momentum, f"momentum of the wave, mean over t in {window}")
    r.value("energy", wave.energy, "energy of the wave, mean over the window")
    r.value("kinetic_mean", wave.kinetic_mean, "kinetic energy of the wave, mean")
    r.value("kinetic_min", wave.kinetic_min, "kinetic energy of the wave, smallest")
    r.value("kinetic_max", wave.kinetic_max, "kinetic energy of the wave, largest")
    r.value("kinetic_midrange", 0.5 * (wave.kinetic_min + wave.kinetic_max),
            "midpoint of the kinetic energy's range")
    r.value("potential_mean", wave.potential_mean, "potential energy of the wave, mean")
    r.value("width", wave.width, "balls of the wave moving faster than 1% of its peak "
                                 "velocity, mean over the window")
    sep = derived.position_at_separation(run)
    off = np.abs(sep / wave.displacement - 1) > SATURATION
    first = int(np.flatnonzero(off[: balls[1]])[-1]) + 1   # last unsaturated ball, 0-based + 1
    r.value("saturation_time", run.separation_time[first],
            f"separation time of the first ball after which the displacement at separation "
            f"stays within {SATURATION:.1%} of the saturated value")
    r.value("saturation_ball", first + 1, "that ball")
    v = run.final_velocity
    _rebound(r, run)
    _ejected(r, v)
    r.array("energy/t", wave.times)
    r.array("energy/kinetic", wave.kinetic)
    r.array("energy/potential", wave.potential)
    # the simulated strain and velocity profiles at the middle of the window, for 5b
    t = np.asarray(run.times)
    i = int(derived.nearest_snapshots(t, 0.5 * sum(window))[0])
    x = np.asarray(run.positions[i])
    vel = np.asarray(run.velocities[i])
    centre = wave.speed * t[i]
    strain = x[:-1] - x[1:]
    r.array("profile/contact_position", np.arange(1, run.n) + 0.5 - centre)
    r.array("profile/strain", strain)
    r.array("profile/ball_position", np.arange(1, run.n + 1) - centre)
    r.array("profile/velocity", vel)
    r.value("profile_time", t[i], "time of the stored profile")

    # the line length: ejected velocities of lines of 5..30 balls
    lengths, table = [], []
    for line in inputs.runs("sec5a-line-length"):
        lengths.append(line.n)
        table.append(line.final_velocity[-3:][::-1])
        if line.n == 5:
            for j in range(5):
                r.value(f"five_v_{j + 1}", line.final_velocity[j],
                        f"final velocity of ball {j + 1} of a line of five")
    lengths = np.array(lengths)
    table = np.array(table)
    r.array("line_length/n", lengths)
    r.array("line_length/ejected", table)
    converged = table[-1]
    for j, decimals in enumerate((3, 3, 3)):
        ok = np.round(table[:, j], decimals) == np.round(converged[j], decimals)
        bad = np.flatnonzero(~ok)
        shortest = lengths[bad[-1] + 1] if len(bad) else lengths[0]
        r.value(f"shortest_line_{j + 1}", shortest,
                f"shortest line from which ejected velocity {j + 1} equals its converged "
                f"value to {decimals} decimals")
        for length in (9, 10):
            r.value(f"ejected_{j + 1}_N{length}", table[lengths == length, j][0],
                    f"ejected velocity {j + 1} of a line of {length}")
    r.setting("window", list(window))
    r.setting("balls", list(balls))
    r.setting("saturation", SATURATION)
    return r


def sec5b(inputs: Inputs) -> Result:
    """Nesterenko's wave with the net displacement of the simulated one, against it."""
    sim = inputs.analysis("sec5a")
    r = Result()
    d = sim.values["displacement"]
    wave = nesterenko.from_displacement(d)
    r.value("amplitude", wave.amplitude, "A from (3 pi sqrt5/(8 sqrt2)) A = the simulated "
                                         "saturated displacement")
    r.value("speed", wave.speed, "c = (2/sqrt5) A^(1/4)")
    r.value("max_velocity", wave.max_velocity, "A c")
    r.value("max_force", wave.max_force, "(9/10) A^(3/2), from (5.1)")
    r.value("momentum", wave.momentum, "(3 pi sqrt5/(8 sqrt2)) A c")
    r.value("kinetic", wave.kinetic_energy, "35 pi sqrt2/(128 sqrt5) A^(5/2)")
    r.value("potential", wave.potential_energy, "28 pi sqrt2/(128 sqrt5) A^(5/2)")
    r.value("c_squared_over_sqrt_a", wave.speed**2 / np.sqrt(wave.amplitude),
            "c^2 / A^(1/2) (4/5)")
    r.value("force_peak_factor", wave.max_force / wave.amplitude**1.5,
            "largest (3/5)(sin^6 + sin^4/2): 0.9")
    r.value("speed_change_percent", 100 * nesterenko.velocity_change_from_force_law(),
            "change of the predicted speed when the force is (5.1) rather than its "
            "leading term, %")
    pairs = {"max_velocity": ("max_velocity", wave.max_velocity),
             "max_force": ("max_force", wave.max_force),
             "kinetic": ("kinetic_mean", wave.kinetic_energy),
             "potential": ("potential_mean", wave.potential_energy),
             "speed": ("speed", wave.speed),
             "momentum": ("momentum", wave.momentum)}
    for key, (simulated, predicted) in pairs.items():
        s = sim.values[simulated]
        r.value(f"{key}_lower_percent", 100 * (s - predicted) / s,
                f"how much lower Nesterenko's {key} is than the simulated one, %")
    # the profiles, simulated and predicted, aligned at their centres
    for kind, field, fn in (("strain", "contact_position", wave.strain),
                            ("velocity", "ball_position", wave.velocity)):
        s = sim.arrays[f"profile/{field}"]
        y = sim.arrays[f"profile/{kind}"]
        centre = float(np.sum(s * y) / np.sum(y))       # centroid of the simulated pulse
        predicted = fn(s - centre + wave.width / 2)
        r.array(f"profile/{kind}/position", s - centre)
        r.array(f"profile/{kind}/simulated", y)
        r.array(f"profile/{kind}/nesterenko", predicted)
        r.value(f"{kind}_profile_max_difference", np.max(np.abs(y - predicted)),
                f"largest difference of the {kind} profiles, aligned at their centroids")
    return r


def _snapshots_at(run, wanted) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(run.times)
    idx = derived.nearest_snapshots(t, wanted)
    return idx, t[idx]


def _displacement_figure(r: Result, run, wanted) -> None:
    idx, times = _snapshots_at(run, wanted)
    n = np.arange(1, run.n + 1)
    for i, t in zip(idx, times):
        x = np.asarray(run.positions[int(i)])
        r.series("series", f"t={t:g}", n, x, label=f"t = {t:g}")
    r.setting("times", [float(t) for t in times])


def fig08(inputs: Inputs) -> Result:
    """Hertz displacement wave x_n against n at t = 5, 10, ..., 50."""
    run = inputs.run("fig08")
    r = Result()
    _displacement_figure(r, run, np.asarray(run.times))
    sep = derived.position_at_separation(run)
    lo, hi = 20, 40
    r.value("displacement", np.median(sep[lo - 1:hi]),
            f"saturated displacement: median displacement at separation, balls {lo}..{hi}")
    x = np.asarray(run.positions)
    r.value("plateau_last", np.median(x[-1, lo - 1:hi]),
            f"median displacement of balls {lo}..{hi} at the last snapshot")
    return r


def fig09(inputs: Inputs) -> Result:
    """Rebound velocities -v_n (semi-log) and the printed line 0.084 exp(-0.55 n)."""
    run = inputs.run("fig09")
    r = Result()
    v = run.final_velocity
    shown = 20
    n = np.arange(1, shown + 1)
    back = v[:shown] < 0
    r.series("series", "rebound", n[back], -v[:shown][back], label="rebound velocity")
    r.series("series", "printed", n.astype(float), 0.084 * np.exp(-0.55 * n), role="guide",
             label=r"$0.084\,e^{-0.55n}$")
    _rebound(r, run)
    _ejected(r, v)
    r.setting("balls_shown", shown)
    return r


def _wave_train(r: Result, run, single, waves: int, balls: tuple[int, int]) -> None:
    """The K waves of a multi-ball impact, their equivalent single impacts and ejections."""
    d1, c1 = single.values["displacement"], single.values["speed"]
    e1, e2 = single.values["ejected_1"], single.values["ejected_2"]
    train = derived.wave_train(run, waves, balls)
    k = run.k
    v = np.sort(run.final_velocity[-2 * k:])[::-1]
    for i in range(waves):
        w = i + 1
        d = train.displacement[i]
        equivalent = (d / d1) ** 1.25
        r.value(f"displacement_{w}", d, f"(additional) displacement of wave {w}, median over "
                                        f"balls {balls[0]}..{balls[1]}")
        r.value(f"speed_{w}", train.speed[i], f"speed of wave {w}: balls per unit time "
                                              f"between its velocity peaks")
        r.value(f"peak_{w}", train.peak[i], f"peak velocity of wave {w}")
        r.value(f"equivalent_{w}", equivalent,
                f"single-impact velocity of wave {w}: (D_{w}/D_1)^(5/4), D_1 from sec5a")
        r.value(f"speed_scaled_{w}", c1 * equivalent**0.2,
                f"speed of a single impact at that velocity, c_1 V^(1/5)")
        if w <= k:
            r.value(f"lead_{w}", v[i], f"faster ball ejected by wave {w} (final velocities of "
                                       f"the last 2K balls, sorted: the K fastest lead)")
            r.value(f"second_{w}", v[k + i], f"slower ball ejected by wave {w}")
            r.value(f"pseudo_lead_{w}", equivalent * e1,
                    f"ball a single impact at V_{w} would eject first: V_{w} x {e1:.5f}")
            r.value(f"pseudo_second_{w}", equivalent * e2,
                    f"ball it would eject second: V_{w} x {e2:.5f}")
    r.setting("balls", list(balls))


def fig10(inputs: Inputs) -> Result:
    """Two impacting balls, N = 50: displacements at t = 5, ..., 50 and the two waves."""
    run = inputs.run("fig10")
    r = Result()
    _displacement_figure(r, run, np.arange(5.0, 50.0 + 1e-9, 5.0))
    _wave_train(r, run, inputs.analysis("sec5a"), 2, (25, 40))
    return r


def fig11(inputs: Inputs) -> Result:
    """Three impacting balls, N = 100: displacements at t = 10, ..., 100 and the waves."""
    run = inputs.run("fig11")
    r = Result()
    _displacement_figure(r, run, np.arange(10.0, 100.0 + 1e-9, 10.0))
    _wave_train(r, run, inputs.analysis("sec5a"), 3, (50, 85))
    return r


def sec5c(inputs: Inputs) -> Result:
    """Four impacting balls: the fastest wave's displacement, and one wave per ball."""
    run = inputs.run("sec5c-four-impacting")
    r = Result()
    _wave_train(r, run, inputs.analysis("sec5a"), 1, (60, 170))
    single = inputs.analysis("sec5a").values
    lead = r.values["lead_1"]
    r.value("displacement_from_lead", single["displacement"]
            * (lead / single["ejected_1"]) ** 0.8,
            "D_1 (V/1)^(4/5) with V = (fastest ejected)/(K = 1 fastest ejected): the fastest "
            "wave's displacement inferred from the ejection instead of measured")
    r.value("displacement_from_lead_rounded", 1.354 * (round(lead, 3) / 0.986) ** 0.8,
            "the same with the paper's rounded 1.354 and 0.986 and the ejected velocity "
            "rounded to 3 decimals")
    ball = 60
    times, _ = derived.refined_peaks(np.asarray(run.times), np.asarray(run.velocities[:, ball - 1]),
                                     0.02)
    r.value("waves", len(times), f"velocity peaks (above 0.02) passing ball {ball} by "
                                 f"t = {run.times[-1]:g}")
    return r


def fig12(inputs: Inputs) -> Result:
    """Final velocities of the ejected balls against (N - n + 1/2)/K, K = 3, 6, 9, 12."""
    r = Result()
    decades = []
    for run in inputs.runs("fig12"):
        big_n, k = run.n, run.k
        v = run.final_velocity
        n = np.arange(1, big_n + 1)
        X = (big_n - n + 0.5) / k
        keep = (X <= 2.5) & (v > 0)
        r.series("series", f"K={k}", X[keep], v[keep], label=f"K = {k}")
        ratio = v[big_n - k - 1] / v[big_n - 2 * k]     # balls n = N-K and n = N-2K+1
        decades.append(np.log10(ratio))
        r.value(f"decades_K{k}", decades[-1], f"log10 of v_(N-K)/v_(N-2K+1), K = {k}: the "
                                              f"decay along the second balls of the waves")
    r.value("decades_mean", np.mean(decades), "mean of those over the four K")
    return r


def fig13(inputs: Inputs) -> Result:
    """Rebound velocities -v_n against n/K, K = 10, 20, 30, 40, 60, 80."""
    r = Result()
    ratios = []
    for run in inputs.runs("fig13"):
        k = run.k
        v = run.final_velocity
        n = np.arange(1, run.n + 1)
        back = v < 0
        r.series("series", f"K={k}", n[back] / k, -v[back], label=f"K = {k}")
        significant = derived.count_significant(v, -1, derived.impact_speed(run))
        r.value(f"rebound_K{k}", np.sum(back), f"balls with a negative final velocity, K = {k}")
        r.value(f"significant_K{k}", significant,
                f"balls rebounding faster than 1% of V, K = {k}")
        ratios.append(significant / k)
    r.value("significant_ratio_median", np.median(ratios),
            "median over K of (balls rebounding faster than 1%)/K")
    r.value("significant_ratio_K10", ratios[0], "(balls rebounding faster than 1%)/K, "
                                                "smallest K")
    r.value("significant_ratio_K80", ratios[-1], "(balls rebounding faster than 1%)/K, "
                                                 "largest K")
    return r


def table1(inputs: Inputs) -> Result:
    """Final velocities of a line of five spheres struck by K = 1..4 spheres."""
    r = Result()
    runs = sorted(inputs.runs("table1"), key=lambda run: run.k)
    table = np.column_stack([run.final_velocity for run in runs])
    r.array("table/velocity", table)
    r.array("table/k", np.array([run.k for run in runs]))
    r.array("table/paper", np.array(TABLE1_PRINTED, dtype=str))
    for run in runs:
        for n in range(1, run.n + 1):
            r.value(f"v_{n}_K{run.k}", run.final_velocity[n - 1],
                    f"final velocity of ball {n}, K = {run.k}")
    # the exact mirror symmetry v_n(K) = 1 - v_(N+1-n)(N-K), applied to the printed K = 1
    r.value("mirror_v_2_K4", 1 - float(TABLE1_PRINTED[3][0]),
            "1 - (printed v_4, K = 1): what the paper's own K = 1 column implies for v_2, K = 4")
    r.value("mirror_v_3_K4", 1 - float(TABLE1_PRINTED[2][0]),
            "1 - (printed v_3, K = 1)")
    return r
