"""The gallery's figures (``make gallery``): one module draws them all, in the paper's style.

Each gallery analysis file (``chainrun.analysis.gallery``) holds its series under one or
two groups; every series names its ``panel`` (0 or 1) and, for markers, the paper's
symbol it takes (``marker``). ``draw(data)`` lays the panels out and labels the axes of
each item; nothing is computed here. ``gallery-transmission`` is the transmission
curve of ``chainrun plot OUTDIR`` (``chainrun.plotting.transmission``), drawn from the
arrays its analysis file keeps: its points that are not steady hollow, as there.
"""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from chainrun.plotting.common import MARKERS, draw_series, series_names

__all__ = ["draw"]

#: For each item: its panels, each (group, x label, y label, x scale, y scale).
PANELS = {
    "gallery-solitary": (
        ("speed", r"peak contact force $F_m$ (N)", r"wave speed $V$ (m/s)", "log", "log"),
        ("precompressed", r"$F_m / F_0$", r"$V / c_0$", "log", "linear"),
    ),
    "gallery-cradle": (
        ("drift", r"ball $n$ (elastic)", r"displacement at $t$ = 1 s (mm)", "linear",
         "symlog"),
        ("drift_damped", r"ball $n$ ($e$ = 0.95, Tsuji)", r"displacement at $t$ = 1 s (mm)",
         "linear", "symlog"),
    ),
    "gallery-wall": (
        ("restitution", r"number of beads $N$", r"effective restitution $e$", "linear",
         "linear"),
        ("duration", r"number of beads $N$", r"contact time / one bead's", "linear",
         "linear"),
        ("speed", r"impact speed $V$ (m/s)", r"effective restitution $e$ ($N$ = 8)", "log",
         "linear"),
    ),
    "gallery-head-on": (
        ("head_on", r"ball $n$", r"final velocity $\dot{x}_n(\infty)$", "linear", "linear"),
        ("impurity", r"impurity mass $\mu$", "energy share", "log", "linear"),
    ),
    "gallery-taper": (
        ("taper", r"taper ratio $q$ (diameter $d_{i+1}/d_i$)", "transmitted / incident",
         "linear", "log"),
    ),
    "gallery-dimer": (
        ("dimer", r"mass ratio $m_2/m_1$", "energy share left behind", "linear", "log"),
    ),
}


def _transmission(data) -> Figure:
    """The transmission curve of ``gallery-transmission``, as ``chainrun plot`` draws a
    sweep's, in SI."""
    import xarray as xr

    from chainrun.plotting.transmission import draw_transmission

    a = {key.partition("/")[2]: value for key, value in data.arrays.items()
         if key.startswith("curve/")}
    variables = {
        "transmission": (("frequency", "sensor", "harmonic"), a["transmission"][:, :, None]),
        "periods": ("frequency", a["periods"]),
        "mode_frequency": ("mode", a["mode_frequency"]),
        "band_bottom": ("branch", a["band_bottom"]), "band_top": ("branch", a["band_top"])}
    if "steady" in a:   # with the rule it was decided by: the legend says it
        variables["steady"] = (("frequency", "sensor"), a["steady"].astype(bool),
                               data.attrs.get("curve", {}))
    ds = xr.Dataset(variables, coords={"frequency": a["frequency"], "sensor": a["sensor"],
                                       "harmonic": [1]},
                    attrs={"units": "SI", "driven_wall": "left"})
    return draw_transmission(ds, data.settings.get("description", ""))


def draw(data) -> Figure:
    if data.name == "gallery-transmission":
        return _transmission(data)
    panels = PANELS[data.name]
    figure = Figure(figsize=(4.8 * len(panels), 3.6))
    for i, (group, xlabel, ylabel, xscale, yscale) in enumerate(panels):
        ax = figure.add_subplot(1, len(panels), i + 1)
        for name in series_names(data, group=group):
            attrs = data.attrs[f"{group}/{name}"]
            if attrs.get("role") == "data":
                style = dict(MARKERS[int(attrs.get("marker", 0)) % len(MARKERS)])
                style["linestyle"] = "none" if group in ("speed", "precompressed",
                                                         "impurity") else ":"
            else:
                style = dict(linestyle="--" if "nesterenko" in name or "two" in name
                             else "-")
            draw_series(ax, data, name, group=group, **style)
        ax.set_xscale(xscale)
        if xscale == "log":
            ax.xaxis.set_minor_formatter(NullFormatter())
        if yscale == "symlog":
            ax.set_yscale("symlog", linthresh=1.0)
        else:
            ax.set_yscale(yscale)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.legend(loc="best")
    return figure
