"""The figure of a sweep's pulses: what its force sensors measured against the swept key.

``draw_sweep_pulses(sweep, title)`` draws a ``chainrun.analysis.pulse_sweep.PulseSweep``
in three panels against the swept key: the wave's speed (in m/s for a line of spheres,
else in balls per unit time) with its standard uncertainty, and each sensor's peak
contact force and pulse width (FWHM). Where the key's values span a decade, the axes are
logarithmic and each curve's legend gives the exponent of the power law fitted through
it, and where the points bend the slopes between its first and its last pair of runs
(``slope 0.188, 0.172 → 0.197``). Each artist carries a ``gid`` naming what it shows.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure
from matplotlib.ticker import LogFormatter

from chainrun.plotting.common import MARKERS
from chainrun.units import axis_label

__all__ = ["draw_sweep_pulses"]


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


def _label(curve, log: bool) -> str:
    """A curve's legend: its name, and on log axes the exponent of the power law
    fitted through it, with the slopes from its first pair of runs to its last where
    the points bend (``Curve``)."""
    if not (log and math.isfinite(curve.slope)):
        return curve.name
    if math.isfinite(curve.first):
        return f"{curve.name} (slope {curve.slope:.3f}, {curve.first:.3f} → {curve.last:.3f})"
    return f"{curve.name} (slope {curve.slope:.3f})"


def draw_sweep_pulses(sweep, title: str) -> Figure:
    """The wave speed, peak contact force and width of a sweep's pulses
    (``chainrun.analysis.pulse_sweep.PulseSweep``) against its key; ``title`` heads the
    figure."""
    from chainrun.plotting.views import _swept_axis

    units, x, log = sweep.units, sweep.x, sweep.log
    xlabel, along = _swept_axis(sweep.key, units, x)
    figure = Figure(figsize=(13.5, 4.0), layout="constrained")

    speed = sweep.speed
    axes = figure.add_subplot(1, 3, 1)
    if sweep.si:
        ylabel, scaled = axis_label("wave speed", "velocity", units, speed.values)
    else:
        ylabel = "wave speed (balls/s)" if units == "si" else "wave speed (balls per unit time)"
        scaled = np.asarray
    axes.errorbar(along(x), scaled(speed.values), yerr=scaled(np.nan_to_num(speed.errors)),
                  label=_label(speed, log), gid="pulses/wave_speed", capsize=2, **MARKERS[0])
    axes.set_ylabel(ylabel)

    for panel, (name, quantity, curves) in enumerate(
            (("peak contact force", "force", sweep.force),
             ("pulse width, FWHM", "time", sweep.width)), start=2):
        axes_i = figure.add_subplot(1, 3, panel)
        every = np.concatenate([c.values for c in curves]) if curves else np.zeros(0)
        ylabel, scaled_i = axis_label(name, quantity, units, every[np.isfinite(every)])
        for i, (ball, curve) in enumerate(zip(sweep.balls, curves)):
            axes_i.plot(along(x), scaled_i(curve.values), label=_label(curve, log),
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
