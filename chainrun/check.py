"""The conditioning check: which digits of a run's answer hold.

This module owns what the check runs, what it measures and what it calls holding.
Some answers are steered by rounding (cascades of near-simultaneous collisions,
disordered lines): there the final velocities move by far more than the step
tolerance when the tolerance changes, while a clean line's hold to about ``rtol``.
The check runs the same line a second time at another tolerance (``check_rtol``: a
tenth of the run's) and takes, for every ball, the difference of the two runs' final
and separation velocities: the *spread*. A spread measures how much of the number is
set by the model and how much by rounding and tolerance; it estimates the run's error
and does not bound it (the check run has an error of its own, about a tenth as large
where errors follow the tolerance: the run's is then about 1.1 times its spread, as
the guide's "Which digits hold" measures). A ball *holds* when both
its spreads are at most ``HOLD`` of the line's speed (``reference_speed``: the impact
speed, the largest initial speed; on a line at rest, its driven walls' speed), in the
run's units.

Spreads of a separation velocity: NaN in both runs (a ball that never separated)
agree, and have a spread of 0; NaN in one run only (the runs disagree on whether the
ball ever separated) has an infinite spread.

References
----------
DESIGN.md, "Rounding-steered answers": a second run at a tenth of the tolerance is the
plain measure of the sensitivity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Check", "ENERGY_DOUBT", "HOLD", "MIN_RTOL", "check_rtol", "energy_doubt",
           "reference_speed", "short", "spread"]

#: Smallest step tolerance a run may ask for (``solver.rtol``).
MIN_RTOL = 1e-15
#: A ball holds when its spreads are at most this share of the line's speed
#: (``reference_speed``).
HOLD = 1e-9


def reference_speed(line) -> tuple[float, str]:
    """The speed a line's spreads are measured against, and its name: a struck line's
    impact speed (its largest initial speed); for a line at rest, its driven walls'
    speed (``Drive.speed``: 2 pi f A, summed over a drive's sines); else 1, the unit
    of velocity."""
    impact = float(np.max(np.abs(line.velocity), initial=0.0))
    if impact > 0.0:
        return impact, "the impact speed"
    drive = sum(w.motion.speed for w in line.walls if w is not None and w.motion is not None)
    if drive > 0.0:
        return float(drive), "the drive's speed"
    return 1.0, "the unit of velocity"


#: A run whose energy balance is off by more than this share of its energy (``|dE|/E``,
#: ``Diagnostics.energy_error``) is reported (at the default rtol a balance holds to
#: about 1e-11), unless rounding alone can leave that much (``Diagnostics.energy_floor``,
#: a sum of magnitudes that rounding seldom reaches: a precompressed line shaken by 1e-6
#: of its static compressions stores 1e12 times the energy the drive moves).
ENERGY_DOUBT = 1e-6


def energy_doubt(energy_error: float, floor: float = 0.0) -> str | None:
    """A warning for a run whose energy balance is off by ``energy_error`` (of its
    energy), if that is over ``ENERGY_DOUBT`` and over the ``floor`` its rounding
    leaves; else None."""
    if not energy_error > max(ENERGY_DOUBT, floor):
        return None
    return (f"its energy balance is off by {energy_error:.1e} of its energy (|dE|/E, "
            f"over {short(ENERGY_DOUBT)}): its numbers may not hold; a smaller "
            f"solver.rtol, and --check, show which do")


def check_rtol(rtol: float) -> float:
    """The tolerance of the check of a run at ``rtol``: ``rtol / 10``, or ``10 rtol``
    where a tenth would be below ``MIN_RTOL``.

    A tenth of the tolerance makes the check run about ten times more accurate, so the
    difference of the two runs is about the run's own error (or, for an answer steered
    by rounding, how far rounding moves it). Below ``MIN_RTOL`` the solver cannot go;
    clamping there would compare a run at 1e-15 with itself (a spread of 0 that
    measures nothing), so the check runs ten times looser instead: the difference is
    then about the looser run's error, which bounds this run's from above.
    """
    low = rtol / 10.0
    if low >= MIN_RTOL * (1.0 - 1e-9):
        return max(low, MIN_RTOL)
    return rtol * 10.0


def short(x: float) -> str:
    """A tolerance as people write it, to three digits: ``1e-9``, ``1.5e-13`` (where
    ``format`` writes ``1e-09``)."""
    mantissa, exponent = f"{x:.2e}".split("e")
    return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"


def spread(a, b) -> np.ndarray:
    """``|a - b|`` elementwise, with 0 where both are NaN and inf where one is.

    Parameters
    ----------
    a, b : array_like, shape (N,)

    Returns
    -------
    ndarray, shape (N,)
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    out = np.abs(a - b)
    gone_a, gone_b = np.isnan(a), np.isnan(b)
    out[gone_a & gone_b] = 0.0
    out[gone_a ^ gone_b] = np.inf
    return out


@dataclass(frozen=True, eq=False)
class Check:
    """The check of one run: its second run's tolerance and outcome, and the spreads.

    Attributes
    ----------
    rtol : float
        The check run's tolerance (``check_rtol`` of the run's).
    outcome : str
        The check run's ``chainrun.solver.Outcome`` value; the spreads are NaN unless
        it succeeded (``"terminal"`` or ``"stop_time"``).
    message : str
        The check run's message (names a failure).
    wall_time : float
        Seconds the check run spent in the solver.
    final_velocity_spread, separation_velocity_spread : ndarray, shape (N,)
        ``spread`` of each ball's final and separation velocity between the two runs,
        in the run's units.
    """

    rtol: float
    outcome: str
    message: str
    wall_time: float
    final_velocity_spread: np.ndarray
    separation_velocity_spread: np.ndarray

    @classmethod
    def between(cls, run, check, rtol: float, units: str = "paper") -> "Check":
        """The check of ``run`` by ``check``, a run of the same line at ``rtol``, its
        message in the run's ``units`` (``chainrun.units.run_message``).

        Parameters
        ----------
        run, check : chainrun.solver.Solution
        rtol : float
        units : str
        """
        from chainrun.units import run_message

        ok = check.outcome.ok
        n = len(run.final_velocity)
        nan = np.full(n, np.nan)
        return cls(
            rtol=float(rtol), outcome=check.outcome.value,
            message=run_message(check, units),
            wall_time=float(check.diagnostics.wall_time),
            final_velocity_spread=(spread(run.final_velocity, check.final_velocity)
                                   if ok else nan),
            separation_velocity_spread=(spread(run.separation_velocity,
                                               check.separation_velocity) if ok else nan.copy()),
        )

    @property
    def ok(self) -> bool:
        """Whether the check run succeeded, so that the spreads are known."""
        return self.outcome in ("terminal", "stop_time")

    @property
    def ball_spread(self) -> np.ndarray:
        """Each ball's larger spread (final or separation velocity), shape (N,)."""
        return np.fmax(self.final_velocity_spread, self.separation_velocity_spread)

    def holding(self, speed: float) -> int:
        """Balls whose spreads are both at most ``HOLD * speed`` (0 if the check failed)."""
        return int(np.sum(self.ball_spread <= HOLD * speed))

    def largest(self) -> tuple[int, float]:
        """(ball number, from 1; its spread) of the ball with the largest spread."""
        spreads = self.ball_spread
        if spreads.size == 0 or np.all(np.isnan(spreads)):
            return 0, math.nan
        i = int(np.nanargmax(spreads))
        return i + 1, float(spreads[i])

    def line(self, speed: float, name: str = "the impact speed") -> str:
        """One clause for a run's summary line, spreads relative to ``speed`` (called
        ``name``; ``reference_speed``).

        ``check (rtol 1e-13): 5 of 5 balls hold to 1e-9 of the impact speed, largest
        spread 6.1e-13 of it (ball 3)``
        """
        head = f"check (rtol {short(self.rtol)})"
        if not self.ok:
            return f"{head} failed ({self.outcome}): {self.message}"
        n = self.final_velocity_spread.size
        ball, largest = self.largest()
        relative = largest / speed if speed else largest
        return (f"{head}: {self.holding(speed)} of {n} balls hold to {short(HOLD)} of "
                f"{name}, largest spread {relative:.1e} of it (ball {ball})")
