"""Figure 2: the rebound velocities of a line of 25 balls, log-log, dashed slope -3/4."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure


def draw(data):
    figure, ax = new_figure()
    draw_series(ax, data, "rebound", linestyle="none", **MARKERS[0])
    draw_series(ax, data, "slope", linestyle="--")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(r"$-\dot{x}_n(\infty)$")
    ax.legend(loc="upper right")
    return figure
