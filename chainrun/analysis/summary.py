"""A run at a glance: what ``chainrun info`` prints, as numbers.

Read from a run file only (``chainrun.store.RunData``), in the conventions of
``derived``: a ball *rebounds* when its final velocity is negative, is *ejected* when it
moves forward faster than ``SIGNIFICANT`` (1% of the impact velocity: of the fastest
initial speed, for a general line), and is *left behind* otherwise; energies are shares
of the impact energy K/2 (the paper's line only).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from chainrun.analysis.derived import SIGNIFICANT
from chainrun.solver import EventKind
from chainrun.solver.physics import kinetic_energy, potential_energy

__all__ = ["RunSummary", "law_name", "summarize"]


def law_name(alpha: float) -> str:
    """``linear``, ``Hertz`` or ``power alpha`` for the contact exponent."""
    if alpha == 1.0:
        return "linear"
    if alpha == 1.5:
        return "Hertz"
    return f"power {alpha:g}"


@dataclass(frozen=True)
class RunSummary:
    """The numbers of one run that a person reads first.

    ``fastest`` and ``slowest`` are (ball number, 1-based; final velocity).
    ``events`` counts the logged events by ``EventKind`` name. ``energy`` holds the
    shares of the impact energy K/2 carried at the end by the rebounding, ejected and
    left-behind balls (kinetic), and ``"contacts"`` the share still stored in contacts.
    """

    path: str
    creator_version: str
    created: str
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
    closed_form: int  # isolated collisions taken whole (0 in older files)
    wall_time: float
    momentum_error: float
    energy_error: float
    energy_correction: float
    fastest: tuple[int, float]
    slowest: tuple[int, float]
    rebounding: int
    ejected: int
    left_behind: int
    energy: dict[str, float]
    snapshots: int
    sensors: int
    samples: int
    first_time: float
    last_time: float
    file_bytes: int
    model: str = ""  # the general line in brief ("" for the paper's line)
    dissipated: float = 0.0  # energy the damping took (0: elastic)
    dissipated_share: float = 0.0  # ... as a share of the initial kinetic energy
    dissipating: int = 0  # the contact (1-based) that dissipated most; 0: a wall or none


def _span(a: np.ndarray, unit: str) -> str:
    """``"1"``, or ``"0.5 ... 2 kg"`` for values that differ."""
    unit = f" {unit}" if unit and unit != "1" else ""
    if a.size == 0:
        return "none"
    lo, hi = float(np.min(a)), float(np.max(a))
    return f"{lo:.4g}{unit}" if lo == hi else f"{lo:.4g} ... {hi:.4g}{unit}"


def describe_model(model: dict | None) -> str:
    """A line for a person: the masses, contacts, walls, forces and units of a run's
    line (``RunData.model``); "" for the paper's line, which N, K and alpha say whole."""
    if not model:
        return ""
    si = model["units"] == "si"
    mass, stiffness, alpha = model["mass"], model["stiffness"], model["alpha"]
    paper = (not si and np.all(mass == 1.0) and np.all(stiffness == 1.0)
             and not np.any(model["gap"]) and not np.any(model["force"])
             and not model["walls"] and np.all(np.isin(model["velocity"], (0.0, 1.0)))
             and np.all(alpha == alpha[:1]) and not np.any(model["damping"]))
    if paper:
        return ""
    parts = [f"masses {_span(mass, 'kg' if si else '')}",
             f"stiffness {_span(stiffness, 'N/m^alpha' if si else '')}",
             f"alpha {_span(alpha, '')}"]
    if np.any(model["gap"]):
        parts.append(f"gaps {_span(model['gap'], 'm' if si else '')}")
    if np.any(model["force"]):
        parts.append(f"forces on {int(np.count_nonzero(model['force']))} balls")
    if np.any(model["damping"]):
        parts.append(f"damping {_span(model['damping'], '')} "
                     f"(exponent {_span(model['damping_exponent'], '')})")
    walls = [f"{side} (stiffness {w['stiffness']:.4g}, alpha {w['alpha']:g}, gap {w['gap']:g}"
             + (f", damping {w['damping']:.4g}" if w.get("damping") else "") + ")"
             for side, w in model["walls"].items()]
    parts.append("walls: " + (", ".join(walls) if walls else "none"))
    v = model["velocity"]
    parts.append(f"initial speeds {_span(v[v != 0], 'm/s' if si else '')}")
    return "; ".join(parts) + ("; SI units" if si else "; paper units")


def summarize(run) -> RunSummary:
    """The summary of a run (``chainrun.store.RunData``)."""
    v = np.asarray(run.final_velocity, dtype=float)
    k = run.k
    impact = 0.5 * k
    # "ejected": faster than 1% of the impact velocity, the fastest initial speed of a
    # general line (in its units)
    speed = (float(np.max(np.abs(run.model["velocity"]))) if run.model is not None
             else 1.0) or 1.0
    back, ahead = v < 0.0, v > SIGNIFICANT * speed
    behind = ~back & ~ahead
    kinetic = {name: float(kinetic_energy(v[mask])) / impact
               for name, mask in (("rebound", back), ("ejected", ahead),
                                  ("left behind", behind))}
    stored = float(potential_energy(run.final_position, run.alpha)) / impact
    kinds = np.asarray(run.event_kind)
    d = run.diagnostics
    return RunSummary(
        path=str(run.path),
        creator_version=run.creator_version,
        created=run.created,
        n=run.n,
        k=k,
        alpha=run.alpha,
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
        fastest=(int(np.argmax(v)) + 1, float(v.max())),
        slowest=(int(np.argmin(v)) + 1, float(v.min())),
        rebounding=int(back.sum()),
        ejected=int(ahead.sum()),
        left_behind=int(behind.sum()),
        energy={**kinetic, "contacts": stored},
        snapshots=int(run.times.size),
        sensors=int(run.sensor_balls.size),
        samples=int(run.sensor_time.size),
        first_time=float(run.times[0]) if run.times.size else float("nan"),
        last_time=float(run.times[-1]) if run.times.size else float("nan"),
        file_bytes=os.path.getsize(run.path),
        model=describe_model(getattr(run, "model", None)),
        **_dissipation(run),
    )


def _dissipation(run) -> dict:
    """What the damping took, as a share of the initial kinetic energy, and where."""
    energy = float(getattr(run, "dissipated_energy", 0.0))
    if not energy:
        return {}
    model = run.model
    initial = 0.5 * float(np.sum(model["mass"] * model["velocity"] ** 2))
    per = run.contact_dissipation
    most = int(np.argmax(per)) + 1 if per is not None and per.size else 0
    if per is not None and per.size and np.max(run.wall_dissipation) > per[most - 1]:
        most = 0
    return dict(dissipated=energy, dissipated_share=energy / initial if initial else math.nan,
                dissipating=most)
