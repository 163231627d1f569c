"""Measurements on runs: rebound and ejection, fits, and trains of solitary waves.

This module owns the definitions of the derived quantities the paper reports, as pure
functions of arrays (and of ``chainrun.store.RunData``, which they only read). The
conventions, used everywhere:

- a ball *rebounds* when its final velocity is negative; its *rebound velocity* is that
  final velocity (for the rebounding balls it equals the velocity at which the ball last
  lost contact: nothing catches them afterwards);
- a velocity is *significant* when its magnitude exceeds 1% of the impact velocity (the
  paper's threshold in sections 3 and 5a);
- energy shares are fractions of the impact energy (``physics.impact_energy``: K/2 on
  the paper's line); energies and momenta are the line's own, from its masses and
  contacts (``chainrun.solver.physics``);
- a *wave* passing ball m is a peak of its velocity history v_m(t); its arrival time and
  peak value are refined by a parabola through the three samples around the peak.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from chainrun.solver.physics import (
    line_contact_forces, line_kinetic_energy, line_momentum, line_potential_energy,
)

__all__ = [
    "SIGNIFICANT",
    "SolitaryWave",
    "WaveTrain",
    "count_significant",
    "exponential_fit",
    "impact_speed",
    "loglog_slope",
    "nearest_snapshots",
    "polynomial_extrapolation",
    "position_at_separation",
    "power_series_fit",
    "rebound_energy_share",
    "rebound_momentum",
    "refined_peaks",
    "solitary_wave",
    "wave_train",
]

#: A velocity is significant above 1% of the impact velocity (paper sections 3 and 5a).
SIGNIFICANT = 0.01


def impact_speed(run) -> float:
    """The largest initial speed of a run's line: the impact velocity of its strikers."""
    return float(np.max(np.abs(run.line.velocity)))


def count_significant(v, sign: int, speed: float) -> int:
    """Number of balls moving backwards (sign -1) or forwards faster than
    ``SIGNIFICANT`` of the impact ``speed``."""
    v = np.asarray(v, dtype=float)
    return int(np.sum(sign * v > SIGNIFICANT * speed))


def rebound_energy_share(v, mass, impact_energy: float) -> float:
    """Kinetic energy of the rebounding balls (v < 0), of masses ``mass`` (one per
    ball), as a share of the ``impact_energy``."""
    v = np.asarray(v, dtype=float)
    back = v < 0
    return float(line_kinetic_energy(v[back], np.broadcast_to(mass, v.shape)[back])
                 / impact_energy)


def rebound_momentum(v, mass) -> float:
    """Total momentum of the rebounding balls (v < 0), of masses ``mass``."""
    v = np.asarray(v, dtype=float)
    back = v < 0
    return float(line_momentum(v[back], np.broadcast_to(mass, v.shape)[back]))


def loglog_slope(x, y) -> float:
    """Least-squares slope of ``log|y|`` against ``log x``."""
    return float(np.polyfit(np.log(np.asarray(x, float)), np.log(np.abs(np.asarray(y, float))),
                            1)[0])


def exponential_fit(n, y) -> tuple[float, float]:
    """``(a, b)`` of the least-squares fit ``log|y| = log a - b n``: ``|y| ~ a exp(-b n)``."""
    slope, intercept = np.polyfit(np.asarray(n, float), np.log(np.abs(np.asarray(y, float))), 1)
    return float(np.exp(intercept)), float(-slope)


def polynomial_extrapolation(x, y, degree: int = 1) -> float:
    """The least-squares polynomial in ``x`` through the points, evaluated at x = 0."""
    return float(np.polyval(np.polyfit(np.asarray(x, float), np.asarray(y, float), degree), 0.0))


def power_series_fit(n, y, powers) -> np.ndarray:
    """Coefficients ``c`` of ``y = c0 + sum_i c_i n^(-p_i)`` by least squares.

    Returns
    -------
    ndarray, shape (1 + len(powers),)
        ``c0`` (the limit n -> inf) first.
    """
    n = np.asarray(n, float)
    basis = np.column_stack([np.ones_like(n)] + [n ** (-p) for p in powers])
    return np.linalg.lstsq(basis, np.asarray(y, float), rcond=None)[0]


def position_at_separation(run) -> np.ndarray:
    """Displacement of each ball when it last lost contact, shape (N,) (NaN: never).

    A ball is free after its last separation, so this is the final displacement moved
    back along the final velocity to the separation time: exact, with no snapshot.
    """
    return run.final_position - run.final_velocity * (run.end_time - run.separation_time)


def nearest_snapshots(times, wanted) -> np.ndarray:
    """Index of the snapshot nearest to each wanted time."""
    times = np.asarray(times, float)
    return np.array([int(np.argmin(np.abs(times - t))) for t in np.atleast_1d(wanted)])


def refined_peaks(t, y, height: float) -> tuple[np.ndarray, np.ndarray]:
    """Local maxima of samples ``y(t)`` above ``height``, refined by a parabola.

    Parameters
    ----------
    t : ndarray, shape (T,)
        Equally spaced sample times.
    y : ndarray, shape (T,)
    height : float

    Returns
    -------
    times, values : ndarray, shape (P,)
        In time order.
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    i = np.flatnonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]) & (y[1:-1] > height)) + 1
    y0, y1, y2 = y[i - 1], y[i], y[i + 1]
    curvature = y0 - 2.0 * y1 + y2
    offset = np.where(curvature < 0, 0.5 * (y0 - y2) / np.where(curvature < 0, curvature, -1),
                      0.0)
    step = t[1] - t[0] if len(t) > 1 else 0.0
    return t[i] + offset * step, y1 - 0.25 * (y0 - y2) * offset


@dataclass(frozen=True)
class WaveTrain:
    """The solitary waves that pass a range of balls, one row per wave, fastest first.

    Attributes
    ----------
    balls : ndarray of int, shape (M,)
        Ball numbers (1-based) measured.
    arrival : ndarray, shape (W, M)
        Time at which each wave's velocity peak passes each ball.
    peak_velocity : ndarray, shape (W, M)
    plateau : ndarray, shape (W, M)
        Displacement of each ball after each wave has passed (and before the next
        arrives): the displacement at the smallest velocity in between.
    speed : ndarray, shape (W,)
        Balls per unit time, the least-squares slope of ball number against arrival.
    displacement : ndarray, shape (W,)
        The (additional) displacement each wave brings, median over the balls.
    peak : ndarray, shape (W,)
        Peak velocity of each wave, median over the balls.
    """

    balls: np.ndarray
    arrival: np.ndarray
    peak_velocity: np.ndarray
    plateau: np.ndarray
    speed: np.ndarray
    displacement: np.ndarray
    peak: np.ndarray


def wave_train(run, waves: int, balls: tuple[int, int], *, settle: float = 8.0,
               height: float = 0.02) -> WaveTrain:
    """Measure the first ``waves`` solitary waves passing balls ``balls[0]..balls[1]``.

    Parameters
    ----------
    run : RunData
        With snapshots dense enough to resolve each velocity pulse (a step of 0.1 is
        ample: a pulse lasts about 5 time units).
    waves : int
        Number of waves to measure (the fastest first).
    balls : (int, int)
        First and last ball (1-based, inclusive): where the waves have separated and
        the far end is not yet felt.
    settle : float
        After the last wave present, the plateau is looked for within this time.
    height : float
        Smallest velocity peak that counts as a wave.
    """
    t = np.asarray(run.times, float)
    x_all = np.asarray(run.positions)
    v_all = np.asarray(run.velocities)
    numbers = np.arange(balls[0], balls[1] + 1)
    arrival = np.full((waves, len(numbers)), np.nan)
    peak = np.full_like(arrival, np.nan)
    plateau = np.full_like(arrival, np.nan)
    for col, m in enumerate(numbers):
        v = v_all[:, m - 1]
        x = x_all[:, m - 1]
        times, values = refined_peaks(t, v, height)
        if len(times) < waves:
            raise ValueError(f"ball {m}: {len(times)} velocity peaks above {height}, "
                             f"expected {waves}")
        arrival[:, col] = times[:waves]
        peak[:, col] = values[:waves]
        for w in range(waves):
            start = t >= times[w]
            end = t <= (times[w + 1] if w + 1 < len(times) else times[w] + settle)
            window = np.flatnonzero(start & end)
            plateau[w, col] = x[window[np.argmin(np.abs(v[window]))]]
    speed = np.array([np.polyfit(arrival[w], numbers, 1)[0] for w in range(waves)])
    added = np.diff(np.vstack([np.zeros((1, len(numbers))), plateau]), axis=0)
    return WaveTrain(balls=numbers, arrival=arrival, peak_velocity=peak, plateau=plateau,
                     speed=speed, displacement=np.median(added, axis=1),
                     peak=np.median(peak, axis=1))


@dataclass(frozen=True)
class SolitaryWave:
    """Properties of a single steady solitary wave (one impacting ball).

    Attributes
    ----------
    speed, displacement, max_velocity, max_force : float
    momentum, energy : float
        Of the balls that have not yet separated for good, averaged over the window.
    kinetic_mean, kinetic_min, kinetic_max, potential_mean : float
        Energies of the wave over the window (their sum is ``energy``).
    width : float
        Mean number of balls of the wave (not yet separated for good) moving faster
        than 1% of the peak velocity.
    times : ndarray, shape (T,)
        The snapshot times of the window.
    kinetic, potential : ndarray, shape (T,)
    """

    speed: float
    displacement: float
    max_velocity: float
    max_force: float
    momentum: float
    energy: float
    kinetic_mean: float
    kinetic_min: float
    kinetic_max: float
    potential_mean: float
    width: float
    times: np.ndarray
    kinetic: np.ndarray
    potential: np.ndarray


def solitary_wave(run, window: tuple[float, float], balls: tuple[int, int]) -> SolitaryWave:
    """Measure the steady solitary wave of a K = 1 run, in its line's units.

    Parameters
    ----------
    run : RunData or Solution
        K = 1, with dense snapshots over ``window``.
    window : (float, float)
        Times over which the wave is steady (the averages run over it).
    balls : (int, int)
        Balls (1-based, inclusive) the wave passes in its steady state.
    """
    line = run.line
    sc = line.scales()  # the thresholds are in the paper's units of the line
    train = wave_train(run, 1, balls, settle=8.0 * sc.time, height=0.02 * sc.velocity)
    t = np.asarray(run.times, float)
    x = np.asarray(run.positions)
    v = np.asarray(run.velocities)
    force = line_contact_forces(x, line)
    forces = [refined_peaks(t, force[:, j - 1], 0.05 * sc.force)[1][0] for j in train.balls]
    sel = (t >= window[0]) & (t <= window[1])
    alive = run.separation_time[None, :] > t[sel][:, None]   # NaN (never) compares False
    alive |= np.isnan(run.separation_time)[None, :]
    vs = v[sel]
    kinetic = line_kinetic_energy(vs * alive, line.mass)
    potential = line_potential_energy(x[sel], line, t[sel])
    momentum = line_momentum(vs * alive, line.mass)
    width = np.mean(np.sum(alive & (np.abs(vs) > 0.01 * train.peak[0]), axis=1))
    sep = position_at_separation(run)
    return SolitaryWave(
        speed=float(train.speed[0]),
        displacement=float(np.median(sep[train.balls - 1])),
        max_velocity=float(train.peak[0]),
        max_force=float(np.median(forces)),
        momentum=float(np.mean(momentum)),
        energy=float(np.mean(kinetic + potential)),
        kinetic_mean=float(np.mean(kinetic)),
        kinetic_min=float(np.min(kinetic)),
        kinetic_max=float(np.max(kinetic)),
        potential_mean=float(np.mean(potential)),
        width=float(width),
        times=t[sel],
        kinetic=kinetic,
        potential=potential,
    )
