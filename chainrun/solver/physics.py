"""Conserved quantities of the line, in paper units (pure numpy, any shape of batch).

The one home of the energy and momentum formulas; the solver's diagnostics, the run
files' observables and the analysis all call these.
"""

from __future__ import annotations

import numpy as np


def compressions(x: np.ndarray) -> np.ndarray:
    """Compression of each contact, ``c_j = x_j - x_{j+1}``; shape (..., N-1)."""
    x = np.asarray(x, dtype=float)
    return x[..., :-1] - x[..., 1:]


def momentum(v: np.ndarray) -> np.ndarray:
    """Total momentum ``sum v``; shape (...)."""
    return np.asarray(v, dtype=float).sum(axis=-1)


def kinetic_energy(v: np.ndarray) -> np.ndarray:
    """``sum v^2 / 2``; shape (...)."""
    v = np.asarray(v, dtype=float)
    return 0.5 * (v * v).sum(axis=-1)


def potential_energy(x: np.ndarray, alpha: float) -> np.ndarray:
    """``sum c_+^(alpha+1) / (alpha+1)`` over contacts; shape (...)."""
    c = np.clip(compressions(x), 0.0, None)
    return (c ** (alpha + 1.0)).sum(axis=-1) / (alpha + 1.0)
