"""Properties of ``chainrun.solver.simulate`` over random lines (Hypothesis).

For random N <= 60, 1 <= K <= N and alpha in [1, 3], every run must reach the
terminal state with momentum and energy conserved, event times ordered, and final
velocities non-decreasing along the line (no pair approaching faster than the
velocity floor).
"""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from chainrun.solver import Line, Outcome, simulate, velocity_floor
from chainrun.solver.physics import line_kinetic_energy, line_momentum, line_potential_energy

#: One table of tolerances for this file.
TOL = {
    "momentum": 1e-12,   # absolute; the initial momentum is K
    "energy": 1e-10,     # relative to the initial energy K / 2
}

SETTINGS = settings(max_examples=25, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow])


@st.composite
def lines(draw):
    """(N, K, alpha) with N <= 60, 1 <= K <= N, alpha in [1, 3] (ends and 3/2 likely)."""
    n = draw(st.integers(min_value=1, max_value=60))
    k = draw(st.integers(min_value=1, max_value=n))
    alpha = draw(st.one_of(st.sampled_from([1.0, 1.5, 3.0]),
                           st.floats(min_value=1.0, max_value=3.0)))
    return n, k, alpha


@SETTINGS
@given(lines())
def test_terminal_state_and_conservation(line):
    n, k, alpha = line
    paper = Line.paper(n, k, alpha)
    sol = simulate(paper)
    where = f"N={n} K={k} alpha={alpha!r}: {sol.message}"

    # Outcome: the terminal state, reached.
    assert sol.outcome is Outcome.TERMINAL, where
    assert sol.terminal, where
    v = sol.final_velocity
    x = sol.final_position
    assert v.shape == (n,) and x.shape == (n,)
    assert np.all(np.isfinite(v)) and np.all(np.isfinite(x)), where

    # Momentum: exactly K initially.
    assert abs(line_momentum(v, paper.mass) - k) <= TOL["momentum"], where
    assert sol.diagnostics.momentum_error <= TOL["momentum"], where

    # Energy: K/2 initially, recomputed here from the final state.
    energy = line_kinetic_energy(v, paper.mass) + line_potential_energy(x, paper)
    assert abs(energy - k / 2) <= TOL["energy"] * (k / 2), where
    assert sol.diagnostics.energy_error <= TOL["energy"], where

    # Event log: ordered times, valid contacts.
    assert np.all(np.diff(sol.event_time) >= 0), where
    assert np.all((sol.event_contact >= 0) & (sol.event_contact < max(n - 1, 0))), where
    assert np.all(sol.event_time <= sol.end_time), where

    # Terminal state: no neighbours approaching faster than the floor.
    floor = velocity_floor(sol.diagnostics.rtol)
    gaps = np.diff(v)
    assert np.all(gaps >= -floor), (
        f"{where}; approaching pairs at {np.flatnonzero(gaps < -floor).tolist()}, "
        f"min dv = {gaps.min():.3e}")
