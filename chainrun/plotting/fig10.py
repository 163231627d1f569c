"""Figure 10: impact by two balls, displacements at t = 5, 10, ..., 50 (N = 50)."""

from __future__ import annotations

from chainrun.plotting.common import draw_displacement_waves


def draw(data):
    return draw_displacement_waves(data, n_max=50.0)
