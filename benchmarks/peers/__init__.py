"""The peers: the tools a researcher would otherwise use for a line of balls.

Each peer is one module with a ``solve(n, k, alpha, t_stop, ...)`` function that
integrates the line (paper units, every coefficient 1; see ``chainrun.solver``)

    x_n'' = (x_{n-1} - x_n)_+^alpha - (x_n - x_{n+1})_+^alpha,
    x_n(0) = 0,  x_n'(0) = 1 for n <= K, 0 otherwise,

from t = 0 to ``t_stop`` and returns a ``PeerResult``. The peers share no code with
``chainrun`` nor with each other (only this result type), so that agreement between
them is evidence:

* ``scipy_dop853``: scipy's DOP853 with the active contact set fixed between events;
* ``rk4_paper``: the paper's fixed-step RK4, steps shortened onto contact openings
  (numba);
* ``heyoka_peer``: heyoka's Taylor integrator with one on/off parameter and one event
  per contact (optional: ``pip install 'chainrun[bench]'``).

``lammps_peer`` is of another kind: LAMMPS's granular model on a line of real spheres in
SI units (``SphereLine``), run as a whole ``lmp`` process at a fixed step (optional, in
the same extra); ``benchmarks.against_lammps`` compares it with chainrun on the same
lines.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["PeerResult", "PeerUnavailable"]


class PeerUnavailable(RuntimeError):
    """The peer cannot run here (an optional package is missing); the text says why."""


@dataclass(frozen=True)
class PeerResult:
    """One peer run.

    Attributes
    ----------
    tool : str
        Short name, e.g. ``"scipy"``.
    settings : str
        The accuracy settings used, for the table, e.g. ``"rtol=1e-12"``.
    t_end : float
        The time the state below is at.
    final_position, final_velocity : ndarray, shape (N,)
    steps : int
        Integration steps taken (accepted steps for adaptive methods).
    events : int
        Contact switches (openings and closings) the method handled.
    solve_time : float
        Wall time of the integration in seconds, without one-off compilation.
    compile_time : float
        Wall time of one-off compilation (JIT) in seconds; 0 if none.
    """

    tool: str
    settings: str
    t_end: float
    final_position: np.ndarray
    final_velocity: np.ndarray
    steps: int
    events: int
    solve_time: float
    compile_time: float = 0.0
