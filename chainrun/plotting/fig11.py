"""Figure 11: impact by three balls, displacements at t = 10, 20, ..., 100 (N = 100)."""

from __future__ import annotations

from chainrun.plotting.common import draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    names = series_names(data, "data")
    for name in names:
        draw_series(ax, data, name, linestyle="-")
    # label each curve with its time at the foot of its wave front
    for name in names:
        x = data.arrays[f"series/{name}/x"]
        y = data.arrays[f"series/{name}/y"]
        foot = x[y > 1e-3].max()
        ax.annotate(data.attrs[f"series/{name}"]["label"].replace("t = ", "t="),
                    xy=(foot, 0.0), xytext=(1, 2), textcoords="offset points",
                    ha="left", va="bottom", fontsize=6, rotation=90)
    ax.set_xlabel(r"$n$")
    ax.set_ylabel(r"$x_n$")
    ax.set_xlim(0.0, 100.0)
    ax.set_ylim(0.0, None)
    return figure
