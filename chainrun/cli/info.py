"""``chainrun info``: what a run file holds, read in ten seconds, in the run's units."""

from __future__ import annotations

import math
from pathlib import Path

import click
import numpy as np

from chainrun.cli.common import fail
from chainrun.cli.text import count
from chainrun.errors import ChainrunError

_EVENT_NAMES = {"OPEN": "openings", "CLOSE": "closings", "RELEASE": "releases",
                "ENGAGE": "engagements", "UNLOAD": "unloadings (a damped force at 0)",
                "RELOAD": "reloadings"}
#: A run's outcome in a folder's table, where its value is not a word already.
_OUTCOME_NAMES = {"stop_time": "at t_end"}
_SHARE_NAMES = {"rebound": "rebound", "ejected": "ejected", "left behind": "left behind",
                "contacts": "in contacts and walls", "forces": "against the forces",
                "dissipated": "dissipated"}


def _events(counts: dict[str, int]) -> str:
    total = sum(counts.values())
    parts = [count(counts[key], name) for key, name in _EVENT_NAMES.items() if counts.get(key)]
    return count(total, "events") + (f" ({', '.join(parts)})" if parts else "")


def _velocity(ball: int, v: float, s, scaled) -> str:
    """Ball ``ball``'s velocity ``v`` at the end of run ``s``, times ``scaled``'s
    factor: six significant digits, trailing zeros kept, and none its check's spread
    does not support (the digits the velocity table shows)."""
    from chainrun.units import format_digits

    spread = (float(s.check.final_velocity_spread[ball - 1]) if s.check is not None
              else math.nan)
    return format_digits(float(scaled(v)), float(scaled(spread)), 6)


def _ball(which: str, pick, s) -> str:
    """A ball's final velocity, to the digits that hold (``_velocity``)."""
    from chainrun.units import scale_for

    if pick is None:
        return f"no ball moves {which}"
    ball, v = pick
    scaled = scale_for("velocity", s.units, [v])
    return (f"ball {ball} at {_velocity(ball, v, s, scaled)}"
            + (f" {scaled.unit}" if scaled.unit else ""))


def _shares(s) -> str:
    """The energy line: the shares of the impact energy where the run ended; at its
    terminal state by the balls' fate, else (stopped mid-way) kinetic as one."""
    from chainrun.units import format_value

    if not math.isfinite(s.energy["rebound"]):
        if s.drive_work:
            return ("no energy taken up to share (the impact energy and the drives' work "
                    f"add up to {format_value(s.impact + s.drive_work, 'energy', s.units)})")
        return "no impact energy to share (the line starts at rest)"
    energy = dict(s.energy)
    if not s.terminal:
        energy = {"kinetic": energy.pop("rebound") + energy.pop("ejected")
                  + energy.pop("left behind"), **energy}
    names = {**_SHARE_NAMES, "kinetic": "kinetic"}
    if not s.walls:
        names["contacts"] = "in contacts"
    shares = ", ".join(f"{names[name]} {share:.2%}" for name, share in energy.items()
                       if name != "dissipated" or share)
    when = "" if s.terminal else f" at t = {format_value(s.end_time, 'time', s.units, 6)}"
    if s.drive_work:
        load = (f" (beyond the static load's {format_value(s.static_load, 'energy', s.units)}"
                f", which the walls' return gives back)" if s.static_load else "")
        return (f"of the energy taken up{when}, the impact's "
                f"{format_value(s.impact, 'energy', s.units)} and the drives' work "
                f"{format_value(s.drive_work, 'energy', s.units)}{load}: {shares}")
    return f"of the impact energy {format_value(s.impact, 'energy', s.units)}{when}: {shares}"


def _balls(s, threshold: str) -> list[str]:
    """The balls' lines: the largest velocities and, at the terminal state, how many
    balls rebound, are ejected or are left behind (a run stopped before it has no
    final velocities to sort them by)."""
    from chainrun.units import format_value

    moving = (f"largest forward velocity: {_ball('forward', s.forward, s)}; "
              f"largest backward velocity: {_ball('backward', s.backward, s)}")
    if not s.terminal:
        return [f"balls     at t = {format_value(s.end_time, 'time', s.units, 6)}, before "
                f"the terminal state: {moving}"]
    return [f"balls     {moving}",
            f"          {s.rebounding} rebound and {s.ejected} ejected (backward and "
            f"forward faster than 1% of the impact speed, {threshold}), "
            f"{s.left_behind} left behind"]


def _pulse_lines(p, static: str | None = None) -> list[str]:
    """The pulses section: a line per sensor (``chainrun.analysis.pulse.Pulses``), and
    the wave's speed when two sensors or more saw it; a loaded line's peaks said to
    hold its ``static`` load (``1 N`` of a precompression, a column's weight)."""
    from chainrun.units import format_measured, format_value, format_with_error, scale_for

    # measured values keep their trailing zeros (31.700 N beside 33.317 N)
    def t(x):
        return format_value(float(x), "time", p.units, 5, zeros=True)

    # a crossing interpolated between samples: to the digits its sampling supports
    def crossing(x, error):
        return format_measured(float(x), float(error), "time", p.units)

    width_error = p.width_error if p.width_error is not None else np.full(p.balls.size, np.nan)
    arrival_error = (p.arrival_error if p.arrival_error is not None
                     else np.full(p.balls.size, np.nan))

    def f(x):
        return format_value(float(x), "force", p.units, 5, zeros=True)

    lines = []
    for i, ball in enumerate(p.balls):
        if not np.isfinite(p.peak_force[i]):
            lines.append(f"ball {ball}: no whole pulse recorded")
            continue
        held = f" (the static {static} included)" if static else ""
        wall = p.on_wall is not None and bool(p.on_wall[i])
        what = ("peak force on the wall (where the wave reflects)"
                if wall else "peak contact force")
        lines.append(f"ball {ball}: {what} {f(p.peak_force[i])}{held} at "
                     f"{t(p.peak_time[i])}, width (FWHM) "
                     f"{crossing(p.width[i], width_error[i])}, arrival "
                     f"{crossing(p.arrival_time[i], arrival_error[i])}; peak of the mean "
                     f"force {f(p.peak_mean_force[i])}")
    fits = [(p.speed_si if p.speed_si is not None else p.speed, "towards ball N"),
            (p.backward_speed_si if p.backward_speed_si is not None else p.backward_speed,
             "towards ball 1")]
    seen = [(speed, way) for speed, way in fits
            if speed.points >= 2 and np.isfinite(speed.value)]
    for speed, way in seen:
        # two waves: each one's way is said in words; one wave: its sign says it
        v = abs(speed.value) if p.backward_speed.points else speed.value
        if p.speed_si is not None:
            scaled = scale_for("velocity", "si", [v])
            value, error = format_with_error(scaled(v), scaled(speed.error))
            value, error = f"{value} {scaled.unit}", (f" +- {error} {scaled.unit}"
                                                      if error else "")
        else:  # (a line without diameters: its speed in balls per unit of its time)
            per = "balls/s" if p.units == "si" else "balls per unit time"
            value, error = format_with_error(v, speed.error)
            value, error = f"{value} {per}", (f" +- {error}" if error else "")
        lines.append("wave speed " + (f"{way} " if p.backward_speed.points else "")
                     + f"{value}{error} (a fit through {speed.points} sensors' peak times"
                     + ("; no uncertainty from two" if speed.points == 2 else "") + ")")
    return [("pulses    " if i == 0 else "          ") + line for i, line in enumerate(lines)]


def _check(s) -> str:
    """The conditioning check: how many balls hold, and the largest spread."""
    from chainrun.check import HOLD, short
    from chainrun.units import format_value

    c = s.check
    if c is None:
        return "not run (chainrun simulate --check measures which digits hold)"
    head = f"at rtol {short(c.rtol)} ({c.wall_time:.2f} s)"
    if not c.ok:
        return f"{head} FAILED ({c.outcome}): {c.message}"
    speed, name = s.reference
    n = c.final_velocity_spread.size
    hold = (f" ({format_value(HOLD * speed, 'velocity', s.units, 3)})"
            if s.units == "si" else "")
    ball, largest = c.largest()
    if not math.isfinite(largest):
        worst = f"ball {ball} separates in only one of the two runs"
    else:
        worst = (f"the largest spread is {format_value(largest, 'velocity', s.units, 3)}"
                 + (f" ({largest / speed:.1e} of it)" if s.units == "si" else "")
                 + f", ball {ball}")
    return (f"{head}: {c.holding(speed)} of {n} balls hold to {short(HOLD)} of {name}"
            f"{hold}; {worst}")


def render(s, sensors=()) -> str:
    """The summary (``chainrun.analysis.summary.RunSummary``) as lines of text, in the
    run's units; ``sensors``, lines of what its force sensors recorded (``_sensors``),
    add a section."""
    from chainrun.analysis.summary import law_name
    from chainrun.limits import human_size
    from chainrun.cli.text import momentum_text, rounding_text
    from chainrun.units import format_value

    def t(x):
        return format_value(x, "time", s.units, 6)

    if s.terminal:
        end = format_value(s.end_time, "time", s.units, 6, zeros=s.units == "si")
        outcome = f"terminal state at t = {end}: no collision can happen again"
    elif s.outcome == "stop_time":
        outcome = f"stopped at t_end = {t(s.end_time)} (not the terminal state)"
    else:
        outcome = f"FAILED ({s.outcome}): {s.message}"
    speed = format_value(s.speed, "velocity", s.units)
    striking = (f"the first K = {s.k} striking at "
                + (speed if s.units == "si" else f"velocity {speed}") if s.k else "none striking")
    units = "SI units" if s.units == "si" else "paper units"
    stored = (f"{s.snapshots} snapshots of positions and velocities, t = "
              f"{t(s.first_time)} ... {t(s.last_time)}" if s.snapshots else "no snapshots")
    threshold = format_value(0.01 * (s.speed or 1.0), "velocity", s.units)
    damping = []
    if s.dissipating >= 0:
        where = f"at contact {s.dissipating}" if s.dissipating else "at a wall"
        damping = [f"damping   dissipated {format_value(s.dissipated, 'energy', s.units)}, "
                   f"most {where}"]
    lines = [
        f"{s.path}  ({human_size(s.file_bytes)}, chainrun {s.creator_version}, {s.created})",
        f"model     N = {s.n} balls, {striking}; "
        + (f"{law_name(s.alpha)} contacts" + (f" (alpha = {s.alpha:g})"
                                              if math.isfinite(s.alpha) else "")
           if s.n > 1 else "no contacts between balls") + f"; {units}",
        *([f"line      {s.line}"] if s.line else []),
        f"outcome   {outcome}",
        f"cost      {_events(s.events)}, {s.steps} steps ({s.rejected_steps} rejected), "
        f"at most {min(s.max_window, s.n)} balls integrated at once, {s.wall_time:.2f} s",
        *([f"          {s.closed_form} isolated collisions taken whole"]
          if s.closed_form else []),
        f"accuracy  {momentum_text(s.momentum_error, s.units, s.momentum_scale)}, "
        f"|dE|/E = {s.energy_error:.1e} "
        f"({rounding_text(s)[2:-1] + '; ' if rounding_text(s) else ''}projection corrected "
        f"{s.energy_correction:.1e} of E); rtol {s.rtol:g}",
        f"check     {_check(s)}",
        *_balls(s, threshold),
        f"energy    {_shares(s)}",
        *damping,
        *sensors,
        f"stored    {stored}; the event log; final and separation velocities"
        + (f"; forces on {s.sensors} sensor ball{'s' * (s.sensors != 1)} at {s.samples} "
           f"sample{'s' * bool(s.samples != 1)}" if s.sensors else ""),
    ]
    return "\n".join(lines)


#: The numbers of a run that an ensemble averages: (label, quantity, value of a summary)
_ENSEMBLE = (
    ("end time", "time", lambda s: s.end_time),
    ("events", None, lambda s: sum(s.events.values())),
    ("rebound (balls)", None, lambda s: s.rebounding),
    ("ejected (balls)", None, lambda s: s.ejected),
    ("left behind (balls)", None, lambda s: s.left_behind),
    ("largest forward velocity", "velocity", lambda s: s.forward[1] if s.forward else 0.0),
    ("largest backward velocity", "velocity",
     lambda s: s.backward[1] if s.backward else 0.0),
    *((f"energy {_SHARE_NAMES[name]} (%)", None,
       (lambda name: lambda s: 100.0 * s.energy.get(name, math.nan))(name))
      for name in ("rebound", "ejected", "left behind", "contacts", "forces", "dissipated")),
)


def _ensemble_rows(when: str) -> tuple:
    """``_ENSEMBLE`` for runs that stopped before their terminal state, ``when`` (``"at
    t = 1.5 ms"``): the balls counted by their velocities there, not by their fate, and
    the kinetic energy there as one share (as a run's own summary gives it)."""
    return (
        *_ENSEMBLE[:2],
        (f"rebounding {when} (balls)", None, lambda s: s.rebounding),
        (f"moving forward {when} (balls)", None, lambda s: s.ejected),
        (f"nearly still {when} (balls)", None, lambda s: s.left_behind),
        (f"largest forward velocity {when}", "velocity",
         lambda s: s.forward[1] if s.forward else 0.0),
        (f"largest backward velocity {when}", "velocity",
         lambda s: s.backward[1] if s.backward else 0.0),
        (f"energy kinetic {when} (%)", None,
         lambda s: 100.0 * (s.energy["rebound"] + s.energy["ejected"]
                            + s.energy["left behind"])),
        (f"energy in contacts and walls {when} (%)", None,
         lambda s: 100.0 * s.energy["contacts"]),
        (f"energy against the forces {when} (%)", None,
         lambda s: 100.0 * s.energy.get("forces", math.nan)),
        (f"energy dissipated {when} (%)", None, lambda s: 100.0 * s.energy["dissipated"]),
    )


def _holding(s) -> str:
    """``"50/60"``: balls that hold to the check's level, of the run's; "-" without a
    check, "failed" for a failed one."""
    if s.check is None:
        return "-"
    if not s.check.ok:
        return "failed"
    return f"{s.check.holding(s.speed or 1.0)}/{s.n}"


def _ensemble_pulses(pulses) -> list[tuple[str, str | None, np.ndarray]]:
    """The pulse numbers an ensemble averages, each run's (``measure_pulses``): the
    wave's speed, and the peak force, width (FWHM) and arrival time at each sensor
    ball."""
    p0 = pulses[0]
    si = p0.speed_si is not None
    per = "balls/s" if p0.units == "si" else "balls per unit time"
    rows = [("wave speed" + ("" if si else f" ({per})"), "velocity" if si else None,
             np.array([(p.speed_si if si else p.speed).value for p in pulses]))]
    for i, ball in enumerate(p0.balls):
        rows.append((f"peak force at ball {ball}", "force",
                     np.array([p.peak_force[i] for p in pulses])))
        rows.append((f"width (FWHM) at ball {ball}", "time",
                     np.array([p.width[i] for p in pulses])))
        rows.append((f"arrival at ball {ball}", "time",
                     np.array([p.arrival_time[i] for p in pulses])))
    return rows


def render_folder(path: Path, summaries, ensemble: bool = False, pulses=None,
                  swept=None) -> str:
    """An output folder of several runs: a line per run (the values of the ``swept``
    keys, ``_swept_columns``; its largest forward velocity in a prefix that suits the
    column, to the digits that hold: ``_velocity``; where the runs have force sensors,
    their ``pulses``, each run's ``measure_pulses``: the wave's speed and the last
    sensor's peak contact force), and for an ``ensemble`` (one line
    over random seeds) the mean and sample standard deviation of each summary number
    over the runs, and of its pulses. Runs that stopped before their terminal state have
    their balls counted, and their velocities and energies given, where they stopped,
    and say so."""
    from chainrun.units import end_phrase, scale_for, scale_for_column

    units = summaries[0].units
    time = scale_for("time", units, [s.end_time for s in summaries])
    speed = scale_for_column("velocity", units, [s.forward[1] if s.forward else 0.0
                                                  for s in summaries])
    wide = max(24, *(len(Path(s.path).name) for s in summaries))
    swept = swept or []
    # (a column as wide as its title: "end (paper units)" outgrows "end (µs)")
    end_title, forward_title = f"end ({time.unit})", f"forward ({speed.unit})"
    end_wide, forward_wide = max(14, len(end_title)), max(16, len(forward_title))
    head = (f"{'file':<{wide}}" + "".join(f" {title:>{width}}" for title, width, _ in swept)
            + f" {'N':>7} {'K':>4} {'outcome':<10} "
            f"{end_title:>{end_wide}} {'events':>8} {forward_title:>{forward_wide}}")
    damped = any(s.energy.get("dissipated", 0.0) > 0.0 for s in summaries)
    if damped:
        head += f" {'dissipated':>11}"
    checked = any(s.check is not None for s in summaries)
    if checked:
        head += f" {'hold to 1e-9':>13}"
    columns = _pulse_columns(pulses, units) if pulses else None
    if columns:
        head += "".join(f" {title:>{width}}" for title, width, _ in columns)
    lines = [f"{path}: {len(summaries)} runs", head]
    for i, s in enumerate(summaries):
        forward = _velocity(*s.forward, s, speed) if s.forward else "0"
        outcome = _OUTCOME_NAMES.get(s.outcome, s.outcome.replace("_", " "))
        share = s.energy.get("dissipated", math.nan)
        lines.append(f"{Path(s.path).name:<{wide}}"
                     + "".join(f" {cells[i]:>{width}}" for _, width, cells in swept)
                     + f" {s.n:>7} {s.k:>4} {outcome:<10} "
                     f"{time(s.end_time):>{end_wide}.6g} {sum(s.events.values()):>8} "
                     f"{forward:>{forward_wide}}"
                     + (f" {share:>11.2%}" if damped else "")
                     + (f" {_holding(s):>13}" if checked else "")
                     + ("".join(f" {cells[i]:>{width}}" for _, width, cells in columns)
                        if columns else ""))
    if not ensemble:
        return "\n".join(lines)
    lines += ["", f"over the {len(summaries)} runs: mean +- sample standard deviation "
                  "(min ... max), to the deviation's second digit"]
    when = end_phrase([s.terminal for s in summaries], [s.end_time for s in summaries],
                      units)
    if when:
        lines.append(f"  (the runs stopped before their terminal state: balls are counted "
                     f"by their velocities {when}, not by their fate; moving forward is "
                     "faster than 1% of the impact speed)")
    rows = [(label, quantity, np.array([value(s) for s in summaries], dtype=float))
            for label, quantity, value in (_ensemble_rows(when) if when else _ENSEMBLE)]
    # (the share against the external forces, on lines that have them only)
    rows = [row for row in rows if "against the forces" not in row[0]
            or not np.all(np.isnan(row[2]))]
    rows += _ensemble_pulses(pulses) if pulses else []
    wide = max(34, *(len(label) for label, _, _ in rows))
    lines += [f"  {label:<{wide}} {_statistics(x, quantity, units)}"
              for label, quantity, x in rows]
    return "\n".join(lines)


def _swept_columns(runs) -> list[tuple[str, int, list[str]]]:
    """The folder table's columns of the keys the runs' sweep sets (their
    ``overrides``): each key's values, in SI with its unit in one prefix where the key
    is a quantity (``speed (mm/s)``), else as given; N and K have columns of their own."""
    from chainrun.units import SWEPT_QUANTITY, scale_for

    overrides = [run.parameters.get("overrides") or {} for run in runs]
    columns = []
    for key in dict.fromkeys(key for o in overrides for key in o):
        name = key.rpartition(".")[2]
        if key in ("chain.n", "chain.k"):
            continue
        values = [o.get(key) for o in overrides]
        quantity = SWEPT_QUANTITY.get(name)
        numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool)
                      for v in values)
        if numbers and quantity is not None and runs[0].units == "si":
            scaled = scale_for(quantity, "si", values)
            title = f"{name} ({scaled.unit})" if scaled.unit else name
            cells = [f"{scaled(float(v)):.6g}" for v in values]
        else:
            title = name
            cells = ["-" if v is None else f"{v:.6g}" if numbers else str(v)
                     for v in values]
        columns.append((title, max(len(title), *(len(c) for c in cells)), cells))
    return columns


def _pulse_columns(pulses, units: str) -> list[tuple[str, int, list[str]]]:
    """The folder table's columns of the runs' ``pulses``: the wave's speed (in m/s
    for a line of spheres, else in balls per unit time) to the digits its uncertainty
    supports (six digits with two sensors, whose fit leaves no residual to judge it by),
    and the peak contact force of the last sensor the wave passes (not one measuring a
    wall's contact) to five digits; each as
    (title, width, a cell per run)."""
    from chainrun.units import format_with_error, scale_for_column

    si = all(p.speed_si is not None for p in pulses)
    fits = [p.speed_si if si else p.speed for p in pulses]
    if si:
        wave = scale_for_column("velocity", units, [f.value for f in fits])
        title = f"wave speed ({wave.unit})"
    else:
        wave = scale_for_column("alpha", "paper")  # (a number: balls per unit time)
        title = "wave speed (ball/s)" if units == "si" else "wave (balls/time)"
    speeds = [format_with_error(wave(f.value), wave(f.error))[0] if np.isfinite(f.error)
              else f"{wave(f.value):#.6g}" for f in fits]
    # the last sensor the wave passes (a wall's contact is where it reflects)
    passed = [i for i in range(pulses[0].balls.size)
              if pulses[0].on_wall is None or not pulses[0].on_wall[i]] or [-1]
    ball = int(pulses[0].balls[passed[-1]])
    peaks = [float(p.peak_force[list(p.balls).index(ball)]) if ball in list(p.balls)
             else math.nan for p in pulses]
    force = scale_for_column("force", units, peaks)
    columns = [(title, max(16, len(title)), speeds)]
    peak_title = (f"peak force, ball {ball}" + (f" ({force.unit})" if force.unit else ""))
    columns.append((peak_title, max(14, len(peak_title)),
                    [f"{force(f):#.5g}" for f in peaks]))
    return columns


def _statistics(x: np.ndarray, quantity: str | None, units: str) -> str:
    """``"88 +- 12 N (75 ... 110)"``: the mean and sample standard deviation of the
    runs' values ``x`` to the deviation's digits (``format_with_error``), and their
    range to the same place (counts exactly), in one prefix; the runs without a value
    (NaN) left out and counted."""
    from chainrun.units import format_with_error, scale_for

    found = x[np.isfinite(x)]
    if not found.size:
        return "none in any run"
    scaled = scale_for(quantity, units, [found.min(), found.max()]) if quantity else None
    unit = f" {scaled.unit}" if scaled is not None and scaled.unit else ""
    y = scaled(found) if scaled is not None else found
    some = f" (in {found.size} of the {x.size} runs)" if found.size < x.size else ""
    if found.size < 2 or y.min() == y.max():
        value = format_with_error(float(y[0]), math.nan)[0]
        return (f"{value}{unit} in every run" if found.size == x.size
                else f"{value}{unit}{some}")
    whole = bool(np.all(found == np.round(found))) and scaled is None
    mean, sd, lo, hi = format_with_error(float(y.mean()), float(np.std(y, ddof=1)),
                                         float(y.min()), float(y.max()))
    if whole:  # a count's range is exact
        lo, hi = f"{y.min():.0f}", f"{y.max():.0f}"
    return f"{mean} +- {sd}{unit} ({lo} ... {hi}){some}"


def _sensors(run) -> list[str]:
    """The section of what the run's force sensors recorded: the pulses
    (``measure_pulses``), or for a line driven by a wall's sine its steady response
    (``chainrun.analysis.transmission``); none without sensors, or for a drive the
    transmission does not take."""
    from chainrun.analysis.pulse import measure_pulses, pulsed
    from chainrun.units import format_value

    if not run.sensor_balls.size:
        return []
    if pulsed(run):
        chain = run.parameters.get("config_resolved", {}).get("chain", {})
        static = (format_value(float(chain["precompression"]), "force", run.units)
                  if chain.get("precompression") else
                  "weight on it" if chain.get("gravity") and run.line.right is not None
                  else None)
        return _pulse_lines(measure_pulses(run), static)
    from chainrun.analysis.transmission import HARMONICS, measure

    # the API's fit (its harmonics), or as many harmonics as the sampling resolves,
    # said where that is fewer
    for harmonics in range(HARMONICS, 0, -1):
        try:
            lines = _steady_lines(measure(run, harmonics=harmonics), run.units)
        except ChainrunError:
            continue
        if harmonics < HARMONICS:
            lines.append(f"          (fitted with {count(harmonics, 'harmonics')}, not "
                         f"chainrun.transmission's {HARMONICS}: the sensors sample too "
                         f"slowly for more; a smaller output.sensor_dt)")
        return lines
    return []


def _steady_lines(tr, units: str) -> list[str]:
    """The steady response at the drive's frequency: a line per sensor, each that is
    not steady (``chainrun.analysis.transmission.STEADY``) said so, with no more
    digits than what the fit leaves allows."""
    from chainrun.analysis.transmission import MIN_PERIODS
    from chainrun.units import format_value

    head = (f"at f = {format_value(float(tr.frequency), 'frequency', units)}, over the "
            f"last {int(tr.periods)} period{'s' * (int(tr.periods) != 1)} "
            "(chainrun.transmission):")
    lines = [head] + [
        f"ball {int(ball)}: " + _response(float(a), float(ph), float(x), float(r), bool(ok),
                                          units)
        for ball, a, ph, x, r, ok in zip(
            tr.sensor.values, tr.amplitude.sel(harmonic=1).values,
            tr.phase.sel(harmonic=1).values, tr.transmission.sel(harmonic=1).values,
            tr.residual.values, tr.steady.values)]
    if int(tr.periods) < MIN_PERIODS:
        lines.append(f"(fewer than {MIN_PERIODS} periods: no response is called steady; "
                     "run longer)")
    return [("steady    " if i == 0 else "          ") + line for i, line in enumerate(lines)]


def _response(a: float, phase: float, x: float, r: float, steady: bool, units: str) -> str:
    """One sensor's amplitude ``a``, ``phase`` and transmission ``x`` at the drive's
    frequency, whose fit left an rms ``r``. A steady one to four digits; one that is
    not to one digit (its phase to 0.1 rad) while ``r`` is below ``a``, and none where
    ``r`` is at or above it: it is below the noise, whose level is given instead."""
    from chainrun.units import format_measured, format_value

    nan = math.nan
    if steady:
        return (f"amplitude {format_value(a, 'force', units, zeros=True)}, phase "
                f"{phase:.3f} rad, transmission {x:#.4g}")
    if not a > 0.0:
        return "no response at the drive's frequency (not steady)"
    if r < a:
        angle = f"{phase:.1f}".replace("-0.0", "0.0")
        return (f"amplitude {format_measured(a, nan, 'force', units, 1)}, phase "
                f"{angle} rad, transmission "
                f"{format_measured(x, nan, None, units, 1)} (not steady: what the fit "
                f"leaves is {r / a:.0%} of it)")
    return (f"amplitude and transmission below the noise: what the fit leaves, "
            f"{format_measured(r, nan, 'force', units, 1)} rms (a transmission of "
            f"{format_measured(x * r / a, nan, None, units, 1)}), is "
            f"{format_measured(r / a, nan, None, units, 2)} times the amplitude "
            "(not steady)")


def _velocities(runs) -> str | None:
    """Every ball's final velocity (or where the runs stopped), the runs across, as
    ``chainrun simulate``'s table is for short lines (``velocity_table``)."""
    from types import SimpleNamespace

    from chainrun.cli.text import velocity_table

    rows = [SimpleNamespace(n=run.n, units=run.units, terminal=run.terminal,
                            final_velocity=np.asarray(run.final_velocity), check=run.check,
                            run_id=str(run.parameters.get("run_id", "run")))
            for run in runs]
    return velocity_table(rows, max_balls=max(run.n for run in runs))


@click.command()
@click.argument("paths", nargs=-1, required=True,
                type=click.Path(exists=True, path_type=Path))
@click.option("--velocities", is_flag=True,
              help="Also print every ball's final velocity (a run, or the runs of a "
                   "folder across), in the run's units, to the digits that hold.")
def info(paths: tuple[Path, ...], velocities: bool):
    """Summarise the run files PATHS, or every run of output folders PATHS, in each
    run's own units.

    For a run file: the line (its spheres, masses, contacts, walls, damping), how the
    run ended and when, its events, steps and cost, its conservation errors, which
    digits hold (for a run made with --check: how many balls' velocities hold to 1e-9
    of the impact speed, and the largest spread), the
    balls with the largest forward and backward velocities, how many balls rebound,
    are ejected (moving forward faster than 1% of the impact speed) or are left
    behind, how the impact energy is shared among them, the contacts and walls and
    the damping, the pulses its force sensors recorded (the peak contact force, its
    time, the pulse's width and arrival at each sensor, and the wave's speed fitted
    through them) or, for a line a wall drives by a sine, their steady amplitude,
    phase and transmission at the drive's frequency, and what the file stores. For an output folder (a sweep or an
    ensemble of seeds, with its index.h5): one line per run (the values of the keys the
    sweep sets among them), then the mean, standard
    deviation and range of each number over the runs when they are an ensemble (the
    same line over random seeds), their pulses' too where they have force sensors (the
    wave's speed, each sensor's peak force, width and arrival); the full summary when the
    folder holds a single run.

    \b
    Examples:
      chainrun info results/cradle/run.h5
      chainrun info results/table1
      chainrun info results/heavy/run.h5 --velocities    # every ball's, any N
    """
    from chainrun.analysis.ensemble import is_ensemble
    from chainrun.analysis.pulse import measure_pulses, pulsed
    from chainrun.analysis.summary import summarize
    from chainrun.paths import INDEX_NAME
    from chainrun.store import read_index, read_run

    try:
        for i, path in enumerate(paths):
            if i:
                click.echo()
            if path.name == INDEX_NAME:  # an output folder named by its index
                path = path.parent
            if path.is_dir():
                index = path / INDEX_NAME
                if not index.is_file():
                    fail(f"{path}: no {INDEX_NAME} (not a chainrun output folder)")
                rows = read_index(index)
                runs = [read_run(path / str(r["file"])) for r in rows]
                summaries = [summarize(run) for run in runs]
                if len(summaries) == 1:
                    click.echo(render(summaries[0], _sensors(runs[0])))
                else:
                    ensemble = is_ensemble(runs)
                    pulses = ([measure_pulses(run) for run in runs]
                              if all(pulsed(run) for run in runs) else None)
                    click.echo(render_folder(path, summaries, ensemble, pulses,
                                             _swept_columns(runs)))
            else:
                runs = [read_run(path)]
                click.echo(render(summarize(runs[0]), _sensors(runs[0])))
            table = _velocities(runs) if velocities else None
            if table:
                click.echo("\n" + table)
            elif velocities:
                click.echo("\n(no table: the runs differ in their number of balls or units)")
    except ChainrunError as exc:
        fail(str(exc))
