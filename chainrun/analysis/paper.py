"""Every number the paper prints, as printed, and where chainrun computes it.

This module owns the catalogue behind ``results/paper-comparison.csv``: one ``Printed``
entry per number of the paper (abstract to section 5d, figure captions, Table 1), with
the text exactly as printed, the analysis value it is compared with, the rule of the
comparison and, where the two disagree, the explanation. Explanations are templates:
``{artefact/value:format}`` is replaced by the computed value, so a note never goes
stale.

Rules
-----
``printed``
    Equal at the printed precision: within half a unit of the last printed digit
    ("0.841" allows 0.0005; "4%" allows 0.5 percentage points; "five" is 5 +- 0.5).
``exact``
    A fraction or count the theory gives exactly ("1/4", "7/24"): equal to 1e-9.
``between``
    Within the printed bounds ("clearly less than -1/2 and greater than -1").
``below``
    Less than the printed bound ("less than 2%").

References
----------
.. [1] E. J. Hinch and S. Saint-Jean, "The fragmentation of a line of balls by an
   impact", Proc. R. Soc. Lond. A 455, 3201-3220 (1999).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from decimal import Decimal
from fractions import Fraction

from chainrun.units import supported_format

__all__ = ["PRINTED", "Printed", "agrees", "parse", "render_note", "tolerance"]

_WORDS = {"two": 2, "three": 3, "four": 4, "five": 5, "half": 0.5}


@dataclass(frozen=True)
class Printed:
    """One number of the paper.

    Attributes
    ----------
    key : str
        Unique, e.g. ``"5a.speed"``.
    where : str
        Section, figure or table, e.g. ``"§5a"``, ``"Fig 9"``, ``"Table 1"``.
    quantity : str
        What the number is, in a few words.
    text : str
        The number exactly as printed ("0.841", "96.2%", "1/4", "five").
    source : str
        ``"artefact/value"``: the analysis value it is compared with.
    rule : str
        ``"printed"``, ``"exact"``, ``"between"`` or ``"below"``.
    transform : str
        ``""``, ``"abs"`` or ``"neg"``: applied to the value first (a coefficient
        printed with the sign of the law it belongs to, say).
    bounds : tuple of float
        For ``between`` (low, high) and ``below`` (high,).
    note : str
        How the value is computed, and why it differs when it does.
    """

    key: str
    where: str
    quantity: str
    text: str
    source: str
    rule: str = "printed"
    transform: str = ""
    bounds: tuple[float, ...] = ()
    note: str = ""


def parse(text: str) -> tuple[float, int | None]:
    """The number in a printed text and its count of decimals (None: exact fraction)."""
    t = text.strip().removeprefix("about ").removeprefix("roughly ").removesuffix("%")
    if t in _WORDS:
        value = _WORDS[t]
        return float(value), (1 if isinstance(value, float) else 0)
    if "/" in t:
        return float(Fraction(t)), None
    exponent = Decimal(t).as_tuple().exponent
    return float(t), max(0, -int(exponent))


def tolerance(text: str) -> float:
    """Half a unit of the last printed digit (0 for fractions)."""
    _, decimals = parse(text)
    return 0.0 if decimals is None else 0.5 * 10.0 ** (-decimals)


def agrees(entry: Printed, computed: float, spread: float = 0.0) -> bool:
    """Whether ``computed`` agrees with ``entry`` by its rule, within ``spread``.

    ``spread`` is how far the computed value moves when the runs' tolerance is cut
    tenfold (``chainrun.check``; NaN or 0: not measured, or none): a value agrees when
    some value within ``spread`` of it does, so that a number its runs do not pin down
    is not called a disagreement.
    """
    s = 0.0 if math.isnan(spread) else abs(spread)
    if entry.rule == "between":
        low, high = entry.bounds
        return low < computed + s and computed - s < high
    if entry.rule == "below":
        return computed - s < entry.bounds[0]
    printed, _ = parse(entry.text)
    if entry.rule == "exact":
        return abs(computed - printed) <= 1e-9 + s
    return abs(computed - printed) <= tolerance(entry.text) * (1 + 1e-9) + 1e-12 + s


_FIELD = re.compile(r"\{([a-z0-9-]+)/([A-Za-z0-9_]+)(?::([^}]*))?\}")
def render_note(note: str, values: dict[str, dict[str, float]],
                spreads: dict[str, dict[str, float]] | None = None) -> str:
    """``note`` with each ``{artefact/value:fmt}`` replaced by the computed value, with
    no digit beyond its spread (``spreads``, by artefact, where measured)."""
    spreads = spreads or {}

    def field(match: re.Match) -> str:
        artefact, key, fmt = match.group(1), match.group(2), match.group(3) or ".6g"
        spread = spreads.get(artefact, {}).get(key, math.nan)
        return supported_format(fmt, values[artefact][key], spread)

    return _FIELD.sub(field, note)


def _table1() -> list[Printed]:
    from chainrun.analysis.hertz import TABLE1_PRINTED

    notes = {
        (2, 4): "By the exact mirror symmetry v_n(K) = 1 - v_(N+1-n)(N-K) "
                "(tests/regression/test_solver.py), column K = 4 mirrors K = 1: the paper's "
                "own v_4 = 0.1270 (K = 1) gives {table1/mirror_v_2_K4:.4f}, and chainrun gives "
                "{table1/v_2_K4:.5f}. The printed 0.8729 is one unit off in the last digit.",
        (3, 4): "By the mirror symmetry, v_3(K = 4) = 1 - v_3(K = 1) = 1 + 0.01446 = "
                "{table1/v_3_K4:.5f}, which rounds to 1.014; the printed 1.015 is Table 1's "
                "own -0.0145 (itself rounded) mirrored, 1.0145, rounded a second time.",
    }
    out = []
    for i, row in enumerate(TABLE1_PRINTED):
        for j, text in enumerate(row):
            n, k = i + 1, j + 1
            out.append(Printed(f"table1.v{n}_K{k}", "Table 1", f"final velocity of ball {n}, "
                               f"K = {k}, N = 5", text, f"table1/v_{n}_K{k}",
                               note=notes.get((n, k), "")))
    return out


_N7 = ("Ball 5 of the seven drifts forward at {fig01/v_5:+.4f} (2% of V; its curve in Fig 1 "
       "is nearly level); only {fig01/rebound_count:.0f} balls have negative final "
       "velocities, and the paper counts ball 5 with the rebounding 'five' (2 + 5 = 7).")

#: The catalogue, in the order of the paper.
PRINTED: tuple[Printed, ...] = (
    # ---------------------------------------------------------------- abstract
    Printed("abstract.linear.fly_count", "abstract", "balls flying off, coefficient of N^(1/3) "
            "(linear)", "1.5", "fig07/significant_mean",
            note="Balls leaving faster than 1% of V, divided by N^(1/3), mean over N = 100, "
                 "200, 400, 800 (Fig 7)."),
    Printed("abstract.linear.fastest", "abstract", "fastest ejected, coefficient of "
            "N^(-1/6) (linear)", "1.4", "fig07/coefficient_largest_N",
            note="v_N N^(1/6) for N = 800."),
    Printed("abstract.linear.impacting", "abstract", "rebound of the impacting ball "
            "(linear)", "-0.13", "sec4/v_1"),
    Printed("abstract.linear.rebound", "abstract", "rebound coefficient of n^(-5/6) "
            "(linear)", "-0.16", "sec4/rebound_limit",
            note="Limit of v_n n^(5/6) fitted on a line of 2000 balls."),
    Printed("abstract.hertz.ejected_1", "abstract", "fastest ejected ball (Hertz)", "0.986",
            "sec5a/ejected_1"),
    Printed("abstract.hertz.ejected_2", "abstract", "second ejected ball (Hertz)", "0.149",
            "sec5a/ejected_2"),
    Printed("abstract.hertz.impacting", "abstract", "rebound of the impacting ball "
            "(Hertz)", "-0.07", "sec5a/v_1"),
    Printed("abstract.hertz.fit_a", "abstract", "rebound law coefficient a in -a e^(-b n) "
            "(Hertz)", "-0.084", "sec5a/fit_2_15_a", transform="neg",
            note="Least-squares fit of log|v_n| over balls 2-15 gives "
                 "{sec5a/fit_2_15_a:.4f} e^(-{sec5a/fit_2_15_b:.4f} n). The decay is not "
                 "exactly exponential (the local rate log(v_n/v_(n+1)) runs from "
                 "{sec5a/decay_rate_max:.3f} to {sec5a/decay_rate_min:.3f} over balls "
                 "2-15), so a and b depend on the fit: over balls 3-15 the same fit gives "
                 "{sec5a/fit_3_15_a:.4f} e^(-{sec5a/fit_3_15_b:.4f} n), the printed "
                 "0.084 and 0.55. The printed line is within "
                 "{sec5a/printed_line_error:.0%} of every |v_n|, n = 2-15 (Fig 9)."),
    Printed("abstract.hertz.fit_b", "abstract", "rebound law rate b in -a e^(-b n) (Hertz)",
            "0.55", "sec5a/fit_2_15_b",
            note="See abstract.hertz.fit_a: {sec5a/fit_2_15_b:.4f} over balls 2-15, "
                 "{sec5a/fit_3_15_b:.4f} over balls 3-15."),
    # ---------------------------------------------------------------- section 3
    Printed("3.speed", "§3, Fig 1", "propagation speed (balls per unit time)", "1",
            "sec4/rear_speed",
            note="Balls per unit time passed by the rear of the wave on a line of 2000 "
                 "(it lags n = t by xi0 t^(1/3), so this tends to 1 from below)."),
    Printed("3.fig1.rebound", "§3, Fig 1", "balls of 7 that rebound", "five",
            "fig01/rebound_count", note=_N7),
    Printed("3.fig1.fly", "§3, Fig 1", "balls of 7 that fly off", "two",
            "fig01/forward_fast",
            note="Balls leaving faster than 0.1; with the 1% threshold there are "
                 "{fig01/forward_significant:.0f}, the third being ball 5 at "
                 "{fig01/v_5:+.4f} (see 3.fig1.rebound)."),
    Printed("3.fig2.significant", "§3, Fig 2", "balls of 25 rebounding faster than 1%",
            "20", "fig02/rebound_significant", rule="exact"),
    Printed("3.fig2.slope", "§3, Fig 2", "dashed slope of the rebound velocities", "-3/4",
            "fig02/slope_fit", rule="exact",
            note="A guide, not a result: the paper itself shows in §4c (Fig 6) that "
                 "n^(-3/4) is wrong and the law is n^(-5/6). The least-squares log-log "
                 "slope over balls 5-20 of the 25 is {fig02/slope_fit:.3f}."),
    Printed("3.fig2.slope_bounds", "§3, Fig 2", "slope of the rebound velocities",
            "between -1 and -1/2", "fig02/slope_fit", rule="between", bounds=(-1.0, -0.5),
            note="Log-log slope over balls 5-20."),
    Printed("3.energy", "§3", "energy of the rebounding balls, N = 25", "4%",
            "fig02/rebound_energy_percent"),
    Printed("3.time10", "§3, Fig 3", "time ball 10 loses contact", "13.5",
            "fig03/loss_time_10"),
    Printed("3.time20", "§3, Fig 3", "time ball 20 loses contact", "24.5",
            "fig03/loss_time_20"),
    Printed("3.time30", "§3, Fig 3", "time ball 30 loses contact", "35.2",
            "fig03/loss_time_30"),
    Printed("3.time40", "§3, Fig 3", "time ball 40 loses contact", "45.7",
            "fig03/loss_time_40"),
    # ---------------------------------------------------------------- section 4
    Printed("4a.rebound_share", "§4a", "energy share of the rebounding balls, long line",
            "3.78%", "sec4/rebound_energy_percent",
            note="chainrun extrapolates the share of an infinite line: partial sums "
                 "converge like M^(-2/3) (v_n ~ n^(-5/6)), to {sec4/rebound_energy_percent:.2f}%"
                 " (a line of 2000 alone: {sec4/rebound_energy_percent_N:.2f}%). 3.78% is "
                 "a finite-line value: the balls separated by t = {sec4/time_share_378:.0f} "
                 "(ball {sec4/ball_share_378:.0f}) carry it, and a line of 80 ends with it. "
                 "The infinite-line value is the consistent one: normalizing (4.9) with "
                 "{sec4/wave_energy_percent:.2f}% gives -f(xi0)/6 = "
                 "{sec4/rebound_coefficient_own_share:.5f}, equal to the simulated limit of "
                 "v_n n^(5/6), {sec4/rebound_limit:.5f}."),
    Printed("4a.wave_share", "§4a", "energy share of the forward wave, long line", "96.2%",
            "sec4/wave_energy_percent", note="100% minus 4a.rebound_share; see there."),
    Printed("4c.fig6_limit", "§4c, Fig 6", "limit of v_n n^(5/6), N = 200", "-0.158",
            "fig06/limit_linear",
            note="Read off Fig 6 as the paper does: a straight line in 1/n through balls "
                 "100-180, extrapolated to 1/n = 0. The correction is ~ n^(-2/3), not 1/n, "
                 "so this undershoots: the fit c0 + c1 n^(-2/3) + c2/n on the same balls "
                 "gives {fig06/limit_fit:.5f}, and on 2000 balls {sec4/rebound_limit:.5f}."),
    Printed("4d.xi0", "§4d", "rear of the similarity wave xi0", "-1.85", "sec4/xi0_shooting",
            note="Exactly a1/2^(1/3) = {sec4/xi0_airy:.6f} (a1 the first zero of Ai), which "
                 "shooting from xi_inf = 3 also gives ({sec4/xi0_shooting:.6f}); the printed "
                 "-1.85 is truncated, not rounded."),
    Printed("4d.f0", "§4d, Fig 5", "f(xi0), the maximum displacement", "0.956",
            "sec4/f0_shooting",
            note="Shooting; the Airy form gives {sec4/f0_airy:.7f}. Both normalized with the "
                 "paper's 96.2%."),
    Printed("4d.peak", "§4f", "peak of -f'", "0.703", "sec4/peak_airy",
            note="Airy form; shooting gives {sec4/peak_shooting:.7f}."),
    Printed("4d.rebound", "§4d", "-f(xi0)/6", "-0.159", "sec4/rebound_coefficient"),
    Printed("4e.delta", "§4e, Fig 5", "shift delta", "1/4", "sec4/delta", rule="exact",
            transform="abs",
            note="The paper's two equations give delta = {sec4/delta:.4f}: a shift of 1/4 "
                 "to the left, as Fig 5 uses, (n - n1 - 0.25)/a^2. The shift that best "
                 "aligns the simulated waves of Fig 5 with the theory is "
                 "{fig05/best_shift_0:.3f} to {fig05/best_shift_3:.3f} (t = 13.5 to 45.7)."),
    Printed("4e.beta", "§4e", "coefficient beta", "7/24", "sec4/beta", rule="exact"),
    Printed("4f.fly_count", "§4f, Fig 7", "balls with significant velocity, coefficient of "
            "N^(1/3)", "1.5", "fig07/significant_mean",
            note="Balls leaving faster than 1% of V over N^(1/3): "
                 "{fig07/significant_N100:.2f}, {fig07/significant_N200:.2f}, "
                 "{fig07/significant_N400:.2f}, {fig07/significant_N800:.2f} for N = 100, "
                 "200, 400, 800."),
    Printed("4f.fastest", "§4f, Fig 7", "fastest ejected, coefficient of N^(-1/6)", "1.397",
            "fig07/coefficient_largest_N",
            note="v_N N^(1/6) for N = 800. It still grows with N: extrapolated in N^(-2/3) "
                 "through the four lines it is {fig07/coefficient_limit:.4f}, close to twice "
                 "the peak of -f', {sec4/peak_airy:.4f} x 2, as the paper argues."),
    # ---------------------------------------------------------------- section 5a
    Printed("5a.speed", "§5a", "speed of the solitary wave", "0.841", "sec5a/speed"),
    Printed("5a.dimensional_speed", "§5a", "dimensional speed coefficient", "0.702",
            "sec5a/dimensional_speed", note="The simulated speed times (4/pi^2)^(1/5)."),
    Printed("5a.saturation_time", "§5a", "end of the adjustment period", "15",
            "sec5a/saturation_time",
            note="Separation time of the first ball after which every ball's displacement "
                 "at separation is within 0.1% of the saturated value."),
    Printed("5a.displacement", "§5a", "saturated displacement", "1.354",
            "sec5a/displacement"),
    Printed("fig8.displacement", "Fig 8", "saturated displacement", "1.354",
            "fig08/displacement"),
    Printed("5a.width", "§5a", "active balls in the wave", "about four", "sec5a/width",
            note="Mean number of balls of the wave faster than 1% of its peak velocity."),
    Printed("5a.max_velocity", "§5a", "peak velocity of a ball", "0.682",
            "sec5a/max_velocity"),
    Printed("5a.max_force", "§5a", "peak contact force", "0.640", "sec5a/max_force"),
    Printed("5a.momentum", "§5a", "momentum of the solitary wave", "1.138", "sec5a/momentum"),
    Printed("5a.energy", "§5a", "energy of the solitary wave", "0.497", "sec5a/energy"),
    Printed("5a.kinetic", "§5a", "mean kinetic energy of the wave", "0.276",
            "sec5a/kinetic_mean"),
    Printed("5a.potential", "§5a", "mean potential energy of the wave", "0.221",
            "sec5a/potential_mean"),
    Printed("5a.kinetic_min", "§5a", "smallest kinetic energy of the wave", "0.272",
            "sec5a/kinetic_min",
            note="The kinetic energy oscillates smoothly and symmetrically between "
                 "{sec5a/kinetic_min:.4f} and {sec5a/kinetic_max:.4f}: the printed mean "
                 "0.276 is the midpoint of these ({sec5a/kinetic_midrange:.4f}), not of the "
                 "printed 0.272-0.282 (0.277). Sampling at 0.1 resolves the minimum (its "
                 "curvature is small), so 0.272 is most likely a misprint of 0.270."),
    Printed("5a.kinetic_max", "§5a", "largest kinetic energy of the wave", "0.282",
            "sec5a/kinetic_max"),
    Printed("5a.rebound_significant", "§5a, Fig 9", "balls rebounding faster than 1%",
            "three", "fig09/rebound_significant"),
    Printed("5a.v1", "§5a, Fig 9", "rebound of the impacting ball", "-0.0711", "fig09/v_1"),
    Printed("5a.v2", "§5a, Fig 9", "rebound of ball 2", "-0.0303", "fig09/v_2"),
    Printed("5a.v3", "§5a, Fig 9", "rebound of ball 3", "-0.0158", "fig09/v_3"),
    Printed("5a.fit_a", "§5a, Fig 9", "rebound law coefficient a in -a e^(-b n)", "-0.084",
            "fig09/fit_2_15_a", transform="neg",
            note="See abstract.hertz.fit_a: over the stated balls 2-15 the fit is "
                 "{fig09/fit_2_15_a:.4f} e^(-{fig09/fit_2_15_b:.4f} n); over 3-15, "
                 "{fig09/fit_3_15_a:.4f} e^(-{fig09/fit_3_15_b:.4f} n)."),
    Printed("5a.fit_b", "§5a, Fig 9", "rebound law rate b", "0.55", "fig09/fit_2_15_b",
            note="See abstract.hertz.fit_a."),
    Printed("5a.rebound_energy", "§5a", "energy of the rebounding balls", "0.63%",
            "fig09/rebound_energy_percent"),
    Printed("5a.rebound_momentum", "§5a", "momentum of the rebounding balls", "-0.138",
            "fig09/rebound_momentum"),
    Printed("5a.ejected_1", "§5a", "fastest ejected ball", "0.986", "fig09/ejected_1"),
    Printed("5a.ejected_2", "§5a", "second ejected ball", "0.146", "fig09/ejected_2",
            note="A misprint for 0.149 (as the abstract prints it): the second ball leaves at "
                 "{fig09/ejected_2:.5f} on every line of 20 balls or more. The paper's own "
                 "§5c uses 0.1486: 1.252 x 0.1486 = 0.186 and 0.655 x 0.1486 = 0.097, as "
                 "printed (0.146 would give 0.183 and 0.096). Lines of 9 or 10 balls give "
                 "{sec5a/ejected_2_N9:.4f} and {sec5a/ejected_2_N10:.4f}."),
    Printed("5a.ejected_3", "§5a", "third ejected ball", "about 0.003", "fig09/ejected_3",
            note="Depends on the line length until about 15 balls: "
                 "{sec5a/ejected_3_N9:.4f} for N = 9, {sec5a/ejected_3_N10:.4f} for N = 10, "
                 "{fig09/ejected_3:.5f} for N >= 20. 'About 0.003' matches a line of 10-11 "
                 "balls."),
    Printed("5a.line_length", "§5a", "shortest line that attains these values",
            "10", "sec5a/shortest_line_1",
            note="To three decimals the fastest ejected ball (0.986) is reached from N = "
                 "{sec5a/shortest_line_1:.0f}, the second (0.149) from N = "
                 "{sec5a/shortest_line_2:.0f}, the third (0.004) from N = "
                 "{sec5a/shortest_line_3:.0f}; a line of 10 gives "
                 "{sec5a/ejected_1_N10:.4f}, {sec5a/ejected_2_N10:.4f}, "
                 "{sec5a/ejected_3_N10:.4f}. 'At least 10' is a fair summary of the "
                 "leading value and of the paper's 0.003."),
    Printed("5a.five_v1", "§5a", "line of five: ball 1", "-0.071", "sec5a/five_v_1"),
    Printed("5a.five_v2", "§5a", "line of five: ball 2", "-0.030", "sec5a/five_v_2"),
    Printed("5a.five_v3", "§5a", "line of five: ball 3", "-0.015", "sec5a/five_v_3",
            note="The value is {sec5a/five_v_3:.5f}: Table 1's -0.0145 rounded a second "
                 "time."),
    Printed("5a.five_v4", "§5a", "line of five: ball 4", "0.127", "sec5a/five_v_4"),
    Printed("5a.five_v5", "§5a", "line of five: ball 5", "0.989", "sec5a/five_v_5"),
    # ---------------------------------------------------------------- section 5b
    Printed("5b.amplitude", "§5b", "Nesterenko amplitude A", "0.727", "sec5b/amplitude",
            note="From the simulated displacement {sec5a/displacement:.5f}."),
    Printed("5b.c2", "§5b", "c^2 / A^(1/2)", "4/5", "sec5b/c_squared_over_sqrt_a",
            rule="exact"),
    Printed("5b.speed", "§5b", "Nesterenko speed c", "0.826", "sec5b/speed"),
    Printed("5b.max_velocity", "§5b", "Nesterenko peak velocity A c", "0.600",
            "sec5b/max_velocity"),
    Printed("5b.max_velocity_lower", "§5b", "how much lower than simulated, %", "12%",
            "sec5b/max_velocity_lower_percent"),
    Printed("5b.max_force", "§5b", "Nesterenko peak force (9/10) A^(3/2)", "0.558",
            "sec5b/max_force"),
    Printed("5b.max_force_lower", "§5b", "how much lower than simulated, %", "13%",
            "sec5b/max_force_lower_percent"),
    Printed("5b.momentum", "§5b", "Nesterenko momentum", "1.118", "sec5b/momentum",
            note="{sec5b/momentum:.5f} lies just past the rounding boundary 1.1185. The "
                 "momentum is D c (D the displacement), and from the printed D = 1.354 and "
                 "c = 0.826 it is 1.1184, the printed 1.118."),
    Printed("5b.kinetic", "§5b", "Nesterenko kinetic energy", "0.245", "sec5b/kinetic"),
    Printed("5b.potential", "§5b", "Nesterenko potential energy", "0.196", "sec5b/potential"),
    Printed("5b.kinetic_lower", "§5b", "how much lower than simulated, %", "11%",
            "sec5b/kinetic_lower_percent"),
    Printed("5b.potential_lower", "§5b", "how much lower than simulated, %", "11%",
            "sec5b/potential_lower_percent"),
    Printed("5b.force_factor", "§5b", "peak of (3/5)(sin^6 + sin^4/2)", "0.9",
            "sec5b/force_peak_factor"),
    Printed("5b.speed_change", "§5b", "change of the predicted speed by (5.1), %",
            "less than 2%", "sec5b/speed_change_percent", rule="below", bounds=(2.0,)),
    # ---------------------------------------------------------------- section 5c, K = 2
    Printed("5c.K2.displacement_1", "§5c, Fig 10", "K = 2: displacement of the faster wave",
            "1.621", "fig10/displacement_1"),
    Printed("5c.K2.speed_1", "§5c, Fig 10", "K = 2: speed of the faster wave", "0.880",
            "fig10/speed_1",
            note="Measured {fig10/speed_1:.5f}; the scaling c_1 V^(1/5) with chainrun's "
                 "c_1 = {sec5a/speed:.5f} gives {fig10/speed_scaled_1:.5f}. The printed "
                 "0.880 is 0.841 x 1.252^(1/5) = 0.8797 from the rounded 0.841."),
    Printed("5c.K2.displacement_2", "§5c, Fig 10", "K = 2: additional displacement of the "
            "slower wave", "0.965", "fig10/displacement_2"),
    Printed("5c.K2.speed_2", "§5c, Fig 10", "K = 2: speed of the slower wave", "0.773",
            "fig10/speed_2",
            note="Measured {fig10/speed_2:.5f}, scaling {fig10/speed_scaled_2:.5f}; the "
                 "printed value is 0.841 x 0.655^(1/5) = 0.7728 from the rounded 0.841."),
    Printed("5c.K2.equivalent_1", "§5c", "K = 2: equivalent impact of the faster wave",
            "1.252", "fig10/equivalent_1"),
    Printed("5c.K2.equivalent_2", "§5c", "K = 2: equivalent impact of the slower wave",
            "0.655", "fig10/equivalent_2"),
    Printed("5c.K2.lead_1", "§5c", "K = 2: first ball from the faster wave", "1.234",
            "fig10/lead_1"),
    Printed("5c.K2.second_1", "§5c", "K = 2: second ball from the faster wave", "0.186",
            "fig10/second_1"),
    Printed("5c.K2.lead_2", "§5c", "K = 2: first ball from the slower wave", "0.647",
            "fig10/lead_2"),
    Printed("5c.K2.second_2", "§5c", "K = 2: second ball from the slower wave", "0.089",
            "fig10/second_2"),
    Printed("5c.K2.pseudo_lead_1", "§5c", "K = 2: single impact at 1.252, first ball",
            "1.234", "fig10/pseudo_lead_1"),
    Printed("5c.K2.pseudo_second_1", "§5c", "K = 2: single impact at 1.252, second ball",
            "0.186", "fig10/pseudo_second_1"),
    Printed("5c.K2.pseudo_lead_2", "§5c", "K = 2: single impact at 0.655, first ball",
            "0.646", "fig10/pseudo_lead_2"),
    Printed("5c.K2.pseudo_second_2", "§5c", "K = 2: single impact at 0.655, second ball",
            "0.097", "fig10/pseudo_second_2"),
    # ---------------------------------------------------------------- section 5c, K = 3
    Printed("5c.K3.displacement_1", "§5c, Fig 11", "K = 3: displacement of wave 1", "1.727",
            "fig11/displacement_1"),
    Printed("5c.K3.displacement_2", "§5c, Fig 11", "K = 3: additional displacement of "
            "wave 2", "1.316", "fig11/displacement_2"),
    Printed("5c.K3.displacement_3", "§5c, Fig 11", "K = 3: additional displacement of "
            "wave 3", "0.745", "fig11/displacement_3"),
    Printed("5c.K3.equivalent_1", "§5c", "K = 3: equivalent impact of wave 1", "1.355",
            "fig11/equivalent_1"),
    Printed("5c.K3.equivalent_2", "§5c", "K = 3: equivalent impact of wave 2", "0.965",
            "fig11/equivalent_2"),
    Printed("5c.K3.equivalent_3", "§5c", "K = 3: equivalent impact of wave 3", "0.474",
            "fig11/equivalent_3"),
    Printed("5c.K3.speed_1", "§5c, Fig 11", "K = 3: speed of wave 1", "0.894",
            "fig11/speed_1",
            note="Measured {fig11/speed_1:.5f}, scaling {fig11/speed_scaled_1:.5f}; the "
                 "printed value is 0.841 x 1.355^(1/5) = 0.8937 from the rounded 0.841."),
    Printed("5c.K3.speed_2", "§5c, Fig 11", "K = 3: speed of wave 2", "0.835",
            "fig11/speed_2"),
    Printed("5c.K3.speed_3", "§5c, Fig 11", "K = 3: speed of wave 3", "0.724",
            "fig11/speed_3"),
    Printed("5c.K3.lead_1", "§5c", "K = 3: first ball from wave 1", "1.336", "fig11/lead_1"),
    Printed("5c.K3.second_1", "§5c", "K = 3: second ball from wave 1", "0.201",
            "fig11/second_1"),
    Printed("5c.K3.lead_2", "§5c", "K = 3: first ball from wave 2", "0.953", "fig11/lead_2"),
    Printed("5c.K3.second_2", "§5c", "K = 3: second ball from wave 2", "0.132",
            "fig11/second_2"),
    Printed("5c.K3.lead_3", "§5c", "K = 3: first ball from wave 3", "0.468", "fig11/lead_3"),
    Printed("5c.K3.second_3", "§5c", "K = 3: second ball from wave 3", "0.056",
            "fig11/second_3"),
    Printed("5c.K3.pseudo_lead_1", "§5c", "K = 3: single impact at 1.355, first ball",
            "1.336", "fig11/pseudo_lead_1"),
    Printed("5c.K3.pseudo_second_1", "§5c", "K = 3: single impact at 1.355, second ball",
            "0.199", "fig11/pseudo_second_1",
            note="V x {sec5a/ejected_2:.4f} = {fig11/pseudo_second_1:.4f}. The printed 0.199 "
                 "and 0.142 (wave 2) are 1.355 x 0.147 and 0.965 x 0.147: 0.147 is the second "
                 "ejected velocity of a line of 10 balls ({sec5a/ejected_2_N10:.4f}), not of "
                 "a long line ({sec5a/ejected_2:.4f}, which the paper's K = 2 values 0.186 "
                 "and 0.097 use)."),
    Printed("5c.K3.pseudo_lead_2", "§5c", "K = 3: single impact at 0.965, first ball",
            "0.951", "fig11/pseudo_lead_2"),
    Printed("5c.K3.pseudo_second_2", "§5c", "K = 3: single impact at 0.965, second ball",
            "0.142", "fig11/pseudo_second_2", note="See 5c.K3.pseudo_second_1."),
    Printed("5c.K3.pseudo_lead_3", "§5c", "K = 3: single impact at 0.474, first ball",
            "0.467", "fig11/pseudo_lead_3"),
    Printed("5c.K3.pseudo_second_3", "§5c", "K = 3: single impact at 0.474, second ball",
            "0.070", "fig11/pseudo_second_3"),
    Printed("5c.K4.displacement_1", "§5c", "K = 4: displacement of the fastest wave",
            "1.775", "sec5c/displacement_1",
            note="Measured as the plateau behind the fastest wave on balls 60-170 of a line of "
                 "200, where it is constant to 1e-5: {sec5c/displacement_1:.5f}. Closer to the "
                 "struck end, before the second wave has separated, the plateau is higher, "
                 "never lower, and inferring it from the fastest ejected ball "
                 "({sec5c/lead_1:.4f}) by the scaling gives the same "
                 "{sec5c/displacement_from_lead:.5f}. With the paper's rounded constants, "
                 "1.354 x (1.383/0.986)^(4/5) = {sec5c/displacement_from_lead_rounded:.4f}, "
                 "the printed 1.775: the likely origin of the 0.001 difference, not verified."),
    Printed("5c.K4.waves", "§5c", "solitary waves for four impacting balls", "four",
            "sec5c/waves"),
    Printed("5c.fig12.decades", "§5c, Fig 12", "decades of decay along the second balls",
            "1", "fig12/decades_mean",
            note="log10 of v_(N-K)/v_(N-2K+1), mean over K = 3, 6, 9, 12: "
                 "{fig12/decades_K3:.2f}, {fig12/decades_K6:.2f}, {fig12/decades_K9:.2f}, "
                 "{fig12/decades_K12:.2f}."),
    Printed("5c.fig13.half", "§5c, Fig 13", "rebounding balls per impacting ball",
            "roughly half", "fig13/significant_ratio_median",
            note="Balls rebounding faster than 1% of V, over K; median over K = 10..80 "
                 "(it falls from {fig13/significant_ratio_K10:.2f} at K = 10 to "
                 "{fig13/significant_ratio_K80:.2f} at K = 80)."),
    # ---------------------------------------------------------------- Table 1 and 5d
    *_table1(),
    Printed("5d.second_from_end", "§5d", "line of five: ball 4", "0.13", "table1/v_4_K1"),
)
