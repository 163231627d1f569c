"""Figure 11: impact by three balls, displacements at t = 10, 20, ..., 100 (N = 100)."""

from __future__ import annotations

from chainrun.plotting.common import draw_displacement_waves


def draw(data):
    return draw_displacement_waves(data, n_max=100.0)
