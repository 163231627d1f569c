"""Figure 13: rebound velocities against n/K, K = 10, 20, 30, 40, 60, 80."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    for name, marker in zip(series_names(data, "data"), MARKERS):
        draw_series(ax, data, name, linestyle="none", **marker)
    ax.set_xlabel(r"$n/K$")
    ax.set_ylabel(r"$-\dot{x}_n(\infty)$")
    ax.set_xlim(0.0, 1.0)
    ax.set_ylim(0.0, None)
    ax.legend(loc="upper right")
    return figure
