"""Figure 9: Hertz rebound velocities (semi-log) with the paper's line 0.084 exp(-0.55 n)."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure


def draw(data):
    figure, ax = new_figure()
    draw_series(ax, data, "rebound", linestyle="none", **MARKERS[1])
    draw_series(ax, data, "printed", linestyle="--")
    ax.set_yscale("log")
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(r"$-\dot{x}_n(\infty)$")
    ax.set_xlim(0.0, 20.5)
    ax.legend(loc="upper right")
    return figure
