"""Elastic constants and densities of the ball materials an experiment file may name.

This module owns the presets behind ``material = "steel"`` (``units = "si"``): Young's
modulus E (Pa), Poisson's ratio nu and density rho (kg/m^3) of each material, and where
each number comes from. It is data only: the Hertz law that turns them into contact
stiffnesses is ``chainrun.solver.physics.hertz_stiffness``, and the experiment file
(``chainrun.config``) is what picks a preset per ball.

Constants of a real batch of balls differ from these by a few per cent (alloys, heat
treatment, and for polymers the rate of loading); give ``young``, ``poisson`` and
``density`` explicitly when they matter.

References
----------
.. [C] W. D. Callister and D. G. Rethwisch, *Materials Science and Engineering: An
   Introduction*, 9th ed., Wiley (2014), Appendix B: Tables B.1 (density), B.2
   (modulus of elasticity) and B.3 (Poisson's ratio).
.. [CFF] C. Coste, E. Falcon and S. Fauve, "Solitary waves in a chain of beads under
   Hertz contact", Phys. Rev. E 56, 6104 (1997): hardened chrome-steel bearing beads.
.. [D05] C. Daraio, V. F. Nesterenko, E. B. Herbold and S. Jin, "Strongly nonlinear
   waves in a chain of Teflon beads", Phys. Rev. E 72, 016603 (2005).
.. [S] J. F. Shackelford, Y.-H. Han, S. Kim and S.-H. Kwon (eds.), *CRC Materials
   Science and Engineering Handbook*, 4th ed., CRC Press (2015): cemented tungsten
   carbide; the density of WC from the *CRC Handbook of Chemistry and Physics*.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["MATERIALS", "Material", "material"]


@dataclass(frozen=True)
class Material:
    """An isotropic elastic solid: Young's modulus ``young`` (Pa), Poisson's ratio
    ``poisson`` and density ``density`` (kg/m^3), with the source of the numbers."""

    name: str
    young: float
    poisson: float
    density: float
    source: str


#: The presets, by the name an experiment file uses.
MATERIALS: dict[str, Material] = {m.name: m for m in (
    Material("steel", 207e9, 0.30, 7850.0,
             "plain carbon steel AISI 1020 [C]"),
    Material("stainless_steel", 193e9, 0.30, 8000.0,
             "stainless steel AISI 316 [C]"),
    Material("chrome_steel", 203e9, 0.30, 7780.0,
             "chrome-steel bearing beads (AISI 52100 / 100Cr6) [CFF]"),
    Material("brass", 110e9, 0.35, 8530.0,
             "cartridge brass C26000, 70Cu-30Zn [C]"),
    Material("aluminium", 69e9, 0.33, 2700.0,
             "aluminium alloy 6061 [C]"),
    Material("glass", 69e9, 0.23, 2500.0,
             "soda-lime glass [C]"),
    Material("ptfe", 1.46e9, 0.46, 2200.0,
             "PTFE (Teflon) beads, modulus measured in impact [D05]"),
    Material("tungsten_carbide", 630e9, 0.24, 15600.0,
             "cemented tungsten carbide [S]"),
)}


def material(name: str) -> Material:
    """The preset called ``name``; KeyError (with the known names) if there is none."""
    try:
        return MATERIALS[name]
    except KeyError:
        raise KeyError(f"unknown material {name!r} (known: {', '.join(MATERIALS)})") from None
