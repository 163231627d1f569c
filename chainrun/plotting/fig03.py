"""Figure 3: the velocity wave at the times balls 10, 20, 30 and 40 lose contact."""

from __future__ import annotations

from chainrun.plotting.common import draw_loss_waves


def draw(data):
    return draw_loss_waves(data, r"$\dot{x}_n$", legend_loc="lower right", legend_ncol=2)
