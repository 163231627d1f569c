"""A run at a glance: what ``chainrun info`` prints, as numbers.

Read from a run file only (``chainrun.store.RunData``), in the conventions of
``derived``: a ball *rebounds* when its final velocity is negative, is *ejected* when it
moves forward faster than ``SIGNIFICANT`` (1% of the impact velocity), and is *left
behind* otherwise; energies are shares of the impact energy K/2.
"""

from __future__ import annotations

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


def summarize(run) -> RunSummary:
    """The summary of a run (``chainrun.store.RunData``)."""
    v = np.asarray(run.final_velocity, dtype=float)
    k = run.k
    impact = 0.5 * k
    back, ahead = v < 0.0, v > SIGNIFICANT
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
    )
