"""A run at a glance: what ``chainrun info`` prints, as numbers.

Read from a run file only (``chainrun.store.RunData``), from its own line (masses,
contacts, walls, forces and damping; ``RunData.line``), in its own units. A ball
*rebounds* when it moves backward, and is *ejected* when it moves forward, faster than
``SIGNIFICANT`` (1%) of the impact speed (the fastest initial speed: the paper's
threshold of a significant velocity, either way), and is *left behind* otherwise.
Energies are shares of the impact energy (``chainrun.solver.physics.impact_energy``: K/2
on the paper's line): the kinetic energy of the rebounding, ejected and left-behind
balls at the end, the energy still in the contacts and walls (above the static state a
precompressed line starts in), the energy stored against the external forces
(-sum f (x - x(0))), and the energy the damping dissipated. They add up to 100%, to the
run's energy error. On a driven line (a moving wall, forces prescribed in time) the
shares are of the energy the line took up by the end: its impact energy (0 without
strikers) plus the drives' work by then (``RunData.drive_energy``), which the same
shares add up to; a line that took up no energy has none. Where a driven line starts
precompressed, the static load's work as its walls move (``physics.static_load_work``,
F0 times the wall's displacement) is taken off both the drives' work and the contacts'
energy: it swings with the wall's phase and is given back, and without it every share
lies between 0 and 100%.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from chainrun.analysis.derived import SIGNIFICANT
from chainrun.check import Check, reference_speed
from chainrun.solver import EventKind
from chainrun.solver.model import strikers
from chainrun.solver.physics import line_kinetic_energy, line_potential_energy

__all__ = ["RunSummary", "describe_line", "law_name", "summarize"]

#: The energy shares, in the order they are shown ("forces" on a line with external
#: forces only: the energy stored against them, -sum f (x - x(0)), the weight's potential
#: energy in a column under gravity).
SHARES = ("rebound", "ejected", "left behind", "contacts", "forces", "dissipated")


def law_name(alpha: float) -> str:
    """``linear``, ``Hertz`` or ``power alpha`` for the contact exponent."""
    if alpha == 1.0:
        return "linear"
    if alpha == 1.5:
        return "Hertz"
    if math.isnan(alpha):
        return "mixed"
    return f"power {alpha:g}"


@dataclass(frozen=True)
class RunSummary:
    """The numbers of one run that a person reads first, in the run's ``units``.

    ``forward`` and ``backward`` are (ball number, 1-based; final velocity) of the ball
    with the largest forward (towards ball N) and backward final velocity, or None where
    no ball moves that way. ``events`` counts the logged events by ``EventKind`` name.
    ``impact`` is the impact energy, ``drive_work`` the drives' work by the end beyond
    the static load's (``physics.static_load_work``; 0 without drives), and ``energy``
    the shares (``SHARES``; "forces" only on a line with external forces) of their sum
    at the end (NaN where it is not > 0). ``dissipating`` is the contact (1-based) that
    dissipated most, 0 for a wall, -1 for an elastic line. ``check`` is the run's
    conditioning check (``chainrun.check.Check``), None for a run without one.
    ``static_load`` is the static load's work taken off the drives' work (0 unless the
    line is driven and starts precompressed); ``reference`` the speed the check's
    spreads are measured against, and its name (``chainrun.check.reference_speed``);
    ``energy_floor`` what the rounding of the energy balance's terms can leave
    (``Diagnostics.energy_floor``).
    ``walls`` is how many walls the line has (0, 1 or 2).
    """

    path: str
    creator_version: str
    created: str
    units: str
    n: int
    k: int
    alpha: float
    rtol: float
    outcome: str
    message: str
    terminal: bool
    end_time: float
    events: dict[str, int]
    steps: int
    rejected_steps: int
    max_window: int
    closed_form: int
    wall_time: float
    momentum_error: float
    energy_error: float
    energy_correction: float
    speed: float
    forward: tuple[int, float] | None
    backward: tuple[int, float] | None
    rebounding: int
    ejected: int
    left_behind: int
    impact: float
    energy: dict[str, float]
    drive_work: float
    dissipating: int
    snapshots: int
    sensors: int
    samples: int
    first_time: float
    last_time: float
    file_bytes: int
    line: str
    check: Check | None = None
    walls: int = 0
    static_load: float = 0.0
    reference: tuple[float, str] = (1.0, "the impact speed")
    energy_floor: float = 0.0
    momentum_scale: float = 1.0  # M V of the line's scales, the unit of momentum_error

    @property
    def dissipated(self) -> float:
        """The energy the damping took (0 on an elastic line)."""
        taken = self.impact + self.drive_work
        return self.energy["dissipated"] * taken if taken > 0.0 else 0.0


def _span(a: np.ndarray, fmt) -> str:
    """``"1"``, or ``"0.5 ... 2"`` for values that differ, each by ``fmt``."""
    a = np.asarray(a)
    if a.size == 0:
        return "none"
    lo, hi = a.min(), a.max()
    return fmt(lo) if lo == hi else f"{fmt(lo)} ... {fmt(hi)}"


def describe_line(line, units: str, precompression: float | None = None,
                  gravity: float | None = None) -> str:
    """The line for a person, in brief: its spheres (material and diameter) or masses,
    contacts, gaps, forces (a ``precompression``'s, or the weights of ``gravity``,
    said as one), damping and walls; "" for the paper's line, which N, K and alpha say
    whole."""
    from chainrun.units import balls_text, format_value

    if line.is_paper and units != "si":
        return ""

    def quantity(name):
        return lambda x: format_value(float(x), name, units)

    parts = []
    if line.diameter is not None:
        # in the line's order (a steel and aluminium dimer starts with steel)
        names = [m for m in dict.fromkeys(np.asarray(line.material).tolist()) if m] or [
            "given constants"]
        parts.append(f"{', '.join(n.replace('_', ' ') for n in names)} spheres of "
                     f"{balls_text(line.diameter, 'diameter', units, 5)}")
    parts.append(f"masses {balls_text(line.mass, 'mass', units)}")
    if line.n > 1:
        alpha = _span(line.alpha, lambda x: f"{x:g}")
        unit = (f" N/m^{alpha}" if " " not in alpha else " N/m^alpha") if units == "si" else ""
        parts.append(f"stiffness {_span(line.stiffness, lambda x: f'{x:.4g}')}{unit}, "
                     f"alpha {alpha}")
    if np.any(line.gap):
        parts.append(f"gaps {_span(line.gap, quantity('gap'))}")
    if gravity:
        parts.append(f"under gravity {gravity:g}" + (" m/s^2" if units == "si" else "")
                     + (" towards ball N, resting on the right wall" if line.right is not None
                        else " towards ball N"))
    elif precompression and np.count_nonzero(line.force) == 1:
        ball = int(np.flatnonzero(line.force)[0]) + 1
        parts.append(f"precompressed {format_value(float(precompression), 'force', units)} "
                     f"(a static force on ball {ball}, held by the right wall)")
    elif np.any(line.force):
        forced = int(np.count_nonzero(line.force))
        parts.append(f"forces on {forced} ball{'s' * (forced != 1)}, "
                     f"{_span(line.force[line.force != 0], quantity('force'))}")
    if np.any(line.damping):
        beta = _span(line.damping_exponent, lambda x: f"{x:g}")
        parts.append(f"damping {_span(line.damping, lambda x: f'{x:.4g}')}"
                     + (f" N s/m^{1 + float(line.damping_exponent[0]):g}"
                        if units == "si" and " " not in beta else "")
                     + f" (exponent {beta})")
    walls = [f"{side} (stiffness {w.stiffness:.4g}" + (f" N/m^{w.alpha:g}" if units == "si"
                                                          else "")
             + f", alpha {w.alpha:g}"
             + (f", gap {format_value(w.gap, 'gap', units)}" if w.gap else "")
             + (f", damping {w.damping:.4g}" + (f" N s/m^{1 + w.damping_exponent:g}"
                                                 if units == "si" else "")
                + f" (exponent {w.damping_exponent:g})" if w.damping else "") + ")"
             for side, w in (("left", line.left), ("right", line.right)) if w is not None]
    parts.append("walls: " + (", ".join(walls) if walls else "none"))
    for side, w in (("left", line.left), ("right", line.right)):
        if w is not None and w.motion is not None:
            parts.append(f"the {side} wall moves by "
                         f"{_drive_text(w.motion, 'position', units)}")
    for ball, drive in line.drives:
        parts.append(f"ball {ball + 1} driven by a force {_drive_text(drive, 'force', units)}")
    return "; ".join(parts)


def _drive_text(drive, quantity: str, units: str) -> str:
    """A drive (``chainrun.solver.Drive``) for a person, in the run's units: its sines'
    amplitudes (a ``quantity``), frequencies and ramps, or its samples."""
    from chainrun.units import format_value

    if drive.times is not None:
        return (f"a spline through {drive.times.size} samples to t = "
                f"{format_value(float(drive.times[-1]), 'time', units)}, held after")
    return " + ".join(
        f"{format_value(s.amplitude, quantity, units)} sin(2 pi f t), f = "
        f"{format_value(s.frequency, 'frequency', units)}"
        + (f", ramp {format_value(s.ramp, 'time', units)}" if s.ramp else "")
        for s in drive.sines)


def summarize(run) -> RunSummary:
    """The summary of a run (``chainrun.store.RunData``)."""
    line = run.line
    v = np.asarray(run.final_velocity, dtype=float)
    speed = float(np.max(np.abs(line.velocity))) if line.n else 0.0
    # significant either way (a ball drifting back at picometres per second, after a
    # cradle's impact, is left behind): the paper's 1% of the impact speed
    significant = SIGNIFICANT * (speed or 1.0)
    back, ahead = v < -significant, v > significant
    scales = (run.model or {}).get("scales") or {}
    behind = ~back & ~ahead
    impact = run.impact_energy
    # on a driven precompressed line, the static load's work as the walls move is given
    # back as they return: taken off the drives' work and the contacts' energy alike
    load = float(run.static_load_work(run.end_time)) if run.drive_energy else 0.0
    work = float(run.drive_energy) - load
    taken = impact + work
    stored = (float(line_potential_energy(run.final_position, line, run.end_time))
              - run.baseline_energy - load)
    amounts = {name: float(line_kinetic_energy(np.where(mask, v, 0.0), line.mass))
               for name, mask in (("rebound", back), ("ejected", ahead),
                                  ("left behind", behind))}
    if np.any(line.force):
        # the energy stored against the external forces (a column's weight), apart
        # from the contacts' and walls' own: -sum f (x - x(0))
        against = -float(line.force @ (np.asarray(run.final_position) - line.position))
        amounts |= {"contacts": stored - against, "forces": against}
    else:
        amounts |= {"contacts": stored}
    amounts["dissipated"] = float(run.dissipated_energy)
    energy = {name: (amount / taken if taken > 0.0 else math.nan)
              for name, amount in amounts.items()}
    kinds = np.asarray(run.event_kind)
    d = run.diagnostics
    chain = run.parameters.get("config_resolved", {}).get("chain", {})
    return RunSummary(
        path=str(run.path),
        creator_version=run.creator_version,
        created=run.created,
        units=run.units,
        n=run.n,
        k=strikers(line),
        alpha=float(line.alpha[0]) if line.n > 1 and np.all(line.alpha == line.alpha[0])
        else (math.nan if line.n > 1 else run.alpha),
        rtol=float(run.parameters["rtol"]),
        outcome=run.outcome,
        message=run.message,
        terminal=run.terminal,
        end_time=run.end_time,
        events={kind.name: int(np.sum(kinds == kind.value)) for kind in EventKind},
        steps=int(d["steps"]),
        rejected_steps=int(d["rejected_steps"]),
        max_window=int(d["max_window"]),
        closed_form=int(d.get("closed_form_collisions", 0)),
        wall_time=float(d["wall_time"]),
        momentum_error=float(d["momentum_error"]),
        energy_error=float(d["energy_error"]),
        energy_correction=float(d["energy_correction"]),
        energy_floor=float(d.get("energy_floor", 0.0)),
        speed=speed,
        forward=(int(np.argmax(v)) + 1, float(v.max())) if v.size and v.max() > 0 else None,
        backward=(int(np.argmin(v)) + 1, float(v.min())) if v.size and v.min() < 0 else None,
        rebounding=int(back.sum()),
        ejected=int(ahead.sum()),
        left_behind=int(behind.sum()),
        impact=impact,
        energy=energy,
        drive_work=work,
        static_load=load,
        reference=reference_speed(line),
        momentum_scale=scales.get("mass", 1.0) * scales.get("velocity", 1.0),
        dissipating=_most_dissipating(run),
        snapshots=int(run.times.size),
        sensors=int(run.sensor_balls.size),
        samples=int(run.sensor_time.size),
        first_time=float(run.times[0]) if run.times.size else math.nan,
        last_time=float(run.times[-1]) if run.times.size else math.nan,
        file_bytes=os.path.getsize(run.path),
        line=describe_line(line, run.units, chain.get("precompression"), chain.get("gravity")),
        walls=sum(w is not None for w in line.walls),
        check=run.check,
    )


def _most_dissipating(run) -> int:
    """The contact (1-based) that dissipated most, 0 for a wall, -1 if none did."""
    per, walls = np.asarray(run.contact_dissipation), np.asarray(run.wall_dissipation)
    best = float(per.max()) if per.size else 0.0
    if max(best, float(walls.max(initial=0.0))) <= 0.0:
        return -1
    return 0 if float(walls.max(initial=0.0)) > best else int(np.argmax(per)) + 1
