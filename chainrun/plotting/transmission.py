"""The figure of a transmission curve: a driven sweep's response against the bands.

``draw_transmission(ds)`` draws the Dataset ``chainrun.transmission`` makes of a sweep
over a wall's drive frequency: each force sensor's transmission at the drive's
frequency against that frequency, on a log scale, over the linear spectrum of the line
at rest: for a periodic line its stop bands (the gaps, and above the top band) shaded
grey and hatched, the band edges dashed; the normal modes of the finite line as ticks
along the top. Curves take the views' colour-blind-safe cycle (``petroff10``) where
the caller asks for colour, and each a line style and a symbol of its own, which tell
them apart in the paper's black and white too (the gallery's page) and which the grey
shading leaves apart. Each artist carries a ``gid`` naming the variable it shows. A
point whose response is steady is drawn filled; one that is not (``steady``: the fit
leaves too much, or too few periods) hollow: it is not a transmitted signal.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from chainrun.plotting.common import MARKERS
from chainrun.units import axis_label

__all__ = ["draw_transmission"]

_STOP = dict(facecolor="0.9", edgecolor="0.72", hatch="////", linewidth=0.0)

#: The sensors' symbols: the paper's that can be filled (diamond, square, triangle,
#: ``MARKERS``), then more of the kind. A steady point is filled and one that is not
#: hollow, so a symbol that has no inside (plus, cross) cannot mark a sensor here.
_SYMBOLS = tuple(m for m in MARKERS if m.get("markerfacecolor") == "none") + tuple(
    dict(marker=m, markersize=5) for m in ("o", "v", "p", "h"))


def _symbol(i: int) -> dict:
    """The i-th sensor's symbol and line style (the views' ``LINESTYLES``, which the
    colour cycle pairs with its colours: in black and white, what tells the lines
    apart between their symbols)."""
    from chainrun.plotting import LINESTYLES

    symbol = {key: value for key, value in _SYMBOLS[i % len(_SYMBOLS)].items()
              if key != "markerfacecolor"}
    return {**symbol, "linestyle": LINESTYLES[i % len(LINESTYLES)]}


def _units(ds) -> str:
    return "si" if ds.attrs.get("units") == "SI" else "paper"


def _bands(axes, ds, scaled, right: float) -> list:
    """Shade the stop bands up to ``right`` and mark the band edges; the legend's
    handles."""
    if "band_bottom" not in ds:
        return []
    bottom, top = scaled(ds["band_bottom"].values), scaled(ds["band_top"].values)
    stops = [(top[b], bottom[b + 1]) for b in range(bottom.size - 1) if bottom[b + 1] > top[b]]
    stops.append((top[-1], max(right, top[-1])))
    for s, (low, high) in enumerate(stops):
        axes.axvspan(low, high, gid=f"stop/{s + 1}", **_STOP)
    for edge in np.unique(np.concatenate([bottom[bottom > 0], top])):
        axes.axvline(edge, color="0.35", linestyle="--", linewidth=0.7, gid="band_edge")
    return [Patch(label="stop band of the infinite line", **_STOP)]


#: the fewest drive frequencies whose points are joined by lines
JOIN_POINTS = 5


def draw_transmission(ds, title: str = "") -> Figure:
    """The transmission curve of ``ds`` (``chainrun.transmission`` of a frequency
    sweep: dims frequency, sensor, harmonic), with ``title`` above it. Call inside
    ``chainrun.plotting.style(colour=True)``."""
    units = _units(ds)
    f = ds["frequency"].values
    modes = ds["mode_frequency"].values
    label, scaled = axis_label("drive frequency $f$", "frequency", units,
                               np.concatenate([f, modes[modes <= 1.05 * f.max()]]))
    x = scaled(f)
    right = float(x.max() + 0.03 * (x.max() - x.min()))
    figure = Figure(figsize=(7.2, 4.4), layout="constrained")
    axes = figure.add_subplot()
    handles = _bands(axes, ds, scaled, right)
    t = ds["transmission"].sel(harmonic=1).transpose("frequency", "sensor")
    steady = (ds["steady"].transpose("frequency", "sensor") if "steady" in ds
              else t.notnull())
    # a line joins the frequencies only where there are enough to be a curve: two or
    # three points joined across a band edge would draw a transmission through the gap
    # that no run measured
    joined = {} if f.size >= JOIN_POINTS else {"linestyle": "none"}
    for i, ball in enumerate(ds["sensor"].values):
        (line,) = axes.plot(x, t.sel(sensor=ball).values, label=f"ball {ball}",
                            gid=f"transmission/{ball}", **{**_symbol(i), **joined})
        line.set_markerfacecolor(line.get_color())   # steady: filled
        handles.insert(i, line)
        loose = ~steady.sel(sensor=ball).values
        if loose.any():  # the same markers, hollow: not a transmitted signal
            # (its colour given: one taken from the cycle would shift the next sensors')
            axes.plot(x[loose], t.sel(sensor=ball).values[loose], linestyle="none",
                      marker=line.get_marker(), markersize=line.get_markersize() + 1,
                      color=line.get_color(), markerfacecolor="white",
                      markeredgecolor=line.get_color(), gid=f"not_steady/{ball}")
    if not bool(steady.all()):
        rule = steady.attrs
        handles.append(Line2D([], [], linestyle="none", marker="o", markersize=5,
                              markerfacecolor="white", markeredgecolor="0.2",
                              label=f"hollow: not steady (residual over "
                                    f"{rule['residual_fraction']:g} of the amplitude, or "
                                    f"under {rule['min_periods']} periods)"))
    left = float(x.min() - 0.03 * (x.max() - x.min()))
    shown = modes[(scaled(modes) >= left) & (scaled(modes) <= right)]
    axes.plot(scaled(shown), np.ones_like(shown), transform=axes.get_xaxis_transform(),
              linestyle="none", marker="|", markersize=9, color="0.2", clip_on=False,
              gid="mode_frequency", label="modes of the finite line")
    handles.append(axes.get_lines()[-1])
    axes.set_yscale("log")
    axes.set_xlim(left, right)
    axes.set_xlabel(label)
    wall = ds.attrs.get("driven_wall", "driven")
    axes.set_ylabel(f"transmission: force amplitude / $K_w A$ ({wall} wall)")
    figure.legend(handles=handles, fontsize="small", loc="outside lower center",
                  ncols=min(4, -(-len(handles) // 2)), frameon=False)   # two rows
    periods = ds["periods"].values
    fitted = (f"{periods.min()}" if periods.min() == periods.max()
              else f"{periods.min()}-{periods.max()}")
    axes.set_title("\n".join(filter(None, [
        title, f"At the drive's frequency: a least-squares fit over the last {fitted} "
               f"period{'s' * bool(periods.max() != 1)} of each run"])), fontsize="small")
    return figure
