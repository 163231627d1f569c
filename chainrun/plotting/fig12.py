"""Figure 12: ejected velocities against (N - n + 1/2)/K, K = 3, 6, 9, 12 (semi-log)."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    for name, marker in zip(series_names(data, "data"), MARKERS):
        draw_series(ax, data, name, linestyle="none", **marker)
    ax.set_yscale("log")
    ax.set_xlabel(r"$(N - n + \frac{1}{2})/K$")
    ax.set_ylabel(r"$\dot{x}_n(\infty)$")
    ax.set_xlim(0.0, 2.5)
    ax.legend(loc="upper right")
    return figure
