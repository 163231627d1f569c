"""A sweep's pulses against its swept key, with the power laws through them.

``pulse_sweep(runs, pulses, key)`` orders the runs of a sweep over one key by its
value and gathers, from each run's pulses (``chainrun.analysis.pulse.measure_pulses``),
the wave's speed (in m/s for a line of spheres, else in balls per unit time) with its
uncertainty, and each sensor's peak contact force and pulse width (FWHM). Where the
key's values are positive and span a decade or more, each curve carries the exponent of
the power law fitted through it (``derived.loglog_slope``) and the slopes between its
first and its last pair of runs, which differ where the points bend: a solitary wave's
speed goes as the impact speed to the 1/5 and its peak force to the 6/5, and on a
column under its weight the speed's slope rises towards 1/5 as the impacts outgrow the
static load. ``chainrun.plotting.pulses`` draws it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from chainrun.analysis.derived import loglog_slope

__all__ = ["Curve", "PulseSweep", "local_slopes", "power_law", "pulse_sweep"]

#: The span of the swept values over which the axes are logarithmic and a power law is
#: fitted: a decade, as in the views' other sweep figures.
DECADE = 10.0


def power_law(x, y) -> float:
    """The exponent of the power law y ~ x^p fitted through the points with x, y > 0
    (``derived.loglog_slope``); NaN with fewer than two such points of different x."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if np.count_nonzero(ok) < 2 or np.ptp(np.log(x[ok])) == 0.0:
        return math.nan
    return loglog_slope(x[ok], y[ok])


def local_slopes(x, y) -> np.ndarray:
    """The slopes of log y against log x between neighbouring points (in x's order)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    order = np.argsort(x)
    return np.diff(np.log(y[order])) / np.diff(np.log(x[order]))


@dataclass(frozen=True)
class Curve:
    """One measured quantity against the swept key: its ``values`` (one per run, in
    the key's order), their ``errors`` (None where not measured), the ``slope`` of the
    power law through them and the slopes between their ``first`` and ``last`` pair of
    runs (NaN where no power law is fitted, or where they differ by 0.005 or less:
    one power law describes the points)."""

    name: str
    values: np.ndarray
    errors: np.ndarray | None = None
    slope: float = math.nan
    first: float = math.nan
    last: float = math.nan


@dataclass(frozen=True)
class PulseSweep:
    """``x``, the swept ``key``'s values in order; ``log`` whether they span a decade
    (and the curves carry power laws); the ``speed`` curve (``si``: in m/s), and a curve
    per sensor (``balls``) of the peak contact ``force`` and the ``width``, each named by
    its ball (and the wall, for a sensor measuring a wall's contact)."""

    key: str
    units: str
    x: np.ndarray
    log: bool
    si: bool
    speed: Curve
    balls: np.ndarray
    force: list[Curve]
    width: list[Curve]


def _curve(name: str, x, values, log: bool, errors=None) -> Curve:
    values = np.asarray(values, dtype=float)
    if not log:
        return Curve(name, values, errors)
    local = local_slopes(x, values)
    local = local[np.isfinite(local)]
    bends = local.size > 1 and np.ptp(local) > 0.005
    return Curve(name, values, errors, power_law(x, values),
                 float(local[0]) if bends else math.nan,
                 float(local[-1]) if bends else math.nan)


def pulse_sweep(runs, pulses, key: str) -> PulseSweep:
    """The ``pulses`` (one per run of ``runs``, ``chainrun.store.RunData``) against the
    swept ``key`` (its values in the runs' ``overrides``); runs whose key is not a
    number are left out."""
    points = sorted((float(run.parameters.get("overrides", {})[key]), i)
                    for i, run in enumerate(runs)
                    if isinstance(run.parameters.get("overrides", {}).get(key), (int, float)))
    x = np.array([value for value, _ in points])
    chosen = [pulses[i] for _, i in points]
    log = bool(x.size > 1 and x.min() > 0 and x.max() >= DECADE * x.min())
    si = all(p.speed_si is not None for p in chosen)
    fits = [p.speed_si if si else p.speed for p in chosen]
    speed = _curve("fitted through the sensors", x, [f.value for f in fits], log,
                   np.array([f.error for f in fits]))
    balls = chosen[0].balls
    on_wall = (chosen[0].on_wall if chosen[0].on_wall is not None
               else np.zeros(balls.size, dtype=bool))
    names = [f"ball {ball}" + (", on the wall" if wall else "")
             for ball, wall in zip(balls, on_wall)]

    def curves(per_run) -> list[Curve]:
        table = np.array([np.asarray(v, dtype=float) for v in per_run])  # run x sensor
        return [_curve(names[i], x, table[:, i], log) for i in range(min(len(names),
                                                                         table.shape[1]))]

    return PulseSweep(key=key, units=runs[0].units, x=x, log=log, si=si, speed=speed,
                      balls=np.asarray(balls), force=curves([p.peak_force for p in chosen]),
                      width=curves([p.width for p in chosen]))
