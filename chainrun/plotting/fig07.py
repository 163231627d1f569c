"""Figure 7: the balls flying off the end, scaled, for N = 100, 200, 400 and 800."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    for name, marker in zip(series_names(data, "data"), MARKERS):
        draw_series(ax, data, name, linestyle="none", **marker)
    ax.axhline(0.0, color="black", linewidth=0.5)
    ax.set_xlabel(r"$(N - n)/N^{1/3}$")
    ax.set_ylabel(r"$\dot{x}_n(\infty)\, N^{1/6}$")
    ax.set_xlim(-0.1, 3.0)
    ax.legend(loc="upper right")
    return figure
