"""Measurements from Python: a run's pulses, a driven run's (or sweep's) transmission,
and a line's linear spectrum, each as an xarray Dataset.

``pulses`` and ``transmission`` take what ``chainrun.api.runs`` gives (a Dataset of
``open_run`` or ``simulate``, a sweep of ``open_sweep``) or a run file or folder;
``spectrum`` takes what ``simulate`` takes and returns the linear spectrum of the line
at rest (``chainrun.analysis.spectrum``), as ``chainrun spectrum`` writes it. Each
variable carries its ``units`` and ``long_name``.
"""

from __future__ import annotations

import os
from numbers import Integral, Real
from pathlib import Path

from chainrun.api.runs import _PAPER_UNIT, _UNITS, _experiment
from chainrun.errors import ChainrunError
from chainrun.paths import index_file


#: What pulses and transmission take, for the error that names what they were given.
_TAKES = ("a run (a Dataset of chainrun.open_run or chainrun.simulate, or a run file's "
          "path) or a sweep (chainrun.open_sweep's Dataset, the DataTree chainrun.simulate "
          "returns for one, or an output folder's path)")
#: Datasets of chainrun's own that are not runs, by a variable only they have.
_NOT_RUNS = (("omega", "a spectrum's (chainrun.spectrum)"),
             ("peak_force", "pulses' (chainrun.pulses)"),
             ("transmission", "a transmission's (chainrun.transmission)"))


def _check_run(run, who: str) -> None:
    """Raise a ``ChainrunError`` naming what ``run`` is if ``who`` cannot measure it."""
    import xarray as xr

    from chainrun.store import RunData

    if isinstance(run, xr.Dataset):
        if "final_velocity" in run or "sensor_force" in run:
            return
        kind = next((text for name, text in _NOT_RUNS if name in run),
                    "one without a run's variables (final_velocity, sensor_force)")
        raise ChainrunError(f"{who}: expected {_TAKES}; got a Dataset, {kind}")
    if isinstance(run, (xr.DataTree, str, os.PathLike, RunData)):
        return
    hint = (": give the run's Dataset, not one of its variables"
            if isinstance(run, xr.DataArray) else "")
    raise ChainrunError(f"{who}: expected {_TAKES}; got {type(run).__name__}{hint}")


# ------------------------------------------------------------------------------ pulses
def pulses(run) -> "xarray.Dataset":  # noqa: F821
    """The first pulse at each force sensor of a run, and the wave's speed, as a Dataset;
    over a sweep or an ensemble, each run's, along a dimension ``run``.

    ``chainrun.analysis.pulse`` measures them; its module's docstring defines each
    number. The run is a Dataset from ``open_run`` or ``simulate``, a run file's path,
    or a ``chainrun.store.RunData``; a sweep is a Dataset from ``open_sweep`` (or one
    run of it, ``.isel(run=i)``), the DataTree ``simulate`` returns for one, or an
    output folder's path.

    Returns
    -------
    xarray.Dataset
        Dimension ``sensor`` (the sensor balls). Variables: ``peak_force``,
        ``peak_time``, ``width`` (FWHM), ``arrival_time`` of the first pulse of the
        contact the wave leaves each sensor ball through (``side``: 0 towards ball 1,
        1 away from it), and ``peak_mean_force``, the peak of the ball's mean force
        (what a sensor embedded in it measures); the wave's speed ``wave_speed`` and
        its standard uncertainty ``wave_speed_error`` (balls per unit time, positive
        towards ball N; the uncertainty is NaN with two sensors), and for spheres with
        diameters ``wave_speed_si`` and ``wave_speed_si_error`` (m/s). Where the
        sensors saw waves going both ways (a line struck from both ends), those are
        the wave towards ball N's, and ``backward_wave_speed`` (``_error``, ``_si``,
        ``_si_error``) the other's, each fitted alone. Every variable has ``units``
        and ``long_name``; NaN where a pulse was not reached or was cut off. For a
        sweep, every variable has the dimension ``run`` first, with the sweep's
        coordinates along it (its run ids, the swept keys), so that an ensemble's mean
        peak force is ``p.peak_force.mean("run")``.

    Raises
    ------
    chainrun.errors.ChainrunError
        For a run without force sensors, or a driven one (whose steady response
        ``transmission`` measures), naming the run in a sweep; for something not a run
        or a sweep (a DataArray, a spectrum's Dataset), saying what it is;
        ``chainrun.errors.StoreError`` for a file or folder that cannot be read.

    Examples
    --------
    >>> ds = chainrun.simulate(chain={"n": 60, "k": 1, "alpha": 1.5},  # doctest: +SKIP
    ...                        output={"sensors": [20, 30, 40, 50], "sensor_dt": 0.01},
    ...                        solver={"t_end": 75.0})
    >>> p = chainrun.pulses(ds)                                       # doctest: +SKIP
    >>> p.peak_force.sel(sensor=40).item(), p.wave_speed.item()       # doctest: +SKIP
    (0.63955..., 0.84050...)
    >>> e = chainrun.pulses("results/ensemble")                       # doctest: +SKIP
    >>> e.wave_speed_si.mean("run").item(), e.wave_speed_si.std("run").item()  # doctest: +SKIP
    """
    import xarray as xr

    from chainrun.api.runs import open_sweep
    from chainrun.analysis.pulse import measure_pulses

    _check_run(run, "pulses")
    if isinstance(run, xr.DataTree):       # simulate's sweep: a child per run
        names = list(run.children)
        return _pulses_along_run([_run_pulses(run[name].to_dataset(), name)
                                  for name in names], open_sweep(run))
    if isinstance(run, xr.Dataset):
        if "run" not in run.dims:
            return _run_pulses(run)
        ids = [str(r) for r in run["run"].values]
        return _pulses_along_run([_run_pulses(run.isel(run=i), ids[i])
                                  for i in range(len(ids))], run)
    path = Path(run) if isinstance(run, (str, os.PathLike)) else None
    if path is not None and path.is_dir():
        return pulses(open_sweep(path))
    if path is not None:
        from chainrun.store import read_run

        run = read_run(path)
    if getattr(run, "line", None) is not None and run.line.is_driven:
        raise ChainrunError(f"pulses: {_DRIVEN}")
    return _as_dataset(measure_pulses(run))


#: Why a driven run has no pulses to measure, and what measures it instead.
_DRIVEN = ("this line is driven (a wall moves, or a force acts, in time): it has a "
           "steady response, not a first pulse; chainrun.transmission measures that")


def _run_pulses(run, name: str | None = None):
    """``pulses`` of one run's Dataset; in a sweep, ``name`` is its run id."""
    import numpy as np

    from chainrun.analysis.pulse import measure_sensors

    where = f"pulses: run {name}" if name is not None else "pulses"
    if "sensor_force" not in run:
        raise ChainrunError(f"{where}: no force sensors in this run; give "
                            "output.sensors and output.sensor_dt to record them")
    if "wall_motion_amplitude" in run or float(run.attrs.get("final_drive_work", 0.0)):
        raise ChainrunError(f"{where}: {_DRIVEN}")
    force = run["sensor_force"]
    if "sensor" not in force.dims:     # one sensor picked by .sel(sensor=b): its own
        force = force.expand_dims("sensor")
    missing = [dim for dim in ("sample", "side") if dim not in force.dims]
    if missing:
        raise ChainrunError(f"{where}: sensor_force needs its dimension "
                            f"{' and '.join(missing)} whole (both sides of each sensor "
                            "ball, over its samples); select sensors or runs only")
    # a run of a sweep has the sweep's samples: NaN where it took none (a run that
    # ended sooner than another, or one sampled at other times)
    force = force.dropna("sample", how="all")
    return _as_dataset(measure_sensors(
        force["sample"].values, force.transpose("sample", "sensor", "side").values,
        force["sensor"].values, units="si" if run.attrs.get("units") == "SI" else "paper",
        diameter=run["diameter"].values if "diameter" in run else None,
        gap=run["gap"].values if "gap" in run else None,
        wall_gap=tuple(np.nan_to_num(run["wall_gap"].values)) if "wall_gap" in run
        else (0.0, 0.0),
        min_rise=1e-9 * float(run.attrs.get("scales_force", 1.0))))


def _pulses_along_run(measured, sweep):
    """Each run's ``pulses`` side by side along ``run``, with the sweep's coordinates
    along it (a variable some runs lack, the backward wave's, NaN in the others)."""
    import xarray as xr

    out = xr.concat(measured, dim="run", join="outer", combine_attrs="drop_conflicts")
    along = {name: coord for name, coord in sweep.coords.items() if coord.dims == ("run",)}
    return out.assign_coords(along)


def _as_dataset(p):
    """A ``chainrun.analysis.pulse`` measurement as ``pulses``' Dataset."""
    import xarray as xr

    from chainrun.units import UNITS

    si = p.units == "si"

    def unit(quantity: str) -> str:
        return UNITS["si"][quantity] if si else _PAPER_UNIT

    per_sensor = {
        "peak_force": (p.peak_force, "force", "largest contact force of the first pulse"),
        "peak_time": (p.peak_time, "time", "time of the peak contact force"),
        "width": (p.width, "time", "full width at half maximum of the first pulse"),
        "arrival_time": (p.arrival_time, "time",
                         f"time the first pulse's rising edge reaches {p.arrival:g} of "
                         "the way from the baseline to its peak"),
        "peak_mean_force": (p.peak_mean_force, "force",
                            "peak of the first pulse of the mean of the two contact "
                            "forces: what a sensor embedded in the ball measures"),
    }
    # the short long_name is the axis label xarray's plots take; the text, description
    labels = {"peak_force": "peak force", "peak_time": "peak time", "width": "pulse width",
              "arrival_time": "arrival time", "peak_mean_force": "peak sensor force"}
    data = {name: ("sensor", values, {"units": unit(q), "long_name": labels[name],
                                      "description": text})
            for name, (values, q, text) in per_sensor.items()}
    data["side"] = ("sensor", p.side, {"long_name": "side",
                                       "description": "the contact measured (a number, "
                                                      "not a quantity): 0 towards ball 1, "
                                                      "1 away from it"})
    if p.on_wall is not None:
        data["on_wall"] = ("sensor", p.on_wall, {
            "long_name": "on a wall",
            "description": "whether the contact measured is a wall's (the end ball's, "
                           "towards its wall): the force on the wall as the wave "
                           "reflects, which the wave speed is not fitted through"})
    per_time = "ball/s" if si else "balls per unit time (paper units)"
    two = p.backward_speed.points > 0
    way = " towards ball N" if two else ""
    speeds = [("wave_speed", p.speed, per_time, "balls per unit time", way)]
    if p.speed_si is not None:
        speeds.append(("wave_speed_si", p.speed_si, "m/s", "metres per second", way))
    if two:
        speeds.append(("backward_wave_speed", p.backward_speed, per_time,
                       "balls per unit time", " towards ball 1"))
        if p.backward_speed_si is not None:
            speeds.append(("backward_wave_speed_si", p.backward_speed_si, "m/s",
                           "metres per second", " towards ball 1"))
    for name, speed, units, what, way in speeds:
        # the speed in balls beside the one in m/s: told apart by their labels
        label = f"wave speed{way}" + (" in balls" if si and not name.endswith("_si") else "")
        data[name] = ((), speed.value, {
            "units": units, "long_name": label,
            "description": f"wave speed{way} in {what}: least-squares slope of the "
                           f"measured contacts' positions against their peak times "
                           f"({speed.points} sensors)"})
        data[f"{name}_error"] = ((), speed.error, {
            "units": units, "long_name": f"{label} uncertainty",
            "description": "standard uncertainty of the wave speed, from the fit's "
                           "residuals (NaN with two sensors)"})
    sensor = {"long_name": "sensor ball", "description": "the ball that carries the sensor"}
    return xr.Dataset(data, coords={"sensor": ("sensor", p.balls, sensor)},
                      attrs={"units": "SI" if si else _UNITS, "arrival_fraction": p.arrival})


# ------------------------------------------------------------------------ transmission
def transmission(run, *, harmonics: int = 3, start: float | None = None,
                 periods: int | None = None) -> "xarray.Dataset":  # noqa: F821
    """The steady response of a driven run's force sensors: amplitude and phase at the
    drive's frequency and its harmonics, and the transmission; over a sweep of the
    drive's frequency, a transmission curve.

    ``chainrun.analysis.transmission`` measures them; its module's docstring defines
    each number. One wall of the run moves by one sine (``walls.<side>.motion``), and
    the run has force sensors (``output.sensors``).

    Parameters
    ----------
    run : xarray.Dataset, xarray.DataTree or path
        A run (``open_run``, ``simulate``) or a sweep (``open_sweep``, or the DataTree
        ``simulate`` returns for one), or the path of a run file or of an output folder
        (its ``index.h5``: the sweep).
    harmonics : int
        Fit the drive's frequency f and its multiples up to ``harmonics`` f.
    start : float, optional
        The fit's window, a whole number of drive periods ending at the last sensor
        sample, begins at or after this time; by default half-way between the end of
        the drive's ramp and the last sample.
    periods : int, optional
        Fit this many periods at the end of the record instead.

    Returns
    -------
    xarray.Dataset
        ``amplitude``, ``phase`` and ``transmission`` (sensor, harmonic: the amplitude
        over ``reference_force``, the drive's amplitude times the linear stiffness of
        the driven wall's contact), ``mean_force`` and ``residual`` (sensor),
        ``periods`` fitted and the window; for a sweep each has a dimension
        ``frequency`` first (ascending; ``run`` along it names the runs). The line's
        linear spectrum in the drive's frequency unit (Hz in SI): ``mode_frequency``
        (mode), and for a periodic line ``band_bottom`` and ``band_top`` (branch).

    Raises
    ------
    chainrun.errors.ChainrunError
        For a run without sensors or without one wall moving by one sine, a window
        without one whole period, too few samples per period for the harmonics, or a
        sweep whose runs share a frequency or differ in their lines (one line naming
        the run); for something not a run or a sweep, or an option of the wrong type;
        ``chainrun.errors.StoreError`` for a file or folder that cannot be read.

    Examples
    --------
    >>> t = chainrun.transmission("results/driven-dimer")         # doctest: +SKIP
    >>> t.transmission.sel(harmonic=1, sensor=20).values          # doctest: +SKIP
    array([8.19e-01, 1.48e-04])
    """
    import xarray as xr

    from chainrun.analysis.transmission import measure, measure_sweep
    from chainrun.errors import StoreError

    from chainrun.store import read_index, read_run

    from chainrun.errors import show_value

    _check_run(run, "transmission")
    for name, value, kind, what in (("harmonics", harmonics, Integral, "a whole number >= 1"),
                                    ("start", start, Real, "a time, or None"),
                                    ("periods", periods, Integral, "a whole number >= 1, or None")):
        if (value is None and name != "harmonics") or (
                isinstance(value, kind) and not isinstance(value, bool)):
            continue
        raise ChainrunError(f"transmission: {name}: expected {what}, got {show_value(value)}")
    options = dict(harmonics=harmonics, start=start, periods=periods)
    if isinstance(run, xr.DataTree):       # simulate's sweep: a child per run
        return measure_sweep([child.to_dataset().assign_attrs(run_id=name)
                              for name, child in run.children.items()], **options)
    if isinstance(run, xr.Dataset):
        return measure_sweep(run, **options) if "run" in run.dims else measure(run, **options)
    folder = Path(run)
    if not folder.is_dir():
        return measure(read_run(folder), **options)
    if not index_file(folder).is_file():
        raise StoreError(f"{folder}: no index.h5 (not a chainrun output folder)")
    return measure_sweep([read_run(folder / str(row["file"]))
                          for row in read_index(index_file(folder))], **options)


def spectrum(config=None, /, *, period: int | None = None,
             **tables) -> "xarray.Dataset | xarray.DataTree":  # noqa: F821
    """The linear spectrum of an experiment's line at rest in its static state.

    The line is the one ``simulate`` would run, its strikers left out, about its static
    state (``chain.precompression`` places one): its contacts' linear stiffnesses, the
    normal modes of the finite line and, for a line that repeats a unit cell, the
    dispersion relation and band edges (``chainrun.analysis.spectrum``). Nothing is
    run, so a line held between two walls needs no ``solver.t_end`` here.

    Parameters
    ----------
    config : path or dict, optional
        An experiment file (``.toml``, ``.yaml``), or its tables as a dict.
    period : int, optional
        Balls in the unit cell of the dispersion relation: by default the smallest cell
        the masses and linear stiffnesses repeat (at least twice); 0 for none.
    **tables
        Tables of the experiment file as keyword arguments, added to a dict ``config``.

    Returns
    -------
    xarray.Dataset, or xarray.DataTree for an experiment with a sweep (a child Dataset
    per run). ``omega`` (mode): the angular frequencies, ascending, in the inverse of the
    file's time unit (rad/s in SI); ``frequency`` = omega / (2 pi); ``shape`` (mode,
    ball), each mode's displacements, largest magnitude 1; per contact
    ``static_compression``, ``static_force`` and ``linear_stiffness``; for a periodic
    line ``dispersion`` (q, branch), ``band_bottom`` and ``band_top`` (branch).

    Raises
    ------
    chainrun.errors.ConfigError
        For an invalid experiment, naming every wrong key.
    chainrun.errors.ChainrunError
        For a line not at rest in a static state, too long, or not of the ``period``
        given (one line).

    Examples
    --------
    >>> ds = chainrun.spectrum(chain={"n": 20, "k": 0, "alpha": 1.5,
    ...                               "precompression": 1.0},
    ...                        walls={"left": {}, "right": {}})
    >>> ds.omega.values[:3]                        # doctest: +SKIP
    """
    import xarray as xr

    from chainrun.analysis.spectrum import run_spectrum

    experiment = _experiment(config, tables, "<spectrum>", to_run=False)
    out = {spec.run_id: run_spectrum(spec, period=period)
           for spec in experiment.runs(to_run=False)}
    if not experiment.sweep:
        return next(iter(out.values()))
    return xr.DataTree.from_dict(out, name=experiment.name)
