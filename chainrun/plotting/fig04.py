"""Figure 4: the displacement wave at the times balls 10, 20, 30 and 40 lose contact."""

from __future__ import annotations

from chainrun.plotting.common import draw_series, new_figure, series_names

LINESTYLES = ("-", "--", "-.", ":")


def draw(data):
    figure, ax = new_figure()
    for name, style in zip(series_names(data, "data"), LINESTYLES):
        draw_series(ax, data, name, linestyle=style)
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(r"$x_n$")
    ax.set_xlim(0.0, 50.0)
    ax.legend(loc="best")
    return figure
