"""Figure 5: the self-similar impulse wave against the solution of (4.9)."""

from __future__ import annotations

from chainrun.plotting.common import MARKERS, draw_series, new_figure, series_names


def draw(data):
    figure, ax = new_figure()
    for name, marker in zip(series_names(data, "data"), MARKERS):
        draw_series(ax, data, name, linestyle="none", **marker)
    for name in series_names(data, "theory"):
        draw_series(ax, data, name, linestyle="-")
    ax.set_xlabel(r"$(n - n_1 - 0.25)/a^2$")
    ax.set_ylabel(r"$\dot{x}_n\, a$")
    ax.set_xlim(-0.5, 4.0)
    ax.axhline(0.0, color="black", linewidth=0.5)
    ax.legend(loc="upper right")
    return figure
