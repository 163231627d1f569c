"""Standard views of any run file, drawn from what the file stores and nothing else.

``VIEWS`` names them: ``spacetime`` (velocity over ball and time, an image in which the
wave front shows), ``forces`` (contact force over contact and time, the walls' too),
``profiles`` and ``displacements`` (velocity and displacement along the line at some
snapshot times),
``final`` (final velocity of every ball), ``energy`` (kinetic, contact and dissipated
energy over time, and their sum) and ``sensors`` (the force sensors' traces).
``draw_sweep`` draws a sweep's final velocities against its swept keys,
``draw_sweep_runs`` a panel per run, and ``draw_ensemble`` the statistics of an
ensemble's runs (the same line over random seeds; ``chainrun.analysis.ensemble``).

Every axis is in the run's own units (``chainrun.units``: SI with a readable prefix, or
the paper's units); lines take a colour-blind-safe colour cycle with distinct line
styles (``chainrun.plotting.style(colour=True)``); ball and contact axes have integer
ticks; titles say what the line is. Each artist carries a ``gid`` naming the array it
shows, so tests can match what is drawn with the file.
"""

from __future__ import annotations

import difflib
import math
import re
import textwrap

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from chainrun.errors import ChainrunError
from chainrun.plotting.common import MARKERS
from chainrun.units import (
    SWEPT_QUANTITY, axis_label, balls_text, end_phrase, format_value, law_unit, scale_for,
)

__all__ = ["VIEWS", "describe", "draw_ensemble", "draw_sweep", "draw_sweep_runs",
           "draw_view"]

VIEWS = ("spacetime", "forces", "profiles", "displacements", "final", "energy", "sensors")
#: an image wider than this many balls shows every s-th ball (the file is read so)
MAX_IMAGE_BALLS = 2000
#: profiles drawn at most
MAX_PROFILES = 6


def _snapshots_needed(run, view: str, least: int) -> None:
    if run.times.size < least:
        raise ChainrunError(f"{run.path}: {view} needs at least {least} snapshots, the file "
                            f"has {run.times.size} (set output.times in the experiment)")


def _integer_axis(axis) -> None:
    """Ball and contact numbers: integer ticks only."""
    axis.set_major_locator(MaxNLocator(integer=True))


def _law(alpha: np.ndarray) -> str:
    if alpha.size == 0:
        return ""
    if np.all(alpha == alpha[0]):
        a = float(alpha[0])
        return {1.0: "linear contacts", 1.5: "Hertz contacts"}.get(a, f"contacts ^{a:g}")
    return "mixed contact laws"


#: a legend of more entries than this, or of longer labels, goes outside the axes,
#: where it hides no curve: below them up to _LEGEND_BELOW entries where a label is
#: long (beside them, a column of long labels takes half the figure's width), else
#: beside them
_LEGEND_INSIDE = 4
_LEGEND_LABEL = 24
_LEGEND_BELOW = 6
_LEGEND_WRAP = 30
#: below the axes, up to this many entries with a long label stand in one column, the
#: figure's width, their lines up to _LEGEND_COLUMN_WRAP characters (in two columns a
#: label of two clauses took three lines)
_LEGEND_COLUMN = 3
_LEGEND_COLUMN_WRAP = 72
#: a legend below the axes takes a column for each label where they are no longer in
#: all than this many characters, else two
_LEGEND_ROW = 40
#: the gid of a legend inside the axes (``_clear_of_curves`` moves it if it hides one)
_INSIDE = "legend/inside"


def _legend(axes) -> None:
    """The axes' legend: inside them where it is short (where it hides no curve:
    ``_clear_of_curves``); up to six entries with a long label below them, in two
    columns; many beside them; each label wrapped to lines of ``_LEGEND_WRAP``
    characters (a longer line would take the figure's width from the axes)."""
    handles, labels = axes.get_legend_handles_labels()
    long = max(map(len, labels), default=0) > _LEGEND_LABEL
    if len(labels) <= _LEGEND_INSIDE and not long:
        axes.legend(fontsize="small").set_gid(_INSIDE)
    elif len(labels) <= _LEGEND_INSIDE or (long and len(labels) <= _LEGEND_BELOW):
        _legend_below(axes, handles, labels)
    else:
        axes.legend(handles, [_wrap(label) for label in labels],
                    fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0),
                    borderaxespad=0.0)


def _legend_below(axes, handles, labels) -> None:
    """The legend below the axes: in one row where its labels are short, else in one
    column of up to _LEGEND_COLUMN entries, or two, its labels wrapped to fit."""
    if sum(map(len, labels)) <= _LEGEND_ROW:
        ncols, width = len(labels), _LEGEND_WRAP
    elif len(labels) <= _LEGEND_COLUMN:
        ncols, width = 1, _LEGEND_COLUMN_WRAP
    else:
        ncols, width = 2, _LEGEND_WRAP
    labels = [_wrap(label.replace("\n", " "), width) for label in labels]
    axes.legend(handles, labels, fontsize="small", loc="upper center",
                bbox_to_anchor=(0.5, -0.16), ncols=ncols, borderaxespad=0.0)


def _clear_of_curves(figure, axes) -> None:
    """Move a legend inside ``axes`` that hides a curve of its own below them.

    Inside, the legend stands where it covers the fewest points of the curves
    (matplotlib's ``"best"``), which where they fill the axes (a driven line's force
    sensors, oscillating from end to end) is still over one. Where it stands is known
    once the figure is laid out, as it is here (its title set)."""
    legend = axes.get_legend()
    if legend is None or legend.get_gid() != _INSIDE:
        return
    figure.draw_without_rendering()
    box = legend.get_window_extent()
    handles, labels = axes.get_legend_handles_labels()
    if any(line.get_transform().transform_path(line.get_path()).intersects_bbox(
            box, filled=False) for line in handles):
        legend.remove()
        _legend_below(axes, handles, labels)


def _wrap(label: str, width: int = _LEGEND_WRAP) -> str:
    """``label`` in lines of ``width`` characters, never breaking inside an equation
    (``t = 0``) or between a number and its unit (``2 kHz``)."""
    glued = re.sub(r"(?<=\S) = (?=\S)", "\u00a0=\u00a0", label)
    glued = re.sub(r"(?<=\d) (?=[^\W\d]{1,3}\b)", "\u00a0", glued)
    return textwrap.fill(glued, width).replace("\u00a0", " ")


def _symlog(axes, values) -> None:
    """A symmetric log scale over ``values`` (linear below the power of ten at or below
    the smallest non-zero magnitude), with room above and below the extreme points, no
    negative half where nothing is negative and no positive half where nothing is
    positive."""
    small = np.abs(values[values != 0.0])
    # the power of ten at or below the smallest magnitude: the linear part then ends
    # on a labelled decade, a decade's height from 0, not between two labels
    least = max(float(small.min()) if small.size else 1.0, 1e-12)
    axes.set_yscale("symlog", linthresh=10.0 ** math.floor(math.log10(least)))
    top, bottom = float(np.max(values, initial=0.0)), float(np.min(values, initial=0.0))
    axes.set_ylim(2.0 * bottom if bottom < 0.0 else 0.0, 2.0 * top if top > 0.0 else 0.0)


def _drawn(table, quantity: str, units: str, unit: str = "") -> str | None:
    """How a key's random values are drawn (``"uniform 1-3 kg"``), from its generator
    table in the resolved config; None for values that are not drawn at random. A
    ``quantity`` without a prefixed unit (a stiffness) is written to 4 digits, ``unit``
    after them."""
    if not isinstance(table, dict) or "random" not in table:
        return None
    def value(x):
        return (format_value(float(x), quantity, units) if quantity != "stiffness"
                else f"{float(x):.4g}")
    after = f" {unit}" if unit else ""
    if table["random"] == "uniform":
        return f"uniform {value(table['low'])}-{value(table['high'])}{after}"
    return f"lognormal, median {value(table['median'])}{after}, sigma {table['sigma']:g}"


def _masses(table, mass: np.ndarray, units: str) -> str | None:
    """The balls' masses in brief, each with its unit: how they are drawn at random, the
    values of a repeating pattern in the line's order (``30 g / 10 g alternating``), or
    their range (``10 g-30 g``); None where every ball has one mass."""
    drawn = _drawn(table, "mass", units)
    if drawn:
        return drawn
    if np.all(mass == mass[0]):
        return None
    def value(x):
        return format_value(float(x), "mass", units)
    pattern = table.get("pattern") if isinstance(table, dict) and "impurity" not in table \
        else None
    if pattern and len(pattern) < mass.size and all(isinstance(x, (int, float))
                                                    for x in pattern):
        return " / ".join(map(value, pattern)) + (" alternating" if len(pattern) == 2
                                                  else " repeating")
    return balls_text(mass, "mass", units)


def _driven(subject: str, drive, quantity: str, units: str, swept=()) -> str:
    """``subject`` (``"left wall driven"``) and what drives it (a ``Drive``, or a tuple of
    its ``Sine`` terms), in the run's units: each sine's amplitude (a ``quantity``) at
    its frequency and its ramp (``left wall driven 10 nm at 5.5 kHz (1 ms ramp)``), less
    the keys ``swept`` (``amplitude``, ``frequency``, ``ramp``: they differ from run to
    run); samples by their number and their last time."""
    def value(x, q):
        return format_value(float(x), q, units)
    if not isinstance(drive, tuple) and drive.times is not None:
        return (f"{subject} through {drive.times.size} samples to "
                f"t = {value(drive.times[-1], 'time')}")
    si = units == "si"
    terms = []
    for sine in drive if isinstance(drive, tuple) else drive.sines:
        words = []
        if "amplitude" not in swept:
            amplitude = value(sine.amplitude, quantity)
            words.append(amplitude if si else f"amplitude {amplitude}")
        if "frequency" not in swept:
            words.append(f"at {'' if si else 'frequency '}{value(sine.frequency, 'frequency')}")
        if sine.ramp and "ramp" not in swept:
            ramp = value(sine.ramp, "time")
            words.append(f"({ramp} ramp)" if si else f"(ramp {ramp})")
        terms.append(" ".join(words))
    words = " + ".join(t for t in terms if t)
    if words and "amplitude" not in swept:  # "a force of 10 mN", "with amplitude 0.1"
        words = ("with " if not si else "of " if quantity == "force" else "") + words
    return f"{subject} {words}" if words else subject


def describe(run, varying=(), width: int | None = None) -> str:
    """What the line of a run is, in a line: its balls (material, diameter), strikers
    and speed, contact law, the balls' damping, each wall with its own, precompression,
    and what drives it (a wall's motion, forces on balls); what the swept keys
    ``varying`` set is left out (it differs from run to run). With ``width``, wrapped
    into lines of about that many characters between its parts."""
    line, units = run.line, run.units
    swept = set(varying)
    varying = {key.rpartition(".")[2] for key in swept if key.startswith("chain.")}
    config = run.parameters.get("config_resolved", {}).get("chain", {})
    parts = []
    if line.diameter is not None:
        # in the line's order (a steel and glass dimer, not glass and steel)
        materials = [str(m) for m in np.asarray(line.material).tolist()]
        names = [m for m in dict.fromkeys(materials) if m]
        odd = ""
        if len(names) == 2 and min(materials.count(n) for n in names) == 1:
            # one ball of another material (a striker, an impurity): said by its number
            alone = min(names, key=materials.count)
            names = [n for n in names if n != alone]
            odd = f", ball {materials.index(alone) + 1} {alone.replace('_', ' ')}"
        d = np.asarray(line.diameter)
        size = (_drawn(config.get("diameter"), "diameter", units)
                or balls_text(d, "diameter", units, 5))
        what = " and ".join(n.replace("_", " ") for n in names) or "given"
        parts.append(("" if "n" in varying else f"N = {line.n} ") + f"{what} spheres"
                     + ("" if "diameter" in varying else f" of {size}") + odd)
    else:
        parts.append("" if "n" in varying else f"N = {line.n}")
        masses = _masses(config.get("mass"), np.asarray(line.mass), units)
        if masses:
            parts.append(f"masses {masses}")
    drawn = _drawn(config.get("stiffness"), "stiffness", units,
                   law_unit("stiffness", line.alpha, units) if units == "si" else "")
    if drawn:
        parts.append(f"stiffnesses {drawn}")
    moving = line.velocity != 0.0
    k = line.n if moving.all() else int(np.argmin(moving))
    if moving.any():
        speed = format_value(float(np.max(np.abs(line.velocity))), "velocity", units)
        # the paper's K on its own line; elsewhere K is as often a contact's stiffness
        strikers = ("" if "k" in varying or k == 0 else f"K = {k}" if line.is_paper
                    and units != "si" else f"{k} striker{'s' * (k != 1)}")
        at = "" if units != "si" or "speed" in varying else \
            f"at {speed}" if strikers else f"struck at {speed}"
        parts.append(" ".join(p for p in (strikers, at) if p))
    if line.n > 1:
        parts.append(_law(np.asarray(line.alpha)))
    # the balls' damping before the walls, each wall with its own
    if "restitution" in config:
        if "restitution" not in varying:
            parts.append(_restitution(config["restitution"], config.get("damping_law", "")))
    elif np.any(np.asarray(line.damping) != 0.0) and "damping" not in varying:
        parts.append("damped")
    walls = run.parameters.get("config_resolved", {}).get("walls", {})
    sides = {}
    for side, wall in (("left", line.left), ("right", line.right)):
        if not wall:
            continue
        table = walls.get(side, {}) if isinstance(walls, dict) else {}
        if f"walls.{side}.restitution" in swept:
            sides[side] = ""
        elif "restitution" in table:
            sides[side] = " (" + _restitution(table["restitution"],
                                                table.get("damping_law", ""), True) + ")"
        else:
            sides[side] = " (damped)" if wall.damping > 0.0 else ""
    if len(sides) == 2 and len(set(sides.values())) == 1:
        parts.append(f"walls at both ends{sides['left']}")
    else:
        parts += [f"{side} wall{how}" for side, how in sides.items()]
    if "precompression" in config and "precompression" not in varying:
        parts.append(f"precompressed {format_value(config['precompression'], 'force', units)}")
    if "gravity" in config and "gravity" not in varying:
        parts.append(f"under gravity {config['gravity']:g}" + (" m/s²" if units == "si" else ""))
    # what drives the line: the experiment, as the strikers are a struck line's
    for side, wall in (("left", line.left), ("right", line.right)):
        if wall and wall.motion is not None:
            parts.append(_driven(f"{side} wall driven", wall.motion, "position", units,
                                 {key.rpartition(".")[2] for key in swept
                                  if key.startswith(f"walls.{side}.motion.")}))
    sines = {}  # (the sines on one ball add up: one force of their sum)
    for ball, drive in line.drives:
        if drive.times is None:
            sines.setdefault(ball, []).extend(drive.sines)
        else:
            parts.append(_driven(f"ball {ball + 1} driven by a force", drive, "force", units))
    parts += [_driven(f"ball {ball + 1} driven by a force", tuple(each), "force", units)
              for ball, each in sines.items()]
    parts = [p for p in parts if p]
    if width is None:
        return ", ".join(parts)
    lines = [parts[0]]
    for part in parts[1:]:
        if len(lines[-1]) + 2 + len(part) > width:
            lines[-1] += ","
            lines.append(part)
        else:
            lines[-1] += ", " + part
    return "\n".join(lines)


def _restitution(e, law: str, inside: bool = False) -> str:
    """``restitution 0.9 (Tsuji)``: a coefficient of restitution and its law
    (``restitution 0.9, Tsuji`` ``inside`` parentheses)."""
    law = {"tsuji": "Tsuji", "kuwabara-kono": "Kuwabara-Kono"}.get(law, law)
    law = "" if not law else f", {law}" if inside else f" ({law})"
    return f"restitution {e if isinstance(e, (int, float)) else 'varied'}{law}"


def _run_name(run) -> str:
    """A run of a sweep by what its keys set: in SI, each value with its unit
    (``speed 1 m/s`` for the run ``speed=1.0``); else, and for a key whose values have
    no unit, its run id; "" for a run of no sweep."""
    run_id = str(run.parameters.get("run_id", ""))
    overrides = run.parameters.get("overrides", {})
    if run_id == "run" or not overrides:
        return "" if run_id == "run" else run_id
    if run.units != "si":
        return run_id
    parts = []
    for key, value in overrides.items():
        name = key.rpartition(".")[2]
        quantity = SWEPT_QUANTITY.get(name)
        if quantity is None or not isinstance(value, (int, float)):
            return run_id
        parts.append(f"{name} {format_value(float(value), quantity, run.units)}")
    return ", ".join(parts)


def _title(run, width: int = 72) -> str:
    """The experiment (and run) name over what the line is, wrapped to ``width``."""
    experiment = run.parameters.get("experiment", "")
    run_name = _run_name(run)
    name = experiment + (f" ({run_name})" if run_name else "")
    return "\n".join([name] * bool(name) + [describe(run, width=width)])


def _on_the_runs_scale(run, quantity: str, values) -> np.ndarray:
    """``values`` with the run's own scale of a time (the last the views draw: its
    last snapshot or sample) or a velocity (the impact speed), so that every view of a
    run writes its times, and its velocities, in one prefix (a profile in m/s beside
    final velocities in mm/s read as two runs)."""
    values = np.ravel(np.asarray(values, dtype=float))
    if quantity == "time":
        ends = [float(t) for t in (*run.times[-1:], *run.sensor_time[-1:])]
        return np.concatenate([values, [max(ends)]]) if ends else values
    if quantity == "velocity":
        speed = float(np.max(np.abs(run.line.velocity))) if run.n else 0.0
        return np.concatenate([values, [speed]]) if speed > 0.0 else values
    return values


def _time_axis(axes, run, times, which: str = "x"):
    """Label a time axis in the run's units, in the prefix of the run's last time
    (``_on_the_runs_scale``); returns the scaling for the times."""
    label, scaled = axis_label("time", "time", run.units,
                               _on_the_runs_scale(run, "time", times))
    (axes.set_xlabel if which == "x" else axes.set_ylabel)(label)
    return scaled


def _spacetime(run, figure: Figure, axes) -> None:
    _snapshots_needed(run, "spacetime", 2)
    stride = -(-run.n // MAX_IMAGE_BALLS)
    v = np.asarray(run.velocities[:, ::stride])
    balls = np.arange(1, run.n + 1)[::stride]
    label, speed = axis_label("velocity", "velocity", run.units,
                              _on_the_runs_scale(run, "velocity", v))
    time = _time_axis(axes, run, run.times)
    top = float(np.max(np.abs(speed(v)))) or 1.0
    t = time(run.times)
    image = axes.imshow(speed(v).T, origin="lower", aspect="auto", cmap="RdBu_r",
                        vmin=-top, vmax=top, interpolation="nearest",
                        extent=(t[0], t[-1], balls[0] - 0.5, balls[-1] + stride - 0.5),
                        gid="velocity")
    figure.colorbar(image, ax=axes, label=label)
    axes.set_ylabel("ball" + (f" (every {stride}th)" if stride > 1 else ""))
    _integer_axis(axes.yaxis)


def _forces(run, figure: Figure, axes) -> None:
    _snapshots_needed(run, "forces", 2)
    if run.n < 2:
        raise ChainrunError(f"{run.path}: a line of one ball has no contacts")
    stride = -(-(run.n - 1) // MAX_IMAGE_BALLS)
    force = run.contact_forces(stride)
    contacts = np.arange(1, run.n)[::stride]
    # a wall's contact as a row of its own beside the balls' (0 the left wall's, N the
    # right's): the force on a wall is what an experiment measures there
    left, right = (w is not None for w in run.line.walls)
    walls = stride == 1 and (left or right)
    if walls:
        on_walls = run.wall_forces()
        if left:
            force, contacts = np.hstack([on_walls[:, :1], force]), np.r_[0, contacts]
        if right:
            force, contacts = np.hstack([force, on_walls[:, 1:]]), np.r_[contacts, run.n]
    # a line under a static load (precompressed, or held by walls) at t = 0: the
    # change of each contact's force from it, on a scale centred at no change, or a
    # wave of a few per cent of the load would be a shade of the load's colour
    loaded = run.times[0] == 0.0 and np.any(force[0] != 0.0)
    if loaded:
        force = force - force[0]
    name = "contact force change since t = 0" if loaded else "contact force"
    label, scaled = axis_label(name, "force", run.units, force)
    t = _time_axis(axes, run, run.times)(run.times)
    top = float(np.max(np.abs(scaled(force)))) or 1.0
    colours = dict(cmap="RdBu_r", vmin=-top, vmax=top) if loaded else dict(cmap="magma_r",
                                                                          vmin=0.0)
    image = axes.imshow(scaled(force).T, origin="lower", aspect="auto",
                        interpolation="nearest", **colours,
                        extent=(t[0], t[-1], contacts[0] - 0.5, contacts[-1] + stride - 0.5),
                        gid="force")
    figure.colorbar(image, ax=axes, label=label)
    axes.set_ylabel("contact j (balls j, j+1)" + (f", every {stride}th" if stride > 1 else "")
                    + (f"; {' and '.join(n for n, w in (('0', left), (str(run.n), right)) if w)}"
                       f" the wall{'s' * (left and right)}" if walls else ""))
    _integer_axis(axes.yaxis)


def _last_moving(run) -> int:
    """The index of the last snapshot worth a profile: the first at or after the
    terminal state (later ones hold the same velocities, and balls flying apart), or
    the last."""
    last = run.times.size - 1
    if run.terminal:
        after = np.flatnonzero(np.asarray(run.times) >= run.end_time)
        if after.size:
            last = int(after[0])
    return last


def _along_the_line(run, figure: Figure, axes, name: str, data, quantity: str,
                    gid: str | None = None) -> None:
    """Profiles of ``data`` along the line at up to MAX_PROFILES snapshots, spread
    over the run until its terminal state (``_last_moving``)."""
    _snapshots_needed(run, gid or name, 1)
    picks = np.unique(np.linspace(0, _last_moving(run), MAX_PROFILES).round().astype(int))
    rows = np.asarray(data[picks])
    label, scaled = axis_label(name, quantity, run.units,
                               _on_the_runs_scale(run, quantity, rows))
    balls = np.arange(1, run.n + 1)
    for row, i in zip(rows, picks):
        axes.plot(balls, scaled(row), label=f"t = {format_value(run.times[i], 'time', run.units)}",
                  gid=f"{gid or name}/{i}")
    axes.set_xlabel("ball")
    _integer_axis(axes.xaxis)
    axes.set_ylabel(label)
    _legend(axes)


def _profiles(run, figure: Figure, axes) -> None:
    _along_the_line(run, figure, axes, "velocity", run.velocities, "velocity")


def _displacements(run, figure: Figure, axes) -> None:
    """Displacements along the line; on a line that starts displaced (precompressed, its
    static compressions far larger than any wave's), their change since t = 0, as the
    force image draws a loaded line's forces."""
    x = np.asarray(run.positions)
    if run.times[0] == 0.0 and np.any(x[0] != 0.0):
        _along_the_line(run, figure, axes, "displacement since t = 0", x - x[0], "position",
                        gid="displacement")
    else:
        _along_the_line(run, figure, axes, "displacement", x, "position")


def _sensors(run, figure: Figure, axes) -> None:
    if run.sensor_balls.size == 0:
        raise ChainrunError(f"{run.path}: no force sensors (set output.sensors and "
                            "output.sensor_dt in the experiment)")
    mean = run.sensor_force.mean(axis=2)
    label, scaled = axis_label("mean contact force on the ball", "force", run.units, mean)
    t = _time_axis(axes, run, run.sensor_time)(run.sensor_time)
    for s, ball in enumerate(run.sensor_balls):
        axes.plot(t, scaled(mean[:, s]), label=f"ball {ball}", gid=f"sensor/{ball}")
    axes.set_ylabel(label)
    _legend(axes)


def _final_name(runs) -> str:
    """What the velocities at the end of ``runs`` are: final velocities at the terminal
    state, else the velocities where the runs stopped (at t_end, or a failure)."""
    when = end_phrase([run.terminal for run in runs], [run.end_time for run in runs],
                      runs[0].units)
    return f"velocity {when}" if when else "final velocity"


def _final(run, figure: Figure, axes, log: bool) -> None:
    v = np.asarray(run.final_velocity)
    label, scaled = axis_label(_final_name([run]), "velocity", run.units,
                               _on_the_runs_scale(run, "velocity", v))
    axes.plot(np.arange(1, run.n + 1), scaled(v), marker="o", markersize=3,
              gid="final_velocity")
    axes.axhline(0.0, color="0.6", linewidth=0.6)
    axes.set_xlabel("ball")
    _integer_axis(axes.xaxis)
    axes.set_ylabel(label)
    if log:
        _symlog(axes, scaled(v))


def _energy(run, figure: Figure, axes) -> None:
    """Kinetic, contact and dissipated energy, on a line with external forces the
    energy stored against them (-sum f (x - x(0)), a column's weight's potential energy,
    as ``chainrun info`` shares it) apart from the contacts', the drives' work on a
    driven line, and the balance, kinetic + contact + dissipated less the drives' work,
    which stays at the initial energy."""
    _snapshots_needed(run, "energy", 2)
    obs = run.observables
    # measured from the static state a precompressed line starts in: its contacts'
    # energy there is the impact's, and the sum is the impact energy
    kinetic, stored = obs["kinetic_energy"], obs["potential_energy"] - run.baseline_energy
    dissipated = obs["dissipated_energy"]
    work = obs.get("drive_work", np.zeros_like(kinetic))
    driven = bool(np.any(work))
    load = np.zeros_like(kinetic)
    if driven:
        # the static load's work as the walls move (F0 w(t), given back as they
        # return) is taken off the drives' work and the contacts' energy alike: it
        # would swing across both, far above what the line takes up
        load = run.static_load_work(run.times)
        stored = stored - stored[0] - load
        work = work - load
    total = kinetic + stored + dissipated - work
    forced = bool(np.any(run.line.force))
    against = (-(np.asarray(run.positions) - run.line.position) @ run.line.force if forced
               else np.zeros_like(kinetic))
    stored = stored - against
    label, scaled = axis_label("energy", "energy", run.units,
                               np.concatenate([kinetic, stored, against, total, work]))
    t = _time_axis(axes, run, run.times)(run.times)
    contacts = "in contacts and walls" if run.line.walls != (None, None) else "in contacts"
    if np.any(run.line.position) and not driven:
        contacts += " (above the static state)"
    if driven:
        contacts += (", about the static state" if np.any(load) else ", since t = 0")
    axes.plot(t, scaled(kinetic), label="kinetic", gid="kinetic_energy")
    axes.plot(t, scaled(stored), label=contacts, gid="potential_energy")
    if forced:
        axes.plot(t, scaled(against), label="against the forces", gid="forces_energy")
    if np.any(dissipated):
        axes.plot(t, scaled(dissipated), label="dissipated", gid="dissipated_energy")
    if np.any(work):
        axes.plot(t, scaled(work), gid="drive_work",
                  label="the drives' work, beyond the static load's" if np.any(load)
                  else "the drives' work")
    axes.plot(t, scaled(total), label="sum less the drives' work" if np.any(work) else "sum",
              color="black", linestyle="-", linewidth=1.4, gid="total_energy")
    axes.set_ylabel(label)
    _legend(axes)


def draw_view(run, view: str, *, log: bool = False) -> Figure:
    """The Figure of ``view`` (one of ``VIEWS``) for a run (``chainrun.store.RunData``).

    ``log`` draws the final velocities on a symmetric log scale (linear below the
    smallest non-zero magnitude). Must be called inside
    ``chainrun.plotting.style(colour=True)`` for the figure to look as saved.
    """
    if view not in VIEWS:
        close = difflib.get_close_matches(view, VIEWS, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise ChainrunError(f"no view {view!r} ({hint}the views: {', '.join(VIEWS)})")
    figure = Figure(layout="constrained")
    axes = figure.add_subplot()
    if view == "final":
        _final(run, figure, axes, log)
    else:
        {"spacetime": _spacetime, "forces": _forces, "profiles": _profiles,
         "displacements": _displacements, "energy": _energy, "sensors": _sensors}[view](
            run, figure, axes)
    axes.set_title(_title(run), fontsize="small")
    _clear_of_curves(figure, axes)
    return figure


def _ball_index(ball: int, n: int) -> int | None:
    """0-based index of ball number ``ball`` (negative: from the end) in a line of n."""
    i = ball - 1 if ball > 0 else n + ball
    return i if 0 <= i < n else None


def _overrides(run) -> dict:
    return run.parameters.get("overrides", {})


def draw_sweep(runs, balls=(1, -1)) -> Figure:
    """Final velocities of ``balls`` against each swept key, a panel per key.

    ``runs`` are the runs of one sweep (``chainrun.store.RunData``); ``balls`` are ball
    numbers, 1-based, negative counting from the end (-1: the last ball). Each point
    carries the run's id; a ball a run does not have is left out of it.
    """
    keys = sorted({key for run in runs for key in _overrides(run)})
    if not keys:
        raise ChainrunError("not a sweep: its runs have no swept keys")
    for ball in balls:
        if all(_ball_index(ball, run.n) is None for run in runs):
            sizes = sorted({run.n for run in runs})
            n = f"N = {sizes[0]}" if len(sizes) == 1 else f"N = {sizes[0]}..{sizes[-1]}"
            raise ChainrunError(f"balls: no run has ball {ball} ({n}; balls are numbered "
                                f"1..N, or -1..-N from the last)")
    units = runs[0].units
    finals = np.concatenate([np.asarray(run.final_velocity) for run in runs])
    label, scaled = axis_label(_final_name(runs), "velocity", units, finals)
    figure = Figure(figsize=(4.5 * len(keys), 3.6), layout="constrained")
    for panel, key in enumerate(keys, start=1):
        axes = figure.add_subplot(1, len(keys), panel)
        for which, ball in enumerate(balls):
            points = []
            for run in runs:
                value = _overrides(run).get(key)
                i = _ball_index(ball, run.n)
                if isinstance(value, (int, float)) and i is not None:
                    points.append((value, run.final_velocity[i]))
            if not points:
                continue
            x, y = np.array(sorted(points)).T
            name = "last ball" if ball == -1 else (f"ball {ball}" if ball > 0
                                                    else f"ball N{ball + 1:+d}")
            xlabel, along = _swept_axis(key, units, x)
            axes.plot(along(x), scaled(y), label=name, gid=f"final_velocity/{key}/{ball}",
                      **MARKERS[which % len(MARKERS)])
            axes.set_xlabel(xlabel)
            if x.min() > 0 and x.max() >= 100 * x.min():  # values spread over decades
                axes.set_xscale("log")
            elif np.all(x == np.round(x)):  # K, N, a seed: whole numbers
                _integer_axis(axes.xaxis)
        axes.axhline(0.0, color="0.6", linewidth=0.6)
        axes.set_ylabel(label)
        axes.legend(fontsize="small")
    experiment = runs[0].parameters.get("experiment", "")
    figure.suptitle("\n".join([f"{experiment}: {len(runs)} runs"]
                              + [describe(runs[0], keys, 40 * len(keys))]),
                    fontsize="small")
    return figure


#: What a swept key is, in words, by its last part (the key itself follows it)
_SWEPT_NAMES = {"k": "K, balls that strike", "n": "N, balls", "alpha": "contact exponent",
                "speed": "impact speed", "restitution": "restitution",
                "precompression": "precompression", "diameter": "diameter",
                "frequency": "drive frequency", "amplitude": "drive amplitude",
                "seed": "random seed", "rtol": "step tolerance"}


def _swept_axis(key: str, units: str, values) -> tuple[str, object]:
    """The label of an axis of swept ``key``'s ``values`` and their scaling:
    ``impact speed (chain.speed, mm/s)``, ``K, balls that strike (chain.k)``; the key
    alone where it has no name here."""
    name = _SWEPT_NAMES.get(key.rpartition(".")[2])
    quantity = SWEPT_QUANTITY.get(key.rpartition(".")[2])
    scaled = scale_for(quantity, units, values) if quantity else scale_for("alpha", "paper")
    inside = ", ".join(p for p in (key if name else "", scaled.unit) if p)
    return (name or key) + (f" ({inside})" if inside else ""), scaled


def draw_sweep_runs(runs, *, log: bool = False) -> Figure:
    """A panel per run of a sweep: its final velocities against ball number, titled by
    its run id, on a grid of at most 5 columns, every panel on one velocity scale; where
    the runs' impact speeds differ tenfold or more (a sweep of the speed), each run's
    over its own impact speed, or the slow runs' panels would be flat lines."""
    cols = min(5, len(runs))
    rows = -(-len(runs) // cols)
    units = runs[0].units
    speeds = np.array([float(np.max(np.abs(r.line.velocity))) if r.n else 0.0 for r in runs])
    relative = bool(np.all(speeds > 0) and speeds.max() >= 10.0 * speeds.min())
    finals = [np.asarray(r.final_velocity) / (v if relative else 1.0)
              for r, v in zip(runs, speeds)]
    if relative:
        label, scaled = f"{_final_name(runs)} / impact speed", (lambda a: np.asarray(a))
    else:
        label, scaled = axis_label(_final_name(runs), "velocity", units, np.concatenate(finals))
    figure = Figure(figsize=(2.6 * cols, 2.2 * rows + 0.4), layout="constrained")
    first = None
    for i, run in enumerate(runs):
        # one velocity scale for every panel, so that the runs compare at a glance
        axes = figure.add_subplot(rows, cols, i + 1, sharey=first)
        first = first or axes
        v = scaled(finals[i])
        axes.plot(np.arange(1, run.n + 1), v, marker="o", markersize=2, linewidth=0.8,
                  gid=f"final_velocity/{run.parameters.get('run_id', i)}")
        axes.axhline(0.0, color="0.6", linewidth=0.5)
        axes.set_title(_run_name(run) or str(i), fontsize="small")
        axes.tick_params(labelsize="x-small")
        _integer_axis(axes.xaxis)
    if log:  # (the panels share it: a scale over every run's velocities)
        _symlog(first, scaled(np.concatenate(finals)))
    figure.supxlabel("ball", fontsize="small")
    figure.supylabel(label, fontsize="small")
    keys = sorted({key for run in runs for key in _overrides(run)})
    experiment = runs[0].parameters.get("experiment", "")
    figure.suptitle("\n".join([f"{experiment}: {len(runs)} runs"]
                              + [describe(runs[0], keys, 45 * cols)]), fontsize="small")
    return figure


def draw_ensemble(stats, run) -> Figure:
    """An ensemble (``chainrun.analysis.ensemble.Ensemble``; ``run`` one of its runs,
    for the title): the mean final velocity of each ball with its standard deviation
    and range over the runs (the velocity where the runs stopped, so labelled, where
    they stopped before their terminal state), and the energy left in the line over
    time, each run's and their mean (where the runs share their snapshot times)."""
    final, units = stats.final, stats.units
    two = stats.energy_left is not None
    figure = Figure(figsize=(9.6 if two else 4.8, 3.8), layout="constrained")
    axes = figure.add_subplot(1, 2 if two else 1, 1)
    when = end_phrase(stats.terminal, stats.end_times, units)
    label, scaled = axis_label(f"velocity {when}" if when else "final velocity", "velocity",
                               units, np.concatenate([final["min"], final["max"]]))
    balls = np.arange(1, final["mean"].size + 1)
    axes.fill_between(balls, scaled(final["min"]), scaled(final["max"]), alpha=0.18,
                      linewidth=0, label="range", gid="final_velocity/range")
    axes.fill_between(balls, scaled(final["mean"] - final["sd"]),
                      scaled(final["mean"] + final["sd"]), alpha=0.35, linewidth=0,
                      label="mean ± standard deviation", gid="final_velocity/sd")
    axes.plot(balls, scaled(final["mean"]), label=f"mean of {stats.runs} runs",
              gid="final_velocity/mean")
    axes.axhline(0.0, color="0.6", linewidth=0.6)
    axes.set_xlabel("ball")
    _integer_axis(axes.xaxis)
    axes.set_ylabel(label)
    axes.legend(fontsize="small")
    if two:
        axes = figure.add_subplot(1, 2, 2)
        t = _time_axis(axes, run, stats.times)(stats.times)
        for i, row in enumerate(stats.energy_left):
            axes.plot(t, 100.0 * row, color="0.7", linestyle="-", linewidth=0.6,
                      label="each run" if i == 0 else None, gid=f"energy/{i}")
        axes.plot(t, 100.0 * stats.energy_left.mean(axis=0), color="black", linestyle="-",
                  linewidth=1.4, label="mean", gid="energy/mean")
        axes.set_ylabel("energy left (% of the impact)")
        axes.set_ylim(0.0, None)
        axes.legend(fontsize="small")
    keys = run.parameters.get("overrides", {})
    experiment = run.parameters.get("experiment", "")
    figure.suptitle("\n".join([f"{experiment}: an ensemble of {stats.runs} runs"]
                              + [describe(run, keys, 80 if two else 40)]),
                    fontsize="small")
    return figure
