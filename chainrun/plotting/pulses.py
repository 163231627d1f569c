"""The figure of a sweep's pulses: what its force sensors measured against the swept key.

``draw_sweep_pulses(runs, pulses, ...)`` draws, for the runs of a sweep over one key
whose lines are struck and carry force sensors, and their pulses (each run's
``chainrun.analysis.pulse.measure_pulses``, the measurements ``chainrun info`` and
``chainrun.pulses`` give), three panels against that key: the wave's speed (in m/s for a
line of spheres, else in balls per unit time) with its standard uncertainty, and each
sensor's peak contact force and pulse width (FWHM). Where the key's values are positive
and span a factor of 10 or more, the axes are logarithmic and each curve's legend gives
the exponent of the power law fitted through it (least squares on the logarithms), and
where the points bend the slopes from the first pair of runs to the last (``slope 0.188,
0.172 → 0.197``): a solitary wave's speed goes as the impact speed to the 1/5, its peak
force to the 6/5, and on a column under its weight the speed's slope rises towards 1/5
as the impacts outgrow the static load. Each artist carries a ``gid`` naming what it
shows.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter

from chainrun.plotting.common import MARKERS
from chainrun.units import axis_label

__all__ = ["draw_sweep_pulses", "local_slopes", "power_law"]

#: The span of the swept values over which the axes are logarithmic and a power law is
#: fitted: a decade, as in the views' other sweep figures.
_DECADE = 10.0


class _PlainLog(LogFormatter):
    """A log axis's labels where matplotlib's log formatter puts them (its minor ticks
    too, on an axis of less than a few decades), written as plain numbers: 0.05 and
    400, not 5e-02 and 4 x 10^2; on an axis of more than a decade, the minor ticks at
    2 and 5 times a power of ten alone (0.03 and 0.04 ran into each other)."""

    def __call__(self, x, pos=None):
        if not super().__call__(x, pos):
            return ""
        low, high = sorted(self.axis.get_view_interval())
        if low > 0 and high > 10.0 * low:
            mantissa = round(x / 10.0 ** math.floor(math.log10(x) + 1e-9), 6)
            if mantissa not in (1.0, 2.0, 5.0):
                return ""
        return f"{x:g}"


def power_law(x, y) -> float:
    """The exponent of the power law y ~ x^p fitted through the points (least squares
    on log y against log x); NaN with fewer than two positive points."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    ok = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if np.count_nonzero(ok) < 2 or np.ptp(np.log(x[ok])) == 0.0:
        return float("nan")
    return float(np.polyfit(np.log(x[ok]), np.log(y[ok]), 1)[0])


def local_slopes(x, y) -> np.ndarray:
    """The slopes of log y against log x between neighbouring points (in x's order)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    order = np.argsort(x)
    return np.diff(np.log(y[order])) / np.diff(np.log(x[order]))


def _label(name: str, x, y, fitted: bool) -> str:
    """A curve's legend: its name, and the exponent fitted through it on log axes;
    where the points bend (their slopes between neighbours differ by more than 0.005),
    the range of those slopes too: one power law does not describe them."""
    p = power_law(x, y) if fitted else float("nan")
    if not np.isfinite(p):
        return name
    local = local_slopes(x, y)
    local = local[np.isfinite(local)]
    if local.size > 1 and np.ptp(local) > 0.005:
        return f"{name} (slope {p:.3f}, {local[0]:.3f} → {local[-1]:.3f})"
    return f"{name} (slope {p:.3f})"


def draw_sweep_pulses(runs, pulses, key: str, title: str) -> Figure:
    """The wave speed, peak contact force and width of the runs' ``pulses`` (one per
    run) against the swept ``key`` (its values in the runs' ``overrides``); ``title``
    heads the figure. Runs whose key is not a number are left out."""
    from chainrun.plotting.views import _swept_axis

    units = runs[0].units
    points = sorted(((float(run.parameters.get("overrides", {})[key]), i)
                     for i, run in enumerate(runs)
                     if isinstance(run.parameters.get("overrides", {}).get(key), (int, float))))
    x = np.array([value for value, _ in points])
    pulses = [pulses[i] for _, i in points]
    xlabel, along = _swept_axis(key, units, x)
    log = x.size > 1 and x.min() > 0 and x.max() >= _DECADE * x.min()
    figure = Figure(figsize=(13.5, 4.0), layout="constrained")

    # the wave's speed: in m/s where every run has it so (spheres), else in balls
    si = all(p.speed_si is not None for p in pulses)
    fits = [p.speed_si if si else p.speed for p in pulses]
    value = np.array([f.value for f in fits])
    error = np.array([f.error for f in fits])
    axes = figure.add_subplot(1, 3, 1)
    if si:
        ylabel, scaled = axis_label("wave speed", "velocity", units, value)
    else:
        ylabel = "wave speed (balls/s)" if units == "si" else "wave speed (balls per unit time)"
        scaled = np.asarray
    axes.errorbar(along(x), scaled(value), yerr=scaled(np.nan_to_num(error)),
                  label=_label("fitted through the sensors", x, value, log),
                  gid="pulses/wave_speed", capsize=2, **MARKERS[0])
    axes.set_ylabel(ylabel)

    balls = pulses[0].balls
    on_wall = (pulses[0].on_wall if pulses[0].on_wall is not None
               else np.zeros(balls.size, dtype=bool))
    for panel, (name, quantity, values) in enumerate(
            (("peak contact force", "force", [p.peak_force for p in pulses]),
             ("pulse width, FWHM", "time", [p.width for p in pulses])), start=2):
        axes_i = figure.add_subplot(1, 3, panel)
        table = np.array([np.asarray(v, dtype=float) for v in values])  # run x sensor
        ylabel, scaled_i = axis_label(name, quantity, units, table[np.isfinite(table)])
        for i, ball in enumerate(balls):
            if i >= table.shape[1]:
                break
            name_i = f"ball {ball}" + (", on the wall" if on_wall[i] else "")
            axes_i.plot(along(x), scaled_i(table[:, i]),
                        label=_label(name_i, x, table[:, i], log),
                        gid=f"pulses/{quantity}/{ball}", **MARKERS[i % len(MARKERS)])
        axes_i.set_ylabel(ylabel)
    for axes_i in figure.axes:
        axes_i.set_xlabel(xlabel)
        if log:
            axes_i.set_xscale("log")
            axes_i.set_yscale("log")
            for axis in (axes_i.xaxis, axes_i.yaxis):
                axis.set_major_formatter(_PlainLog(labelOnlyBase=False))
                axis.set_minor_formatter(_PlainLog(labelOnlyBase=False,
                                                   minor_thresholds=(2, 0.5)))
        # below the panel: labels with their slopes are long, and inside they hid points
        axes_i.legend(fontsize="small", loc="upper center", bbox_to_anchor=(0.5, -0.2),
                      borderaxespad=0.0)
    figure.suptitle(title, fontsize="small")
    return figure
