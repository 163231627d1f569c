"""How a sweep's results read: one line per run, and the table of final velocities.

The runner reports typed results (``chainrun.runner.RunSummary``, ``RunError``); this
module puts them into words for ``chainrun simulate`` (and ``chainrun info``).
"""

from __future__ import annotations

import math

import numpy as np


def count(n: int, plural: str) -> str:
    """``n`` things, in the singular for one: ``1 event``, ``4 events``, ``1 unloading
    (a damped force at 0)`` (the first word of ``plural`` loses its s)."""
    if n == 1:
        first, _, rest = plural.partition(" ")
        plural = first.removesuffix("s") + (f" {rest}" if rest else "")
    return f"{n} {plural}"


def rounding_text(run) -> str:
    """`` (within its rounding, 2.5e-01)`` after |dE|/E where the rounding of the
    balance's terms can leave more than a millionth (``Diagnostics.energy_floor``: a
    precompressed line shaken by far less than its static compressions)."""
    from chainrun.check import ENERGY_DOUBT

    floor = getattr(run, "energy_floor", 0.0)
    if not (floor > ENERGY_DOUBT and run.energy_error <= floor):
        return ""
    return f" (within its rounding, {floor:.1e})"


def momentum_text(error: float, units: str = "paper", scale: float = 1.0) -> str:
    """|dP| for a summary, in the run's units: ``error`` is relative to the momentum
    of the line's scales (``Diagnostics.momentum_error``), ``scale`` that momentum
    (M V; 1 in paper units); n/a in files that did not check it (older ones, with a
    wall)."""
    if not math.isfinite(error):
        return "|dP| n/a"
    if units == "si":
        return f"|dP| = {error * scale:.1e} N s"
    return f"|dP| = {error:.1e}"


def run_line(run) -> str:
    """One line for a run (``RunSummary``): how it ended, its cost and its conservation
    errors (and, for a checked run, how many balls hold to ``chainrun.check.HOLD``); for
    a run that failed to run (``RunError``), its error."""
    from chainrun.runner import RunError
    from chainrun.units import format_value

    if isinstance(run, RunError):  # no file
        return f"{run.run_id}: error: {run.message}"
    end = format_value(run.end_time, "time", run.units, 6)
    if run.terminal:
        # a computed time, to six digits in every run's line (752.780 µs beside 1.37048 ms)
        computed = format_value(run.end_time, "time", run.units, 6, zeros=run.units == "si")
        how = f"terminal at t = {computed}"
    elif run.outcome == "stop_time":
        how = f"stopped at t_end = {end}"
    else:
        how = run.message
    text = (f"{how}, {count(run.events, 'events')}, {count(run.steps, 'steps')}, "
            f"{momentum_text(run.momentum_error, run.units, run.momentum_scale)}, "
            f"|dE|/E = {run.energy_error:.1e}"
            + rounding_text(run) + ", "
            + (f"dissipated {run.dissipated:.1%} of the "
               f"{'energy taken up' if run.driven else 'impact energy'}, "
               if run.dissipated else "")
            + f"{run.wall_time:.2f} s"
            + (f"; {run.check.line(run.speed, run.speed_name)}" if run.check is not None else ""))
    if run.skipped:
        return f"{run.run_id}: skipped, file up to date ({text})"
    return f"{run.run_id}: {text}"


def velocity_table(summaries: list, max_balls: int = 20) -> str | None:
    """The velocities where the runs (``RunSummary``) ended as a text table (balls
    down, runs across), under a heading with their unit, for short lines: final
    velocities where every run reached its terminal state. Four decimals of the
    table's unit, more for a value below 0.01 of it (three significant digits); a
    checked run's to six significant digits, none beyond its spread
    (``chainrun.units.supported_format``: a velocity of 0.0133 m/s that holds to
    1e-14 is 0.0133125, not 0.0133)."""
    from chainrun.units import scale_for, supported_format

    if (not summaries or any(s.n != summaries[0].n for s in summaries)
            or len({s.units for s in summaries}) > 1):
        return None
    n = summaries[0].n
    if n > max_balls:
        return None
    scaled = scale_for("velocity", summaries[0].units,
                       np.concatenate([s.final_velocity for s in summaries]))
    what = ("final velocities" if all(s.terminal for s in summaries)
            else "velocities where the runs stopped" if len(summaries) > 1
            else "velocities where the run stopped")

    def cell(s, i: int) -> str:
        spread = s.check.final_velocity_spread[i] if s.check is not None else np.nan
        v = float(scaled(s.final_velocity[i]))
        # four decimals, and more for a small value: at least three significant
        # digits, six where a check measured how many hold
        significant = 6 if s.check is not None else 3
        lead = math.floor(math.log10(abs(v))) if v != 0.0 and math.isfinite(v) else 0
        decimals = max(4, min(12, significant - 1 - lead)) if s.check is not None else (
            min(12, 2 - lead) if v != 0.0 and math.isfinite(v) and abs(v) < 0.01 else 4)
        return supported_format(f".{decimals}f", v, float(scaled(spread)))

    head = ["n"] + [s.run_id for s in summaries]
    rows = [[str(i + 1)] + [cell(s, i) for s in summaries] for i in range(n)]
    widths = [max(len(r[c]) for r in [head] + rows) for c in range(len(head))]
    fmt = lambda r: "  ".join(v.rjust(w) for v, w in zip(r, widths))
    return "\n".join([f"{what} ({scaled.unit})", fmt(head)] + [fmt(r) for r in rows])
