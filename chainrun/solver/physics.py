"""Forces and conserved quantities of the line (pure numpy, any shape of batch).

The one home of the energy and momentum formulas; the solver's diagnostics, the run
files' observables and the analysis all call these.
"""

from __future__ import annotations

import numpy as np


def compressions(x: np.ndarray) -> np.ndarray:
    """Compression of each contact, ``c_j = x_j - x_{j+1}``; shape (..., N-1)."""
    x = np.asarray(x, dtype=float)
    return x[..., :-1] - x[..., 1:]


def contact_forces(x: np.ndarray, alpha, stiffness=1.0) -> np.ndarray:
    """Force of each contact, ``kappa c_+^alpha`` (it never pulls); shape (..., N-1).

    ``alpha`` and ``stiffness`` are numbers or one per contact; the compressions are
    the plain differences of ``x`` (positions measured with the gaps taken out).
    """
    f = np.clip(compressions(x), 0.0, None) ** alpha
    return f if np.all(np.asarray(stiffness) == 1.0) else f * stiffness


def momentum(v: np.ndarray) -> np.ndarray:
    """Total momentum ``sum v``; shape (...)."""
    return np.asarray(v, dtype=float).sum(axis=-1)


def kinetic_energy(v: np.ndarray) -> np.ndarray:
    """``sum v^2 / 2``; shape (...)."""
    v = np.asarray(v, dtype=float)
    return 0.5 * np.einsum("...i,...i->...", v, v)


#: Contacts per block of ``potential_energy``: its temporaries stay small and reused.
_BLOCK = 2**16


def potential_energy(x: np.ndarray, alpha: float) -> np.ndarray:
    """``sum c_+^(alpha+1) / (alpha+1)`` over contacts; shape (...).

    By blocks of contacts, and the power only where c > 0: a snapshot of a long line
    is mostly balls at rest, and a fractional power, like a fresh temporary as long
    as the line, costs far more than the test.
    """
    x = np.asarray(x, dtype=float)
    total = np.zeros(x.shape[:-1])
    for i in range(0, x.shape[-1] - 1, _BLOCK):
        c = compressions(x[..., i:i + _BLOCK + 1])
        e = np.zeros_like(c)
        np.power(c, alpha + 1.0, out=e, where=c > 0.0)
        total += e.sum(axis=-1)
    return total[()] / (alpha + 1.0)
