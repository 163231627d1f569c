"""Transmission from a driven run: the steady response of force sensors to a wall's sine.

This module owns what a driven line transmits and how it is measured from the force
sensors of a run (``output.sensors``) whose wall moves by a sine
(``walls.<side>.motion``):

- the *window* is a whole number of drive periods ending at the last sensor sample.
  By default it is every whole period in the second half of the time after the
  drive's ramp: the first half lets the wave cross the line and the start's transient
  (which a smooth ramp over many periods keeps small) pass the sensors; ``start`` moves
  its beginning and ``periods`` takes that many periods at the end instead;
- over the window each sensor's mean force (what a piezo sensor in the ball measures)
  is fitted by least squares with

      F(t) = F_mean + sum_k a_k sin(2 pi k f t + phi_k),   k = 1 .. harmonics

  f the drive's frequency. Over whole periods the harmonics are orthogonal, so each
  ``a_k`` is what a discrete Fourier transform at k f would give, without its leakage
  from a window cut inside a period. ``phi_k``, in (-pi, pi], is the phase against
  ``sin(2 pi k f t)``, the drive's own clock (the wall moves by ``A sin(2 pi f t)``; a
  negative A is a phase of pi); the rms of what the fit leaves is ``residual``, the
  part of the signal that is not steady at f: the modes the start excited, and any
  other frequency;
- a sensor's response is *steady* where that residual is at most ``STEADY`` (a tenth)
  of its amplitude at f and the window holds at least ``MIN_PERIODS`` periods; deep in
  a stop band, or where the start's transient has not passed, the amplitude is the
  fit's reading of what is left of the transient, not a transmitted signal, and says
  little of the line's transmission;
- the *transmission* is each amplitude over the force the drive would put on a held
  ball, ``K_w |A|``: the drive's amplitude A times the linear stiffness ``K_w`` of the
  driven wall's contact at the static state (``chainrun.analysis.spectrum``). It is a
  property of the line and the drive alone: it needs no reference sensor, it does not
  inherit a reference sensor's own resonances, and the ratio of two sensors'
  transmissions is the ratio of their amplitudes. A line of springs between two
  walls, driven slowly, carries ``K_w |A| / (K_w sum_j 1/K_j)`` (the springs in
  series): 1/(N+1) of it for N equal balls and equal springs.

The linear spectrum of the line at rest (its normal modes and, for a periodic line,
its band edges) comes with the result, in the drive's frequency unit (Hz in SI), so a
transmission curve can be read against the bands: inside a gap or above the top band a
drive decays along the line, by ``cosh(mu) = omega^2 m / (2 K) - 1`` per ball above the
cut-off ``2 sqrt(K/m)`` of a uniform line.

``measure`` takes a run (its Dataset, ``chainrun.open_run``, or its file read by
``chainrun.store``), ``measure_sweep`` a sweep's runs (``chainrun.open_sweep``, or the
files read) and puts them along the drive's frequency: a transmission curve. ``fit_harmonics`` and ``fit_window`` are the pieces.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from chainrun.errors import ChainrunError
from chainrun.solver import Drive, Line, Wall
from chainrun.store import RunData
from chainrun.units import PAPER, UNITS

__all__ = ["HARMONICS", "MIN_PERIODS", "STEADY", "fit_harmonics", "fit_window", "measure", "measure_sweep"]

#: Harmonics fitted by default: the drive's frequency, and twice and three times it.
HARMONICS = 3
#: A response is steady where the fit's residual is at most this fraction of its
#: amplitude at the drive's frequency ...
STEADY = 0.1
#: ... over a window of at least this many periods.
MIN_PERIODS = 3
#: Periods count as whole within this fraction of one (rounding in the sample times).
_PERIOD_SLACK = 1e-9
#: Variables of the linear spectrum, the same on every run of a sweep of one line.
_SPECTRUM_VARS = ("mode_frequency", "band_bottom", "band_top")


def fit_harmonics(t, y, frequency: float, harmonics: int = HARMONICS):
    """The least-squares fit ``y = mean + sum_k a_k sin(2 pi k f t + phi_k)``.

    Parameters
    ----------
    t : ndarray, shape (M,)
        Sample times.
    y : ndarray, shape (M,) or (M, S)
        Samples, one column per signal.
    frequency : float
        f, in cycles per unit of ``t``.
    harmonics : int
        k = 1 .. harmonics.

    Returns
    -------
    mean : ndarray, shape () or (S,)
    amplitude, phase : ndarray, shape (harmonics,) or (harmonics, S)
        ``a_k >= 0`` and ``phi_k`` in (-pi, pi].
    residual : ndarray, shape () or (S,)
        The rms of the samples less the fit.
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    k = np.arange(1, harmonics + 1)
    theta = 2.0 * np.pi * frequency * np.outer(t, k)
    # columns: 1, sin(k theta) for each k, cos(k theta) for each k
    basis = np.hstack([np.ones((t.size, 1)), np.sin(theta), np.cos(theta)])
    coef, *_ = np.linalg.lstsq(basis, y, rcond=None)
    s, c = coef[1:harmonics + 1], coef[harmonics + 1:]
    # s sin + c cos = a sin(. + phi): a = hypot(s, c), phi = atan2(c, s)
    residual = np.sqrt(np.mean((y - basis @ coef) ** 2, axis=0))
    return coef[0], np.hypot(s, c), np.arctan2(c, s), residual


def fit_window(times, frequency: float, start: float, periods: int | None = None):
    """The window of whole drive periods that ends at the last sample time.

    Parameters
    ----------
    times : ndarray, shape (M,)
        Sample times, increasing.
    frequency : float
    start : float
        The window begins at or after this time (and the first sample).
    periods : int, optional
        Periods to take; by default as many as fit between ``start`` and the last
        sample.

    Returns
    -------
    (begin, end, periods) : (float, float, int)

    Raises
    ------
    ChainrunError
        If not one whole period fits, or ``periods`` do not.
    """
    end = float(times[-1])
    start = max(start, float(times[0]))  # (nothing to fit before the first sample)
    fit = math.floor((end - start) * frequency + _PERIOD_SLACK)
    if periods is None:
        periods = fit
    elif periods < 1:
        raise ChainrunError(f"periods: must be >= 1, got {periods}")
    elif periods > (end - float(times[0])) * frequency + _PERIOD_SLACK:
        raise ChainrunError(f"periods: {periods} periods of the drive are longer than the "
                            f"sensors' record ({end - float(times[0]):.6g})")
    if periods < 1:
        raise ChainrunError(f"not one whole period of the drive (1/f = {1.0 / frequency:.6g}) "
                            f"between t = {start:.6g} and the last sensor sample "
                            f"({end:.6g}): run longer (solver.t_end, output.sensor_end) "
                            "or give an earlier start")
    return end - periods / frequency, end, int(periods)


def _driven_wall(line: Line) -> tuple[int, float, float, float]:
    """(wall index, frequency, amplitude, ramp) of the line's one wall moving by one
    sine, or a ChainrunError saying what is missing."""
    moving = [(w, wall.motion) for w, wall in enumerate((line.left, line.right))
              if wall is not None and wall.motion is not None]
    if not moving:
        raise ChainrunError("transmission: no wall moves by a sine in this run; give "
                            "walls.left.motion = {amplitude, frequency, ramp}")
    if len(moving) != 1 or len(moving[0][1].sines) != 1:
        raise ChainrunError("transmission: needs one wall moving by one sine; this run's "
                            "walls move by " + ", ".join(
                                "a file's samples" if m.times is not None
                                else f"{len(m.sines)} sine(s)" for _, m in moving))
    w, motion = moving[0]
    sine = motion.sines[0]
    return w, sine.frequency, sine.amplitude, sine.ramp


def _line(ds) -> Line:
    """The line of a run's Dataset (``chainrun.open_run``), its walls' motions
    rebuilt from their sines (``wall_motion_*``)."""
    n = ds.sizes["ball"]
    walls = {}
    for side in ("left", "right"):
        wall = ds.sel(wall=side)
        if not np.isfinite(float(wall["wall_stiffness"])):
            continue
        motion = None
        if "wall_motion_frequency" in ds:
            sines = [dict(amplitude=float(a), frequency=float(f), ramp=float(r))
                     for a, f, r in zip(wall["wall_motion_amplitude"].values,
                                        wall["wall_motion_frequency"].values,
                                        wall["wall_motion_ramp"].values) if np.isfinite(f)]
            motion = Drive.of_sines(sines) if sines else None
        walls[side] = Wall(**{key: float(wall[f"wall_{key}"]) for key in (
            "stiffness", "alpha", "gap", "damping", "damping_exponent")}, motion=motion)
    return Line(mass=ds["mass"].values, stiffness=ds["stiffness"].values,
                alpha=ds["alpha"].values, gap=ds["gap"].values, velocity=np.zeros(n),
                force=ds["force"].values, position=ds["initial_position"].values,
                damping=ds["damping"].values, damping_exponent=ds["damping_exponent"].values,
                **walls)


def _unit(quantity: str, units: str) -> str:
    return UNITS[units][quantity] if units == "si" else PAPER


def _sensors(run):
    """(times (M,), mean forces (M, S), sensor balls (S,), line, units, attrs) of a
    run's Dataset or ``chainrun.store.RunData``; a sweep's NaN padding dropped."""
    if isinstance(run, RunData):
        if run.sensor_balls.size == 0:
            return None
        return (run.sensor_time, run.sensor_force.mean(axis=2), run.sensor_balls, run.line,
                run.units, {key: run.parameters.get(key, "") for key in ("experiment",
                                                                          "run_id")})
    if "sensor_mean_force" not in run:
        return None
    force = run["sensor_mean_force"].transpose("sample", "sensor").values
    kept = np.isfinite(force).all(axis=1)
    return (run["sample"].values[kept], force[kept], run["sensor"].values, _line(run),
            "si" if run.attrs.get("units") == "SI" else "paper",
            {key: run.attrs.get(key, "") for key in ("experiment", "run_id")})


def measure(run, *, harmonics: int = HARMONICS, start: float | None = None,
            periods: int | None = None) -> xr.Dataset:
    """The steady response of each force sensor of a driven run, and its transmission.

    Parameters
    ----------
    run : xarray.Dataset or chainrun.store.RunData
        A run (``chainrun.open_run``, or a run file read by ``chainrun.store``) with
        force sensors, one of whose walls moves by one sine.
    harmonics : int
        The drive's frequency f and its multiples up to ``harmonics`` f are fitted.
    start : float, optional
        The fit's window begins at or after this time; by default half-way between
        the end of the drive's ramp and the last sensor sample.
    periods : int, optional
        Fit this many periods at the end of the record instead.

    Returns
    -------
    xarray.Dataset
        Dimensions ``sensor`` (the sensor balls) and ``harmonic`` (1..harmonics).
        ``amplitude`` and ``phase`` (sensor, harmonic), ``transmission`` (sensor,
        harmonic: amplitude over ``reference_force``), ``mean_force``,
        ``residual`` and ``steady`` (sensor); scalars ``frequency``, ``drive_amplitude``,
        ``reference_stiffness``, ``reference_force``, ``periods``, ``window_start``
        and ``window_end``; the line's linear spectrum in the drive's frequency unit:
        ``mode_frequency`` (mode) and, for a periodic line, ``band_bottom`` and
        ``band_top`` (branch). Every variable has ``units`` and ``long_name``.

    Raises
    ------
    ChainrunError
        For a run without sensors, without one wall moving by one sine, whose line is
        not at rest in a static state, too short for one period in the window, or
        sampled too coarsely for the harmonics asked for.
    """
    from chainrun.analysis.spectrum import line_spectrum

    sensors = _sensors(run)
    if sensors is None:
        raise ChainrunError("transmission: no force sensors in this run; give "
                            "output.sensors and output.sensor_dt to record them")
    t, y, balls, line, units, attrs = sensors
    if harmonics < 1:
        raise ChainrunError(f"harmonics: must be >= 1, got {harmonics}")
    wall, frequency, amplitude, ramp = _driven_wall(line)
    if t.size < 2:
        raise ChainrunError("transmission: the sensors have fewer than two samples")
    dt = float(np.min(np.diff(t)))
    if harmonics * frequency >= 0.5 / dt:
        from chainrun.units import format_value

        def hz(f):
            return format_value(f, "frequency", units)
        raise ChainrunError(f"harmonics: {harmonics} times the drive's frequency "
                            f"{hz(frequency)} is above the sensors' Nyquist frequency "
                            f"1/(2 sensor_dt) = {hz(0.5 / dt)}; sample faster (a sensor_dt "
                            f"below {format_value(0.5 / (harmonics * frequency), 'time', units)})"
                            f" or fit fewer harmonics (harmonics={harmonics - 1})"
                            if harmonics > 1 else
                            f"harmonics: the drive's frequency {hz(frequency)} is above the "
                            f"sensors' Nyquist frequency 1/(2 sensor_dt) = {hz(0.5 / dt)}; "
                            f"sample faster (a sensor_dt below "
                            f"{format_value(0.5 / frequency, 'time', units)})")
    if not amplitude:
        side = ("left", "right")[wall]
        raise ChainrunError(f"transmission: the driven wall does not move "
                            f"(walls.{side}.motion.amplitude is 0)")
    if start is None:
        start = ramp + 0.5 * (float(t[-1]) - ramp)
    begin, end, periods = fit_window(t, frequency, start, periods)
    inside = t >= begin - _PERIOD_SLACK / frequency
    mean, amp, phase, residual = fit_harmonics(t[inside], y[inside], frequency, harmonics)

    spectrum = line_spectrum(line, units)
    contact = 0 if wall == 0 else line.n
    stiffness = float(spectrum["linear_stiffness"].sel(contact=contact))
    reference = stiffness * abs(amplitude)
    if not reference > 0.0:
        raise ChainrunError("transmission: the driven wall's contact has no linear "
                            "stiffness at rest (it carries no load); give "
                            "chain.precompression")
    u = {q: _unit(q, units) for q in ("force", "time", "frequency", "position",
                                      "linear_stiffness")}
    side = ("left", "right")[wall]
    data = {
        "amplitude": (("harmonic", "sensor"), amp, {
            "units": u["force"], "long_name": "amplitude of the sensor's mean force at k "
                                              "times the drive's frequency"}),
        "phase": (("harmonic", "sensor"), phase, {
            "units": "rad", "long_name": "phase of that harmonic: the force's component "
                                         "is amplitude sin(2 pi k f t + phase)"}),
        "transmission": (("harmonic", "sensor"), amp / reference, {
            "units": "1", "long_name": "amplitude over the drive's force on a held ball, "
                                       "reference_force"}),
        "mean_force": ("sensor", np.atleast_1d(mean), {
            "units": u["force"], "long_name": "mean of the sensor's force over the window"}),
        "residual": ("sensor", np.atleast_1d(residual), {
            "units": u["force"], "long_name": "rms of the force less the fit: what is not "
                                              "steady at the drive's harmonics"}),
        "steady": ("sensor", (np.atleast_1d(residual) <= STEADY * amp[0])
                   & (periods >= MIN_PERIODS), {
            "long_name": f"whether the response is steady: the residual at most {STEADY:g} "
                         f"of the amplitude at f, over at least {MIN_PERIODS} periods",
            "residual_fraction": STEADY, "min_periods": MIN_PERIODS}),
        "frequency": ((), frequency, {"units": u["frequency"],
                                      "long_name": "the drive's frequency f"}),
        "drive_amplitude": ((), amplitude, {"units": u["position"],
                                            "long_name": f"amplitude A of the {side} wall's "
                                                         "sine"}),
        "reference_stiffness": ((), stiffness, {
            "units": u["linear_stiffness"], "long_name": f"linear stiffness K_w of the "
                                                         f"{side} wall's contact at rest"}),
        "reference_force": ((), reference, {
            "units": u["force"], "long_name": "K_w |A|: the force the drive would put on a "
                                              "held ball"}),
        "periods": ((), periods, {"long_name": "whole drive periods fitted"}),
        "window_start": ((), begin, {"units": u["time"],
                                     "long_name": "the fit's window begins"}),
        "window_end": ((), end, {"units": u["time"], "long_name": "the fit's window ends: "
                                                                  "the last sample"}),
        "mode_frequency": ("mode", spectrum["frequency"].values, {
            "units": u["frequency"], "long_name": "normal modes of the line at rest"}),
    }
    if "band_bottom" in spectrum:
        for name in ("band_bottom", "band_top"):
            data[name] = ("branch", spectrum[name].values / (2.0 * np.pi), {
                "units": u["frequency"], "long_name": f"{name.replace('_', ' ')} of each "
                                                      "band of the infinite periodic line"})
    for name, label in _LABELS.items():
        if name in data:
            dims, values, meta = data[name]
            data[name] = (dims, values, {**meta, "long_name": label,
                                         "description": meta["long_name"]})
    out = xr.Dataset(data, coords={
        "sensor": ("sensor", np.asarray(balls), {"long_name": "sensor ball"}),
        "harmonic": ("harmonic", np.arange(1, harmonics + 1),
                     {"long_name": "harmonic", "description": "k of the frequency k f"})})
    for name in ("amplitude", "phase", "transmission"):
        out[name] = out[name].transpose("sensor", "harmonic")
    return out.assign_attrs(units="SI" if units == "si" else PAPER, driven_wall=side,
                            **attrs)


#: The short ``long_name`` of each variable, which xarray's plots take for an axis
#: label; the longer text it is built with is its ``description``.
_LABELS = {
    "amplitude": "force amplitude", "phase": "phase", "transmission": "transmission",
    "mean_force": "mean force", "residual": "fit residual", "steady": "steady",
    "frequency": "drive frequency", "drive_amplitude": "drive amplitude",
    "reference_stiffness": "reference stiffness", "reference_force": "reference force",
    "periods": "periods fitted", "window_start": "window start", "window_end": "window end",
    "mode_frequency": "mode frequency", "band_bottom": "band bottom", "band_top": "band top",
}


def measure_sweep(runs, **options) -> xr.Dataset:
    """``measure`` on every run of a sweep, along the drive's frequency: a
    transmission curve.

    Parameters
    ----------
    runs : xarray.Dataset, or list of xarray.Dataset or chainrun.store.RunData
        A sweep (``chainrun.open_sweep``: a dimension ``run``), or its runs one by one
        (Datasets named by their ``run_id`` attribute, or run files read).
    **options
        ``harmonics``, ``start``, ``periods``: as ``measure``'s.

    Returns
    -------
    xarray.Dataset
        As ``measure``'s, with a dimension ``frequency`` (ascending) before the others;
        ``run`` along it names each run. The spectrum's variables are the line's, once.

    Raises
    ------
    ChainrunError
        As ``measure``, naming the run; or if two runs share a frequency, or their
        lines differ (a transmission curve is of one line).
    """
    if isinstance(runs, xr.Dataset):
        ids = [str(run_id) for run_id in runs["run"].values]
        runs = [runs.isel(run=i).assign_attrs(run_id=run_id) for i, run_id in enumerate(ids)]
    else:
        ids = [str(run.parameters.get("run_id", i)) if isinstance(run, RunData)
               else str(run.attrs.get("run_id", i)) for i, run in enumerate(runs)]
    results = []
    for run_id, run in zip(ids, runs):
        try:
            results.append(measure(run, **options))
        except ChainrunError as exc:
            raise ChainrunError(f"{run_id}: {exc}") from None
    first = results[0]
    for run_id, r in zip(ids[1:], results[1:]):
        if not all(r[name].equals(first[name]) for name in _SPECTRUM_VARS if name in first):
            raise ChainrunError(f"{run_id}: its line differs from the first run's; a "
                                "transmission curve is of one line")
    f = np.array([float(r["frequency"]) for r in results])
    if np.unique(f).size != f.size:
        raise ChainrunError("transmission: several runs drive at the same frequency; a "
                            "transmission curve needs one run per frequency")
    order = np.argsort(f)
    spectrum = first[[name for name in _SPECTRUM_VARS if name in first]]
    drop = list(spectrum.data_vars) + ["frequency"]
    curve = xr.concat([results[i].drop_vars(drop) for i in order], dim="frequency",
                      data_vars="all", coords="minimal", combine_attrs="drop_conflicts")
    curve = curve.assign_coords(
        frequency=("frequency", f[order], first["frequency"].attrs),
        run=("frequency", [ids[i] for i in order],
             {"long_name": "run", "description": "the id of the run at each frequency"}))
    # (the runs' ids are the coordinate run: the curve is of no one run)
    out = xr.merge([curve, spectrum], combine_attrs="override").assign_attrs(
        experiment=first.attrs.get("experiment", ""))
    out.attrs.pop("run_id", None)
    return out
