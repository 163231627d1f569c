"""Pulse measurements: the first pulse a force sensor records, and the wave's speed.

This module owns what a pulse is and how it is measured, for any run with force
sensors (``output.sensors``) and for any force trace on a uniform time grid: the peak of
the first pulse, the time of that peak, its full width at half maximum, its arrival
time, and the speed of a wave fitted through several sensors' peak times.
``measure_pulses`` applies them to a run (``measure_sensors`` to its sensors' arrays);
``first_pulse``, ``parabola_peak``, ``wave_speed`` and ``contact_places`` are the pieces
(the gallery's recipes use them too).

Definitions (every quantity in the run's own units):

- the *baseline* of a trace is its first sample (0 for a contact at rest, the static
  force F0 of a precompressed chain), and its *rise* the force above it;
- the *first pulse* of a trace is the first stretch of samples whose rise exceeds half
  the trace's largest rise, and its *peak* the largest sample of that stretch, refined by
  the parabola through that sample and its two neighbours. A later pulse (a reflected
  wave, a second solitary wave) is not measured, unless it is more than twice as high as
  the first (``detect`` sets that fraction);
- the *peak force* is the refined largest value, baseline included, and the *peak time*
  its time;
- the *width* (FWHM) is the time between the crossings of half-way between the baseline
  and the peak, on the rising edge and on the falling edge, each interpolated linearly
  between the two samples about it;
- the *arrival time* is the time the rising edge crosses a fraction ``arrival`` (0.1 by
  default) of the way from the baseline to the peak, interpolated likewise;
- a crossing interpolated linearly between samples ``h`` apart misses the trace by
  ``f''/2 (t - t_a)(t_b - t)``, at most ``h^2 |f''| / 8``, which along the edge's slope
  ``f' ~ (f_b - f_a) / h`` is a time of ``h |d2f| / (8 |f_b - f_a|)``: a fraction of the
  sampling interval set by the trace's second difference ``d2f`` beside the crossing
  (the larger of the two there). That is each crossing's *error*, the arrival's, and the
  sum of two the width's; the peak the half level is taken from errs by a higher power
  of ``h`` (the parabola is exact to second order), which moves the crossings less;
- a trace whose rise never exceeds ``min_rise`` has no pulse, and a pulse cut off by the
  ends of the samples (its peak at the first or last sample, or a crossing outside them)
  leaves the numbers it cannot give as NaN: a sensor the wave never reaches, or reaches
  as the run ends, gives NaN, not an error;
- a wave's *speed* is the least-squares slope of the positions of the contacts measured
  against their peak times, with its standard uncertainty from the fit's residuals.
  Where the sensors saw waves travelling both ways (a line struck from both ends: a
  sensor with a pulse on both contacts knows which way its wave went), each wave is
  fitted alone, through the sensors that saw it go its way: one line through both
  would be neither's speed.

A sensor ball has two contacts, side 0 towards ball 1 and side 1 away from it. The
wave arrives through one and leaves through the other; the *sensor's pulse* is that of
the contact it leaves through: of the sides whose trace has a pulse, the one whose pulse
starts later (side 1 if they tie). A solitary wave presses both contacts alike, each to
its largest contact force between two beads (0.63955 in the paper's units for the wave
of one striker; the paper prints 0.640). The sensor's *mean force*, the mean of its two contact forces, is what
a piezo sensor embedded in the bead measures; its peak is lower, the two contacts
peaking at different times.

References
----------
.. [1] E. J. Hinch and S. Saint-Jean, "The fragmentation of a line of balls by an
   impact", Proc. R. Soc. Lond. A 455, 3201-3220 (1999), section 5a: the solitary wave
   of one striker, its speed 0.841 and peak force 0.640.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from chainrun.errors import ChainrunError
from chainrun.store import RunData, read_run

__all__ = ["Pulse", "Pulses", "WaveSpeed", "contact_places", "first_pulse", "measure_pulses",
           "measure_sensors", "parabola_peak", "pulsed", "wave_speed"]

_NAN = math.nan


@dataclass(frozen=True)
class Pulse:
    """The first pulse of one force trace (NaN where it cannot be measured).

    Attributes
    ----------
    peak : float
        Its largest force, baseline included.
    peak_time : float
    width : float
        Full width at half maximum (half-way between the baseline and the peak).
    arrival_time : float
        When its rising edge crosses the ``arrival`` fraction from baseline to peak.
    onset : float
        The time of the pulse's first sample (the first whose rise exceeds ``detect`` of
        the largest): known even for a pulse cut off before its peak; NaN without one.
    width_error, arrival_error : float
        What the linear interpolation between samples can miss of the width and the
        arrival time (the module's docstring): a fraction of the sampling interval.
    """

    peak: float
    peak_time: float
    width: float
    arrival_time: float
    onset: float
    width_error: float = _NAN
    arrival_error: float = _NAN


_NO_PULSE = Pulse(_NAN, _NAN, _NAN, _NAN, _NAN)


@dataclass(frozen=True)
class WaveSpeed:
    """A wave's speed fitted through ``points`` (position, time) pairs.

    Attributes
    ----------
    value : float
        The least-squares slope of position against time (NaN with fewer than two
        points); positive for a wave travelling towards ball N.
    error : float
        Its standard uncertainty, ``sqrt(sum(r^2) / (points - 2) / sum((t - mean t)^2))``
        from the residuals r of the positions; NaN with two points, through which the
        line passes exactly, leaving no residual to estimate it from.
    points : int
    """

    value: float
    error: float
    points: int


@dataclass(frozen=True)
class Pulses:
    """The first pulse at each force sensor of a run, and the wave's speed.

    Every value is in the run's units (``units``: the paper's, or SI: N, s, m/s).

    Attributes
    ----------
    units : str
        ``"paper"`` or ``"si"``.
    balls : ndarray of int, shape (S,)
        The sensor balls (1..N).
    side : ndarray of int, shape (S,)
        The contact each sensor's pulse was measured on, the one the wave leaves
        through: 0 towards ball 1, 1 away from it.
    peak_force, peak_time, width, arrival_time : ndarray, shape (S,)
        That contact's first pulse (see ``Pulse``).
    width_error, arrival_error : ndarray, shape (S,)
        What the sampling leaves uncertain of each width and arrival time (see
        ``Pulse``); None where not measured.
    on_wall : ndarray of bool, shape (S,)
        Whether the contact measured is a wall's (an end ball's, towards its wall): the
        force on the wall as the wave reflects there, which the wave's speed is not
        fitted through; None where not known.
    peak_mean_force : ndarray, shape (S,)
        The peak of the first pulse of the sensor's mean force (the mean of its two
        contact forces: what a sensor embedded in the ball measures).
    speed : WaveSpeed
        Balls per unit time: the fit of the measured contacts' positions, in balls
        (the contact of balls b and b + 1 at b + 1/2), against their peak times;
        positive for a wave travelling towards ball N. Where the sensors saw waves
        going both ways, the fit of the one towards ball N alone.
    speed_si : WaveSpeed or None
        m/s, for a run of spheres with diameters: the same fit with the positions in
        metres, from the centre-to-centre distances (the radii plus the gaps); a
        contact sits in the middle of its gap. None otherwise.
    backward_speed, backward_speed_si : WaveSpeed, WaveSpeed or None
        Where the sensors saw waves going both ways, the same for the wave towards
        ball 1 (a negative slope); otherwise NaN with no points.
    arrival : float
        The fraction of the rise that defines the arrival time.
    """

    units: str
    balls: np.ndarray
    side: np.ndarray
    peak_force: np.ndarray
    peak_time: np.ndarray
    width: np.ndarray
    arrival_time: np.ndarray
    peak_mean_force: np.ndarray
    speed: WaveSpeed
    speed_si: WaveSpeed | None
    arrival: float
    backward_speed: WaveSpeed = WaveSpeed(_NAN, _NAN, 0)
    backward_speed_si: WaveSpeed | None = None
    width_error: np.ndarray | None = None
    arrival_error: np.ndarray | None = None
    on_wall: np.ndarray | None = None


def parabola_peak(t, y, i: int) -> tuple[float, float]:
    """The vertex of the parabola through samples ``i - 1, i, i + 1`` of equally spaced
    ``(t, y)``: ``(t_peak, y_peak)``."""
    y0, y1, y2 = float(y[i - 1]), float(y[i]), float(y[i + 1])
    h = float(t[i + 1] - t[i])
    denom = y0 - 2.0 * y1 + y2
    if denom == 0.0:
        return float(t[i]), y1
    s = 0.5 * (y0 - y2) / denom
    return float(t[i]) + s * h, y1 - 0.25 * (y0 - y2) * s


def _crossing(t: np.ndarray, f: np.ndarray, level: float, i: int,
              back: bool) -> tuple[float, float]:
    """Where ``f`` first falls to ``level`` going from sample ``i`` backwards (``back``)
    or forwards, interpolated linearly, and what the interpolation can miss of it
    (the module's docstring); NaN, NaN if it does not fall so within the samples."""
    if back:
        below = np.flatnonzero(f[:i] <= level)
        if not below.size:
            return _NAN, _NAN
        a = int(below[-1])
        b = a + 1
    else:
        below = np.flatnonzero(f[i + 1:] <= level)
        if not below.size:
            return _NAN, _NAN
        b = i + 1 + int(below[0])
        a = b - 1
    h, rise = float(t[b] - t[a]), float(f[b] - f[a])
    # the second differences beside the crossing, where the samples have them
    bends = [abs(float(f[j - 1] - 2.0 * f[j] + f[j + 1])) for j in (a, b)
             if 0 < j < f.size - 1]
    error = h * max(bends) / (8.0 * abs(rise)) if bends else _NAN
    return float(t[a] + (level - f[a]) / rise * h), error


def first_pulse(t, f, baseline: float | None = None, *, arrival: float = 0.1,
                detect: float = 0.5, min_rise: float = 0.0) -> Pulse:
    """The first pulse of a force trace: its peak, peak time, width and arrival time.

    See the module's docstring for the definitions.

    Parameters
    ----------
    t, f : ndarray, shape (M,)
        Equally spaced sample times and the force at each.
    baseline : float, optional
        The force without the pulse; ``f[0]`` unless given.
    arrival : float
        The fraction of the way from the baseline to the peak that defines the arrival.
    detect : float
        A pulse is a stretch whose rise exceeds this fraction of the largest rise.
    min_rise : float
        A trace whose largest rise does not exceed this has no pulse.

    Returns
    -------
    Pulse
        All NaN without a pulse; NaN where the pulse is cut off by the ends of ``t``.
    """
    t = np.asarray(t, dtype=float)
    f = np.asarray(f, dtype=float)
    if f.size < 3:
        return _NO_PULSE
    base = float(f[0]) if baseline is None else float(baseline)
    top = float(f.max())
    if not top - base > min_rise:
        return _NO_PULSE
    level = base + detect * (top - base)
    start = int(np.flatnonzero(f > level)[0])
    below = np.flatnonzero(f[start:] <= level)
    stop = start + (int(below[0]) if below.size else f.size - start)
    i = start + int(np.argmax(f[start:stop]))
    onset = float(t[start])
    if i == 0 or i == f.size - 1:   # the peak is not within the samples
        return Pulse(_NAN, _NAN, _NAN, _NAN, onset)
    t_peak, peak = parabola_peak(t, f, i)
    half = base + 0.5 * (peak - base)
    up, up_error = _crossing(t, f, half, i, back=True)
    down, down_error = _crossing(t, f, half, i, back=False)
    came, came_error = _crossing(t, f, base + arrival * (peak - base), i, back=True)
    return Pulse(peak, t_peak, down - up, came, onset, up_error + down_error, came_error)


def wave_speed(positions, times) -> WaveSpeed:
    """Least-squares slope of ``positions`` against ``times``, with its uncertainty.

    Parameters
    ----------
    positions, times : ndarray, shape (P,)
        Where and when the wave passed; pairs with a NaN are left out.

    Returns
    -------
    WaveSpeed
    """
    x = np.asarray(positions, dtype=float)
    t = np.asarray(times, dtype=float)
    ok = np.isfinite(x) & np.isfinite(t)
    x, t = x[ok], t[ok]
    if x.size < 2 or np.ptp(t) == 0.0:
        return WaveSpeed(_NAN, _NAN, int(x.size))
    if x.size == 2:
        return WaveSpeed(float(np.polyfit(t, x, 1)[0]), _NAN, 2)
    # cov=True scales the covariance by the residuals' sum of squares over (P - 2)
    p, cov = np.polyfit(t, x, 1, cov=True)
    return WaveSpeed(float(p[0]), float(math.sqrt(cov[0, 0])), int(x.size))


def contact_places(diameter=None, gap=None, wall_gap=(0.0, 0.0)) -> np.ndarray:
    """Where each contact of a line of spheres is, in metres, at the start.

    Ball 1's centre is at 0, each centre the two radii plus their gap beyond the one
    before, and a contact sits in the middle of its gap.

    Parameters
    ----------
    diameter : ndarray, shape (N,)
    gap : ndarray, shape (N - 1,)
        The gap of each contact (< 0: an overlap).
    wall_gap : (float, float)
        The left and right walls' gaps (0 where there is no wall).

    Returns
    -------
    ndarray, shape (N + 1,)
        Entry j is the contact between balls j and j + 1 (1-based; 0 and N are the
        walls', or where they would be).
    """
    r = 0.5 * np.asarray(diameter, dtype=float)
    g = np.concatenate([[wall_gap[0]], np.asarray(gap, dtype=float), [wall_gap[1]]])
    centre = np.concatenate([[0.0], np.cumsum(r[:-1] + r[1:] + g[1:-1])])
    # contact j is half its gap left of ball j + 1's left surface; the right wall's,
    # half its gap right of ball N's right surface
    return np.concatenate([centre - r - 0.5 * g[:-1], [centre[-1] + r[-1] + 0.5 * g[-1]]])


def pulsed(run) -> bool:
    """Whether a run's force sensors saw pulses (``chainrun.store.RunData``): it has
    sensors, and nothing drives its line (a driven line's sensors see its steady
    response: ``chainrun.analysis.transmission``)."""
    return bool(run.sensor_balls.size) and not run.line.is_driven


def measure_pulses(run, *, arrival: float = 0.1, min_rise: float | None = None) -> Pulses:
    """Measure the first pulse at each force sensor of a run, and the wave's speed.

    Per sensor ball: the peak contact force, its time, the width (FWHM) and the
    arrival time of the first pulse of the contact the wave leaves the ball through,
    and the peak of the ball's mean force; with two or more sensors the wave's speed,
    fitted through those contacts' peak times (the module's docstring defines each).

    Parameters
    ----------
    run : chainrun.store.RunData or path
        A run with force sensors, or its run file.
    arrival : float
        The arrival time is when a pulse's rising edge crosses this fraction of the way
        from the baseline to the peak, in (0, 1).
    min_rise : float, optional
        Traces that never rise more than this above their first sample have no pulse
        (NaN); default 1e-9 of the line's force scale (``model["scales"]["force"]``,
        1 in the paper's units), well above the forces ahead of a wave's front.

    Returns
    -------
    Pulses

    Raises
    ------
    ChainrunError
        For a run without force sensors, or an ``arrival`` outside (0, 1).
    """
    if not isinstance(run, RunData):
        run = read_run(run)
    model = run.model or {}
    walls = model.get("walls") or {}
    if not run.sensor_balls.size:
        raise ChainrunError(f"{run.path}: no force sensors in this run; give "
                            "output.sensors and output.sensor_dt to record them")
    if min_rise is None:
        min_rise = 1e-9 * float((model.get("scales") or {}).get("force", 1.0))
    return measure_sensors(
        run.sensor_time, run.sensor_force, run.sensor_balls, units=run.units,
        diameter=model.get("diameter"), gap=model.get("gap"),
        wall_gap=tuple(walls.get(side, {}).get("gap", 0.0) for side in ("left", "right")),
        arrival=arrival, min_rise=min_rise, n=run.n,
        walls=tuple(side in walls for side in ("left", "right")))


def measure_sensors(time, force, balls, *, units: str = "paper", diameter=None, gap=None,
                    wall_gap=(0.0, 0.0), arrival: float = 0.1,
                    min_rise: float = 1e-9, n: int | None = None,
                    walls: tuple[bool, bool] = (False, False)) -> Pulses:
    """``measure_pulses`` on the arrays of a run's force sensors.

    Parameters
    ----------
    time : ndarray, shape (M,)
        The sample times (equally spaced).
    force : ndarray, shape (M, S, 2)
        Each sensor's contact force towards ball 1 (side 0) and away from it (side 1).
    balls : ndarray of int, shape (S,)
        The sensor balls (1..N).
    units : str
        ``"paper"`` or ``"si"``: recorded in the result.
    diameter, gap, wall_gap
        For spheres, as ``contact_places`` takes them: the speed in m/s. Without
        ``diameter``, no speed in m/s.
    arrival, min_rise : float
        As ``measure_pulses`` takes them (``min_rise`` in force units).
    n : int, optional
        The number of balls, and ``walls`` whether the line has a left and a right
        wall: a sensor measuring its wall's contact (ball 1 towards the left wall,
        ball N towards the right) sees the wave reflect, not pass; the speed is not
        fitted through it (``Pulses.on_wall``).

    Returns
    -------
    Pulses

    Raises
    ------
    ChainrunError
        Without sensors, or for an ``arrival`` outside (0, 1).
    """
    if not 0.0 < arrival < 1.0:
        raise ChainrunError(f"arrival: must be within (0, 1), got {arrival!r}")
    balls = np.asarray(balls, dtype=np.int64)
    if not balls.size:
        raise ChainrunError("no force sensors; give output.sensors and output.sensor_dt "
                            "to record them")
    t, force = np.asarray(time, dtype=float), np.asarray(force, dtype=float)

    def measure(trace) -> Pulse:
        return first_pulse(t, trace, arrival=arrival, min_rise=min_rise)

    sides = [[measure(force[:, s, side]) for side in (0, 1)] for s in range(balls.size)]
    side = np.array([_leaving_side(pair) for pair in sides], dtype=np.int64)
    chosen = [pair[k] for pair, k in zip(sides, side)]
    mean = [measure(force[:, s, :].mean(axis=1)) for s in range(balls.size)]

    peak_time = np.array([p.peak_time for p in chosen])
    where = balls - 1 + side   # each measured contact: j joins balls j and j + 1
    on_wall = (where == 0) & walls[0]
    if n is not None and walls[1]:
        on_wall |= where == n
    places = None if diameter is None else contact_places(diameter, gap, wall_gap)[where]

    def speeds(used) -> tuple[WaveSpeed, WaveSpeed | None]:
        """The fits through the sensors ``used`` (a wall's contact never)."""
        times = np.where(used & ~on_wall, peak_time, _NAN)
        return (wave_speed(where + 0.5, times),
                None if places is None else wave_speed(places, times))

    # a sensor whose two contacts both had a pulse knows its wave's way (an end ball,
    # or a ball the wave stops at, has one: its side says nothing of the way)
    known = np.array([all(math.isfinite(q.onset) for q in pair) for pair in sides], bool)
    if np.any(known & (side == 1)) and np.any(known & (side == 0)):
        (speed, speed_si), (back, back_si) = speeds(known & (side == 1)), \
            speeds(known & (side == 0))
    else:
        (speed, speed_si), back, back_si = speeds(True), WaveSpeed(_NAN, _NAN, 0), None
    return Pulses(
        units=units, balls=balls, side=side,
        peak_force=np.array([p.peak for p in chosen]), peak_time=peak_time,
        width=np.array([p.width for p in chosen]),
        arrival_time=np.array([p.arrival_time for p in chosen]),
        peak_mean_force=np.array([p.peak for p in mean]),
        speed=speed, speed_si=speed_si, arrival=float(arrival),
        backward_speed=back, backward_speed_si=back_si,
        width_error=np.array([p.width_error for p in chosen]),
        arrival_error=np.array([p.arrival_error for p in chosen]),
        on_wall=on_wall)


def _leaving_side(pair: list[Pulse]) -> int:
    """The side the wave leaves through: of the sides with a pulse, the one whose pulse
    starts later (its ``onset``, known even for a pulse cut off before its peak);
    side 1 on a tie or without a pulse."""
    t0, t1 = (-math.inf if math.isnan(p.onset) else p.onset for p in pair)
    return 0 if t0 > t1 else 1
