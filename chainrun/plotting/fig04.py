"""Figure 4: the displacement wave at the times balls 10, 20, 30 and 40 lose contact."""

from __future__ import annotations

from chainrun.plotting.common import draw_loss_waves


def draw(data):
    return draw_loss_waves(data, r"$x_n$", legend_loc="best")
