"""Figure 6: v_n n^(5/6) (continuous) and v_n n^(3/4) (broken) against 1/n, N = 200."""

from __future__ import annotations

from chainrun.plotting.common import draw_series, new_figure


def draw(data):
    figure, ax = new_figure()
    draw_series(ax, data, "n^5:6", linestyle="-")
    draw_series(ax, data, "n^3:4", linestyle="--")
    ax.set_xlabel(r"$1/n$")
    ax.set_ylabel(r"$\dot{x}_n(\infty)\, n^{5/6}$,  $\dot{x}_n(\infty)\, n^{3/4}$")
    ax.set_xlim(0.0, 1.0)
    ax.legend(loc="lower right")
    return figure
