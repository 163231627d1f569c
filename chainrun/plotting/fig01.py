"""Figure 1: the displacements x_n(t) + n of the seven balls of a short linear line."""

from __future__ import annotations

from chainrun.plotting.common import draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    for name in series_names(data, "data"):
        draw_series(ax, data, name, linestyle="-")
    for name in series_names(data, "guide"):
        draw_series(ax, data, name, linestyle="--")
    ax.set_xlabel(r"$t$")
    ax.set_ylabel(r"$x_n(t) + n$")
    ax.set_xlim(0.0, 20.0)
    ax.set_ylim(-0.5, None)
    return figure
