"""Nesterenko's long-wave solitary wave for Hertz contacts (paper section 5b).

This module owns the formulas of the long-wavelength theory, in the paper's units
(alpha = 3/2, every coefficient 1). The strain of the wave is::

    dx/dn = -A sin^4( sqrt(2/5) (n - c t) )   for 0 <= sqrt(2/5)(n - c t) <= pi,

and zero outside one period, with ``c^2 = (4/5) A^(1/2)``. Every quantity below follows
from A; the paper fixes A by equating the net displacement of the wave to the simulated
saturated displacement (1.354).

References
----------
.. [1] V. F. Nesterenko, "Propagation of nonlinear compression pulses in granular
   media", J. Appl. Mech. Tech. Phys. 24, 733-743 (1983).
.. [2] E. J. Hinch and S. Saint-Jean (1999), section 5b.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "DISPLACEMENT_FACTOR",
    "NesterenkoWave",
    "from_amplitude",
    "from_displacement",
    "velocity_change_from_force_law",
]

#: Net displacement per unit amplitude: ``int sin^4 dn`` over one period, 3 pi sqrt5 / (8 sqrt2).
DISPLACEMENT_FACTOR = 3.0 * np.pi * np.sqrt(5.0) / (8.0 * np.sqrt(2.0))
_ENERGY_FACTOR = np.pi * np.sqrt(2.0) / (128.0 * np.sqrt(5.0))
_K = np.sqrt(2.0 / 5.0)


@dataclass(frozen=True)
class NesterenkoWave:
    """The solitary wave of amplitude ``A`` and its integral properties.

    Attributes
    ----------
    amplitude : float
        A, the largest strain ``-dx/dn``.
    speed : float
        ``c = (2/sqrt5) A^(1/4)``.
    displacement : float
        Net displacement of a ball as the wave passes, ``(3 pi sqrt5/(8 sqrt2)) A``.
    max_velocity : float
        ``A c``.
    max_force : float
        Largest force by the two-term law (5.1), ``(9/10) A^(3/2)``.
    max_force_leading : float
        Largest force by the leading term alone, ``A^(3/2)``.
    momentum : float
        ``(3 pi sqrt5/(8 sqrt2)) A c``.
    kinetic_energy, potential_energy : float
        ``35 pi sqrt2/(128 sqrt5) A^(5/2)`` and ``28 pi sqrt2/(128 sqrt5) A^(5/2)``.
    width : float
        Length of the wave in balls, ``pi / sqrt(2/5)``.
    """

    amplitude: float
    speed: float
    displacement: float
    max_velocity: float
    max_force: float
    max_force_leading: float
    momentum: float
    kinetic_energy: float
    potential_energy: float
    width: float

    def strain(self, s) -> np.ndarray:
        """``-dx/dn`` at ``s = n - c t`` (the wave occupies 0 <= s <= width)."""
        s = np.asarray(s, dtype=float)
        inside = (s >= 0.0) & (s <= self.width)
        return np.where(inside, self.amplitude * np.sin(_K * s) ** 4, 0.0)

    def force(self, s) -> np.ndarray:
        """Contact force by (5.1), ``(3/5) A^(3/2) (sin^6 + sin^4 / 2)``, at ``s``."""
        s = np.asarray(s, dtype=float)
        inside = (s >= 0.0) & (s <= self.width)
        sn = np.sin(_K * s)
        return np.where(inside, 0.6 * self.amplitude**1.5 * (sn**6 + 0.5 * sn**4), 0.0)

    def velocity(self, s) -> np.ndarray:
        """Ball velocity ``c (-dx/dn)`` at ``s``."""
        return self.speed * self.strain(s)


def from_amplitude(amplitude: float) -> NesterenkoWave:
    """The wave of strain amplitude ``A``."""
    a = float(amplitude)
    c = 2.0 / np.sqrt(5.0) * a**0.25
    return NesterenkoWave(
        amplitude=a,
        speed=c,
        displacement=DISPLACEMENT_FACTOR * a,
        max_velocity=a * c,
        max_force=0.9 * a**1.5,
        max_force_leading=a**1.5,
        momentum=DISPLACEMENT_FACTOR * a * c,
        kinetic_energy=35.0 * _ENERGY_FACTOR * a**2.5,
        potential_energy=28.0 * _ENERGY_FACTOR * a**2.5,
        width=np.pi / _K,
    )


def from_displacement(displacement: float) -> NesterenkoWave:
    """The wave whose net displacement is ``displacement`` (the paper uses 1.354)."""
    return from_amplitude(float(displacement) / DISPLACEMENT_FACTOR)


def velocity_change_from_force_law() -> float:
    """Relative change of the speed predicted from a measured peak force when the force is
    taken as (5.1) (peak 0.9 A^(3/2)) rather than the leading term (peak A^(3/2)).

    At a given peak force F, A is larger by ``0.9^(-2/3)`` and ``c ~ A^(1/4)`` by
    ``0.9^(-1/6)``: the change is ``0.9^(-1/6) - 1`` (the paper: "less than 2%").
    """
    return 0.9 ** (-1.0 / 6.0) - 1.0
