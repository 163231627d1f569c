"""The gallery's recipes: one per item of ``make gallery`` (``docs/gallery/``).

This module owns what each gallery item derives from its runs: the arrays its figure
draws (as series of the analysis file, with the panel they belong to in ``panel``) and
the named values the gallery's comparison (``chainrun.analysis.gallery_comparison``)
quotes. The measurements themselves are in ``chainrun.analysis.gallery_measure`` and, for
pulses, ``chainrun.analysis.pulse``.

Items: ``solitary`` (Coste et al. 1997; Nesterenko's laws), ``cradle`` (Newton's cradle
in SI, elastic and damped), ``wall`` (Falcon et al. 1998; N = 2K on a wall; elastic and
damped), ``head_on`` (a line struck at
both ends; an impurity), ``taper`` (tapered chains), ``dimer`` (dimer chains),
``transmission`` (a driven dimer chain's transmission, ``chainrun.analysis.transmission``).
"""

from __future__ import annotations

import numpy as np

from chainrun.analysis import Inputs, Result
from chainrun.analysis import derived
from chainrun.analysis import gallery_measure as gm
from chainrun.analysis.pulse import first_pulse, wave_speed
from chainrun.materials import material
from chainrun.solver.physics import line_kinetic_energy, line_momentum

__all__ = ["cradle", "dimer", "head_on", "solitary", "taper", "transmission", "wall"]


def _swept(run, key: str):
    return run.parameters["overrides"][key]


def _first_pulses(run, side: int = 1, baseline: float | None = None):
    """Peak time and force of the first pulse at each sensor (its contact on ``side``:
    0 towards ball 1, 1 away from it)."""
    out = [first_pulse(run.sensor_time, run.sensor_force[:, s, side], baseline)
           for s in range(run.sensor_balls.size)]
    if any(np.isnan(o.peak) for o in out):
        raise ValueError(f"{run.path}: a sensor without a whole pulse")
    return np.array([o.peak_time for o in out]), np.array([o.peak for o in out])


def _bead(run, name: str):
    """The material and diameter of a uniform SI chain (from its config)."""
    chain = run.parameters["config_resolved"]["chain"]
    d = _swept(run, "chain.diameter") if "chain.diameter" in run.parameters["overrides"] \
        else chain["diameter"]
    return material(name), float(d)


# --------------------------------------------------------------------------- solitary
def solitary(inputs: Inputs) -> Result:
    """Solitary waves: the discrete chain's prefactor, steel chains with and without
    precompression, beside Nesterenko's long-wave laws."""
    r = Result()
    r.setting("measure", "first pulse peak of each sensor's contact force away from ball "
                         "1 (parabola through the samples); speed: slope of ball against "
                         "peak time")
    # The prefactor: one wave in the paper's units.
    run = inputs.run("gallery/solitary-prefactor")
    balls = run.sensor_balls
    t, f = _first_pulses(run)
    c = wave_speed(balls, t).value
    F = float(np.mean(f))
    half = balls.size // 2 + 1
    c_a = wave_speed(balls[:half], t[:half]).value
    c_b = wave_speed(balls[half - 1:], t[half - 1:]).value
    ratio = c / F ** (1.0 / 6.0)
    r.value("c", c, "speed of the settled solitary wave, balls per unit time (paper units)")
    r.value("F", F, "its peak contact force (paper units), mean over the sensors")
    r.value("F_spread", float(np.ptp(f) / F), "relative spread of the peak force between "
                                              "balls 40 and 160")
    r.value("c_spread", abs(c_a - c_b) / c, "relative difference of the speeds over balls "
                                           "40-100 and 100-160")
    r.value("ratio", ratio, "c / F^(1/6) of the discrete chain (paper units)")
    r.value("prefactor_discrete", ratio * gm.PAPER_TO_SI,
            "the discrete chain's prefactor C in V = C (4E^2 F/(d^2 rho^3 (1-nu^2)^2))^(1/6)")
    r.value("prefactor_long_wave", gm.long_wave_prefactor(),
            "Nesterenko's long-wave prefactor, peak force by the leading term A^(3/2)")
    r.value("prefactor_long_wave_51", gm.long_wave_prefactor("5.1"),
            "the same with the peak force by (5.1), 0.9 A^(3/2)")
    r.value("prefactor_sound", gm.long_wave_sound_prefactor(),
            "prefactor of the sound speed under a static force F0")
    r.value("prefactor_discrete_over_long_wave", ratio * gm.PAPER_TO_SI
            / gm.long_wave_prefactor(), "discrete over long-wave prefactor")
    r.value("speed_check_0841", ratio * 0.640 ** (1.0 / 6.0),
            "c at the paper's peak force 0.640 by the measured ratio")

    # Steel without precompression.
    law = gm.long_wave_prefactor()
    errors = []
    F_si, V_si = [], []
    for run in inputs.runs("gallery/solitary-steel"):
        mat, d = _bead(run, "chrome_steel")
        t, f = _first_pulses(run)
        V = wave_speed(run.sensor_balls, t).value * d
        Fm = float(np.mean(f))
        group = float(gm.daraio_group(Fm, mat.young, mat.poisson, mat.density, d))
        F_si.append(Fm)
        V_si.append(V)
        errors.append(V / (law * group) - 1.0)
        r.value(f"steel_V_{_swept(run, 'chain.speed'):g}", V,
                f"wave speed (m/s), striker at {_swept(run, 'chain.speed'):g} m/s")
        r.value(f"steel_F_{_swept(run, 'chain.speed'):g}", Fm,
                f"peak contact force (N), striker at {_swept(run, 'chain.speed'):g} m/s")
        r.value(f"steel_C_{_swept(run, 'chain.speed'):g}", V / group,
                "measured prefactor V / (4E^2F/(d^2 rho^3 (1-nu^2)^2))^(1/6)")
    order = np.argsort(F_si)
    F_si, V_si = np.array(F_si)[order], np.array(V_si)[order]
    mat, d = material("chrome_steel"), 0.008
    grid = np.geomspace(F_si[0] / 2, F_si[-1] * 2, 60)
    g = gm.daraio_group(grid, mat.young, mat.poisson, mat.density, d)
    r.series("speed", "chainrun", F_si, V_si, label="chainrun", role="data", panel=0)
    r.series("speed", "discrete", grid, r.values["prefactor_discrete"] * g,
             label=f"{r.values['prefactor_discrete']:.4f} (discrete chain)", role="theory",
             panel=0)
    r.series("speed", "nesterenko", grid, law * g, label="0.6802 (long wave)",
             role="theory", panel=0)
    r.value("steel_law_error_mean", float(np.mean(errors)),
            "mean relative excess of the steel chain's speed over the 0.6802 law")

    # Steel with precompression: V / c0 against F_m / F0, every F0 on one curve.
    fr_all = []
    dev = []
    for run in inputs.runs("gallery/solitary-precompressed"):
        mat, d = _bead(run, "chrome_steel")
        F0 = float(_swept(run, "chain.precompression"))
        t, f = _first_pulses(run, baseline=F0)
        V = wave_speed(run.sensor_balls, t).value * d
        Fm = float(np.mean(f))
        c0 = gm.long_wave_sound_prefactor() * float(
            gm.daraio_group(F0, mat.young, mat.poisson, mat.density, d))
        fr = Fm / F0
        theory = float(gm.nesterenko_precompressed_ratio(fr))
        fr_all.append((F0, fr, V / c0, theory))
        dev.append(V / c0 / theory - 1.0)
        key = f"pre_{F0:g}_{_swept(run, 'chain.speed'):g}"
        r.value(f"{key}_fr", fr, f"F_m / F0, F0 = {F0:g} N, striker "
                                 f"{_swept(run, 'chain.speed'):g} m/s")
        r.value(f"{key}_V", V, "wave speed (m/s)")
        r.value(f"{key}_ratio", V / c0, "V / c0")
    for k, F0 in enumerate(sorted({x[0] for x in fr_all})):
        pts = sorted((x[1], x[2]) for x in fr_all if x[0] == F0)
        r.series("precompressed", f"F0={F0:g}", [p[0] for p in pts], [p[1] for p in pts],
                 label=f"$F_0$ = {F0:g} N", role="data", panel=1, marker=k)
    frs = np.geomspace(1.02, max(x[1] for x in fr_all) * 1.5, 80)
    r.series("precompressed", "nesterenko", frs, gm.nesterenko_precompressed_ratio(frs),
             label="long wave", role="theory", panel=1)
    r.value("pre_dev_max", float(np.max(np.abs(dev))),
            "largest relative deviation of V/c0 from the long-wave law")
    r.value("pre_dev_min", float(np.min(np.abs(dev))),
            "smallest relative deviation of V/c0 from the long-wave law")
    return r


# ----------------------------------------------------------------------------- cradle
#: The cradle's experiments: (experiment, suffix of its values, panel, what it is).
_CRADLES = (("cradle", "", 0, "elastic"),
            ("cradle-damped", "_damped", 1, "e = 0.95, Tsuji"),
            ("cradle-damped-kk", "_kk", None, "e = 0.95 at 0.5 m/s, Kuwabara-Kono"))


def cradle(inputs: Inputs) -> Result:
    """Newton's cradle in SI: Table 1 at 0.5 m/s and the drift in the first second,
    elastic and with a restitution of 0.95 (two damping laws)."""
    r = Result()
    r.setting("drift_time", 1.0)
    both = []  # the (ball, K) of the two damped cradles
    for experiment, sfx, panel, what in _CRADLES:
        for run in inputs.runs(f"gallery/{experiment}"):
            k = run.k
            speed = derived.impact_speed(run)
            v = run.final_velocity
            x = gm.drift(run.final_position, v, run.end_time, 1.0) * 1e3
            if sfx == "_damped":
                both += [(n, k) for n in range(1, run.n + 1)]
            for n in range(1, run.n + 1):
                r.value(f"v_{n}_K{k}{sfx}", v[n - 1],
                        f"final velocity (m/s) of ball {n}, K = {k}, {what}")
                r.value(f"scaled_{n}_K{k}{sfx}", v[n - 1] / speed,
                        f"final velocity of ball {n} over the impact speed, K = {k}, {what}")
                r.value(f"drift_mm_{n}_K{k}{sfx}", x[n - 1],
                        f"displacement (mm) of ball {n} at t = 1 s, K = {k}, {what}")
            r.value(f"contact_us_K{k}{sfx}", run.end_time * 1e6,
                    f"time (microseconds) from first contact to the last, K = {k}, {what}")
            if sfx:
                e0 = run.impact_energy
                kinetic = float(line_kinetic_energy(v, run.line.mass))
                r.value(f"dissipated_K{k}{sfx}", run.dissipated_energy / e0,
                        f"share of the impact energy dissipated, K = {k}, {what}")
                r.value(f"energy_balance_K{k}{sfx}",
                        abs(kinetic + run.dissipated_energy - e0) / e0,
                        f"|final kinetic + dissipated - initial| / initial, K = {k}, {what}")
            if panel is not None:
                r.series("drift" if panel == 0 else "drift_damped", f"K={k}",
                         np.arange(1, run.n + 1), x, label=f"K = {k}", role="data",
                         panel=panel, marker=k - 1)
    r.value("speed", speed, "impact speed (m/s)")
    r.value("law_difference_mm", max(
        abs(r.values[f"drift_mm_{n}_K{k}_damped"] - r.values[f"drift_mm_{n}_K{k}_kk"])
        for n, k in both),
        "largest difference (mm) of a ball's displacement at 1 s between the Tsuji and the "
        "Kuwabara-Kono cradle")
    return r


# ------------------------------------------------------------------------------- wall
def _wall_contact(run) -> tuple[float, float, int]:
    """``gm.wall_contact`` of the right wall (contact N) of a run."""
    return gm.wall_contact(run.event_time, run.event_contact, run.event_kind, run.n)


def _column_restitution(run) -> float:
    return gm.restitution(run.line.mass, run.line.velocity, run.final_velocity)


def _wall_law(run) -> tuple[float, float, float, float]:
    """The right wall's (damping, damping_exponent, stiffness, alpha) as solved."""
    wall = run.model["walls"]["right"]
    return (float(wall["damping"]), float(wall["damping_exponent"]),
            float(wall["stiffness"]), float(wall["alpha"]))


def wall(inputs: Inputs) -> Result:
    """A column hitting a wall, and K balls striking K resting on a wall, elastic and
    with a restitution of 0.95."""
    from chainrun.solver import restitution as two_body

    r = Result()
    tau = gm.hertz_contact_time_factor()
    r.value("hertz_tau", tau, "Hertz's contact time factor: t_c = tau (m^2/(kappa^2 v))^(1/5)")
    for experiment, sfx, what, marker in (("wall-column", "", "elastic", 0),
                                          ("wall-column-damped", "_damped",
                                           "e = 0.95, Tsuji", 2)):
        ns, es, ds = [], [], []
        for run in inputs.runs(f"gallery/{experiment}"):
            n = run.n
            m = run.line.mass
            e = _column_restitution(run)
            release, opened, count = _wall_contact(run)
            ns.append(n)
            es.append(e)
            ds.append(release)
            r.value(f"column_e_{n}{sfx}", e, f"effective restitution, column of {n}, {what}")
            r.value(f"column_duration_us_{n}{sfx}", release * 1e6,
                    f"wall contact duration (microseconds), column of {n}, {what}")
            r.value(f"column_wall_contacts_{n}{sfx}", count,
                    f"separate wall contacts, column of {n}, {what}")
            if sfx:
                e0 = run.impact_energy
                kinetic = float(line_kinetic_energy(run.final_velocity, m))
                r.value(f"column_dissipated_{n}{sfx}", run.dissipated_energy / e0,
                        f"share of the impact energy dissipated, column of {n}, {what}")
                r.value(f"column_wall_dissipated_{n}{sfx}", run.wall_dissipation[1] / e0,
                        f"share of the impact energy dissipated at the wall, column of {n}")
                r.value(f"column_energy_balance_{n}{sfx}",
                        abs(kinetic + run.dissipated_energy - e0) / e0,
                        f"|final kinetic + dissipated - initial| / initial, column of {n}")
                r.value(f"column_open_us_{n}{sfx}", opened * 1e6,
                        f"time the wall's compression is gone (microseconds), column of {n}")
            if n == 1:
                v = float(run.line.velocity[0])
                eta, beta, kappa, alpha = _wall_law(run)
                if sfx:
                    e_law = two_body.restitution(eta, beta, kappa, alpha, m[0], v)
                    t_law = two_body.contact_duration(eta, beta, kappa, alpha, m[0], v)
                    r.value(f"one_e_law{sfx}", e_law,
                            "restitution of one bead on the damped wall, two-body law")
                    r.value(f"one_e_error{sfx}", abs(e - e_law),
                            "|chainrun's restitution of one bead - the two-body law's|")
                    r.value(f"one_t_c_us{sfx}", t_law * 1e6,
                            "contact time of one bead on the damped wall, two-body law "
                            "(microseconds)")
                    r.value(f"one_t_rel_error{sfx}", abs(release / t_law - 1.0),
                            "relative difference of chainrun's contact time from the "
                            "two-body law's")
                else:
                    t_c = tau * (m[0] ** 2 / (kappa**2 * v)) ** 0.2
                    r.value("hertz_t_c_us", t_c * 1e6,
                            "Hertz's contact time of one bead on the wall (microseconds)")
                    r.value("hertz_rel_error", abs(release / t_c - 1.0),
                            "relative difference of chainrun's contact time from Hertz's")
        order = np.argsort(ns)
        ns, es, ds = np.array(ns)[order], np.array(es)[order], np.array(ds)[order]
        label = f"column of N, 0.2 m/s, {what}"
        r.series("restitution", f"column{sfx}", ns, es, label=label, role="data",
                 panel=0, marker=marker)
        r.series("duration", f"column{sfx}", ns, ds / ds[0], label=label, role="data",
                 panel=1, marker=marker)
    for experiment, sfx, what, marker in (
            ("wall-column-speed", "", "elastic", 0),
            ("wall-column-damped-speed", "_damped", "e = 0.95, Tsuji", 2),
            ("wall-column-kk-speed", "_kk", "e = 0.95 at 0.2 m/s, Kuwabara-Kono", 3)):
        speeds, dur, ev = [], [], []
        for run in inputs.runs(f"gallery/{experiment}"):
            v = float(_swept(run, "chain.speed"))
            speeds.append(v)
            dur.append(_wall_contact(run)[0])
            ev.append(_column_restitution(run))
            if sfx:
                cms = f"{round(v * 100)}cms"   # no '.' in a key: the notes quote them
                r.value(f"speed_e_{cms}{sfx}", ev[-1],
                        f"restitution of a column of 8 at {v:g} m/s, {what}")
                r.value(f"speed_duration_us_{cms}{sfx}", dur[-1] * 1e6,
                        f"wall contact duration (microseconds), column of 8 at {v:g} m/s, "
                        f"{what}")
        speeds, dur, ev = (np.array(a)[np.argsort(speeds)] for a in (speeds, dur, ev))
        slope = float(np.polyfit(np.log(speeds), np.log(dur), 1)[0])
        r.value(f"speed_slope{sfx}", slope, "log-log slope of the contact duration of a "
                                            f"column of 8 against the impact speed, {what}")
        r.value(f"speed_e_spread{sfx}", float(np.ptp(ev)),
                f"spread of the restitution of a column of 8 over impact speeds 0.05-3.2 "
                f"m/s, {what}")
        r.value(f"speed_e{sfx}", float(np.mean(ev)),
                f"restitution of a column of 8, mean over speeds, {what}")
        r.series("speed", f"column{sfx}", speeds, ev, label=f"column of 8, {what}",
                 role="data", panel=2, marker=marker)
    for sfx, what, marker in (("", "elastic", 1), ("_damped", "e = 0.95, Tsuji", 3)):
        runs = sorted((inputs.run(e) for e in inputs.artefact.experiments
                       if e.rpartition("-")[0] == f"gallery/wall-2k{sfx.replace('_', '-')}"),
                      key=lambda run: run.k)
        for run in runs:
            k = run.k
            m, v0, v = run.line.mass, run.line.velocity, run.final_velocity
            e = gm.restitution(m, v0, v)
            release, _, count = _wall_contact(run)
            r.value(f"2k_e_{k}{sfx}", e, f"effective restitution, {k} striking {k} on a "
                                         f"wall, {what}")
            r.value(f"2k_strikers_{k}{sfx}", float(np.sum(v[:k]) / k),
                    f"mean final velocity of the {k} strikers, {what}")
            r.value(f"2k_rest_{k}{sfx}", float(np.sum(v[k:]) / (run.n - k)),
                    f"mean final velocity of the {k} balls that rested on the wall, {what}")
            r.value(f"2k_release_{k}{sfx}", release,
                    f"time the wall lets go (paper units), K = {k}, {what}")
            r.value(f"2k_wall_contacts_{k}{sfx}", count,
                    f"separate wall contacts, K = {k}, {what}")
            if sfx:
                r.value(f"2k_dissipated_{k}{sfx}", run.dissipated_energy / run.impact_energy,
                        f"share of the impact energy dissipated, K = {k}, {what}")
        r.series("restitution", f"2k{sfx}", np.array([run.n for run in runs]),
                 [r.values[f"2k_e_{run.k}{sfx}"] for run in runs],
                 label=f"K on K resting on the wall, {what}", role="data", panel=0,
                 marker=marker)
    return r


# ---------------------------------------------------------------------------- head-on
def head_on(inputs: Inputs) -> Result:
    """A line struck at both ends; a light or heavy impurity in the middle."""
    r = Result()
    run = inputs.run("gallery/head-on")
    v = run.final_velocity
    m = run.line.mass
    ends = [0, run.n - 1]
    r.value("symmetry_error", float(np.max(np.abs(v + v[::-1]))),
            "largest |v_n + v_(N+1-n)| (0 by symmetry)")
    r.value("end_speed", float(v[-1]), "final velocity of ball N (the one struck at -1)")
    r.value("end_energy_share", float(line_kinetic_energy(v[ends], m[ends]))
            / run.impact_energy,
            "share of the impact energy carried away by the two end balls")
    r.value("momentum_error", float(abs(line_momentum(v, m))), "|total momentum| (0)")
    r.value("moving_balls", int(np.sum(np.abs(v) > derived.SIGNIFICANT
                                       * derived.impact_speed(run))),
            "balls leaving faster than 1% of the impact speed")
    r.series("head_on", "equal", np.arange(1, run.n + 1), v, label="±1", role="data",
             panel=0, marker=0)
    run = inputs.run("gallery/head-on-unequal")
    u = run.final_velocity
    n = run.n
    r.value("unequal_first", float(u[0]), "final velocity of ball 1, strikers +1 and -0.5")
    r.value("unequal_last", float(u[-1]), "final velocity of ball N, strikers +1 and -0.5")
    r.value("unequal_momentum", float(line_momentum(u, run.line.mass)),
            "total momentum (0.5)")
    r.series("head_on", "unequal", np.arange(1, n + 1), u, label="+1 and −0.5", role="data",
             panel=0, marker=1)
    masses, refl, trans, two = [], [], [], []
    for experiment in (e for e in inputs.artefact.experiments if "impurity" in e):
        run = inputs.run(experiment)
        m = run.line.mass
        at = int(np.argmax(np.abs(m - 1.0))) + 1
        before, on, after = gm.energy_split(m, run.final_velocity, at)
        e0 = run.impact_energy
        mu = float(m[at - 1])
        masses.append(mu)
        refl.append(before / e0)
        trans.append((on + after) / e0)
        two.append(4.0 * mu / (1.0 + mu) ** 2)
        r.value(f"impurity_{mu:g}_reflected", before / e0,
                f"energy share left before the impurity of mass {mu:g}")
        r.value(f"impurity_{mu:g}_transmitted", (on + after) / e0,
                f"energy share in the impurity of mass {mu:g} and beyond")
        r.value(f"impurity_{mu:g}_two_ball", 4.0 * mu / (1.0 + mu) ** 2,
                "energy share a ball of mass 1 gives a ball of this mass at rest")
    mus = np.geomspace(0.2, 5.0, 60)
    r.series("impurity", "transmitted", masses, trans, label="transmitted", role="data",
             panel=1, marker=0)
    r.series("impurity", "reflected", masses, refl, label="reflected", role="data",
             panel=1, marker=1)
    r.series("impurity", "two_ball", mus, 4.0 * mus / (1.0 + mus) ** 2,
             label="two balls, $4\\mu/(1+\\mu)^2$", role="theory", panel=1)
    return r


# ------------------------------------------------------------------------------ taper
def taper(inputs: Inputs) -> Result:
    """Tapered chains: transmitted force and energy against the taper ratio."""
    r = Result()
    qs, force, energy = [], [], []
    for experiment in inputs.artefact.experiments:
        name = experiment.rsplit("-", 1)[1]
        run = inputs.run(experiment)
        q = float(name)
        m = run.line.mass
        first = float(run.sensor_force[:, 0, 0].max())   # contact 1 (balls 1-2)
        last = float(run.sensor_force[:, 1, 1].max())    # contact 19 (balls 19-20)
        e_in = run.impact_energy
        e_out = float(line_kinetic_energy(run.final_velocity[-1:], m[-1:]))
        qs.append(q)
        force.append(last / first)
        energy.append(e_out / e_in)
        r.value(f"force_ratio_{name}", last / first,
                f"peak force of the last contact over the first, taper {name}")
        r.value(f"energy_out_{name}", e_out / e_in,
                f"kinetic energy of the last bead over the impact energy, taper {name}")
        r.value(f"speed_out_{name}", float(run.final_velocity[-1] / derived.impact_speed(run)),
                f"velocity of the last bead over the impact speed, taper {name}")
    r.series("taper", "force", qs, force, label="last contact / first (peak force)",
             role="data", panel=0, marker=0)
    r.series("taper", "energy", qs, energy, label="energy of the last bead / impact",
             role="data", panel=0, marker=1)
    return r


# ------------------------------------------------------------------------------ dimer
def dimer(inputs: Inputs) -> Result:
    """Dimer chains: the energy the wave leaves behind, against the mass ratio."""
    r = Result()
    lo, hi = 11, 40
    r.setting("behind", f"balls {lo}-{hi}")
    ratios, left = [], []
    for experiment in inputs.artefact.experiments:
        name = experiment.rsplit("-", 1)[1]
        run = inputs.run(experiment)
        m = run.line.mass
        v = run.final_velocity
        ratios.append(float(name))
        left.append(float(line_kinetic_energy(v[lo - 1:hi], m[lo - 1:hi]))
                    / run.impact_energy)
        r.value(f"left_{name}", left[-1], f"energy share left in balls {lo}-{hi}, "
                                          f"mass ratio {name}")
    ratios, left = np.array(ratios), np.array(left)
    r.series("dimer", "left", ratios, left, label=f"energy left in balls {lo}-{hi}",
             role="data", panel=0, marker=0)
    # Local minima inside the scanned range, refined by a parabola in log(energy).
    minima = [i for i in range(1, ratios.size - 1)
              if left[i] < left[i - 1] and left[i] < left[i + 1]]
    for j, i in enumerate(minima, start=1):
        # Near a ratio where the tail vanishes its amplitude is linear in the distance to
        # it, so the energy is a parabola there; through the three grid points around it.
        p = np.polyfit(ratios[i - 1:i + 2], left[i - 1:i + 2], 2)
        r.value(f"antiresonance_{j}", -p[1] / (2 * p[0]),
                "mass ratio of a minimum of the energy left behind (parabola through the "
                "three grid points around it)")
        r.value(f"antiresonance_{j}_left", left[i], "energy share left at that grid point")
    r.value("minima", len(minima), "local minima in the scanned ratios")
    return r


# ----------------------------------------------------------------------- transmission
#: A sweep point is stopped when the last bead's amplitude is under this fraction of the
#: first bead's (-20 dB).
STOPPED = 0.1


def transmission(inputs: Inputs) -> Result:
    """A driven dimer chain: the transmission curve of its frequency sweep, the line's
    modes and bands, and its stop bands as the sweep sees them against the closed forms
    of the infinite dimer chain's band edges."""
    from chainrun.analysis.transmission import MIN_PERIODS, STEADY, measure_sweep

    r = Result()
    runs = inputs.runs("gallery/transmission-dimer")
    t = measure_sweep(runs)
    f = t["frequency"].values
    first, last = int(t["sensor"].values[0]), int(t["sensor"].values[-1])
    curve = t["transmission"].sel(harmonic=1).transpose("frequency", "sensor").values
    steady = t["steady"].transpose("frequency", "sensor")
    # what the fit leaves over the amplitude at the drive's frequency: what ``steady`` is
    # decided by, kept so that the page can say how far from steady a point is
    residual = (t["residual"] / t["amplitude"].sel(harmonic=1)).transpose("frequency",
                                                                           "sensor")
    for name, value in (("frequency", f), ("sensor", t["sensor"].values),
                        ("transmission", curve), ("steady", steady.values),
                        ("residual_fraction", residual.values),
                        ("periods", t["periods"].values),
                        ("mode_frequency", t["mode_frequency"].values),
                        ("band_bottom", t["band_bottom"].values),
                        ("band_top", t["band_top"].values)):
        r.array(f"curve/{name}", value)
    # the rule ``steady`` was decided by, for the figure's legend
    r.attrs["curve"] = {key: steady.attrs[key] for key in ("residual_fraction",
                                                           "min_periods")}
    r.setting("description", runs[0].parameters["config_resolved"].get("description", ""))
    r.setting("measure", f"least squares at the drive's frequency over whole periods at the "
                         f"end of each run (chainrun.analysis.transmission); stopped: ball "
                         f"{last}'s amplitude under {STOPPED:g} of ball {first}'s")
    # the infinite dimer chain's band edges in closed form: every contact between two
    # beads has K = (3/2) kappa^(2/3) F0^(1/3) at rest, the masses m1 > m2 alternate
    line = runs[0].line
    m1, m2 = sorted(line.mass[:2], reverse=True)
    f0 = float(runs[0].parameters["config_resolved"]["chain"]["precompression"])
    k = 1.5 * float(line.stiffness[0]) ** (2.0 / 3.0) * f0 ** (1.0 / 3.0)
    edges = np.sqrt([2 * k / m1, 2 * k / m2, 2 * k * (1 / m1 + 1 / m2)]) / (2 * np.pi)
    for name, value, what in zip(("acoustic_top", "optical_bottom", "optical_top"), edges,
                                 ("top of the acoustic band", "bottom of the optical band",
                                  "top of the optical band")):
        r.value(f"{name}_khz", value / 1e3, f"{what}, sqrt(2K/m) closed form (kHz)")
    for name, value in (("acoustic_top", t["band_top"].values[0]),
                        ("optical_bottom", t["band_bottom"].values[1]),
                        ("optical_top", t["band_top"].values[1])):
        r.value(f"spectrum_{name}_khz", value / 1e3, "the same edge from chainrun's linear "
                                                     "spectrum of the line (kHz)")
    step = float(np.min(np.diff(f)))
    r.value("step_khz", step / 1e3, "the sweep's step (kHz)")
    r.value("K", k, "linear stiffness of a contact between two beads at rest (N/m)")
    near, far = curve[:, 0], curve[:, -1]
    stopped = far < STOPPED * near
    gap = np.flatnonzero(stopped & (f > edges[0] - 2 * step) & (f < edges[1] + 2 * step))
    above = np.flatnonzero(stopped & (f > edges[1] + 2 * step))
    if gap.size == 0 or above.size == 0:
        raise ValueError("gallery-transmission: the sweep found no stop band at the gap or "
                         "above the top band")
    r.value("gap_low_khz", f[gap[0]] / 1e3, "the lowest frequency the chain stops at, about "
                                            "the gap (kHz)")
    r.value("gap_high_khz", f[gap[-1]] / 1e3, "the highest frequency the chain stops at, "
                                              "about the gap (kHz)")
    r.value("top_khz", f[above[0]] / 1e3, "the lowest frequency above the optical band the "
                                          "chain stops at (kHz)")
    inside = (f > edges[0] + step) & (f < edges[1] - step)
    acoustic = f < edges[0]
    r.value("drop", np.median(far[inside]) / np.median(far[acoustic]),
            f"median transmission to ball {last} inside the gap over that in the acoustic band")
    r.value("gap_min", far[inside].min(), f"the least transmission to ball {last} in the gap")
    r.value("acoustic_median", np.median(far[acoustic]),
            f"median transmission to ball {last} in the acoustic band")
    # the evanescent decay per cell at mid-gap: cos q = 1 - (2K(m1+m2) w^2 - m1 m2 w^4) /
    # (2 K^2) < -1 in the gap, q = pi + i mu
    w = np.pi * (edges[0] + edges[1])
    cos_q = 1.0 - (2 * k * (m1 + m2) * w**2 - m1 * m2 * w**4) / (2 * k**2)
    mu = float(np.arccosh(-cos_q))
    cells = line.n // 2
    r.value("mid_gap_mu", mu, "the infinite chain's decay per cell at mid-gap")
    r.value("mid_gap_decay", np.exp(-mu * cells), f"e^(-mu {cells}): its decay over the "
                                                  f"chain's {cells} cells")
    for s, ball in enumerate(t["sensor"].values):
        r.value(f"not_steady_{ball}", int(np.sum(~steady.values[:, s])),
                f"sweep frequencies (of {f.size}) at which ball {ball}'s response is not "
                f"steady (residual over {STEADY:g} of the amplitude, or under "
                f"{MIN_PERIODS} periods): drawn hollow")
        r.value(f"gap_min_{ball}", curve[inside, s].min(),
                f"the least transmission to ball {ball} in the gap")
    left = residual.values[:, -1] * far   # over K_w A, as the transmission is
    r.value("residual_floor", np.median(left[inside]),
            f"median over the gap of what the fit leaves at ball {last}, over K_w A: what "
            f"the start left in the line there")
    kept = steady.values
    r.value("steady_residual_max", float(residual.values[kept].max()) if kept.any() else np.nan,
            "the largest residual over the amplitude at f among the steady points")
    r.value("periods_min", int(t["periods"].values.min()), "fewest periods fitted in a run")
    r.value("periods_max", int(t["periods"].values.max()), "most periods fitted in a run")
    return r
