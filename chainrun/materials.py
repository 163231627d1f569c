"""Elastic constants and densities of the ball materials an experiment file may name.

This module owns the presets behind ``material = "steel"`` (``units = "si"``): Young's
modulus E (Pa), Poisson's ratio nu and density rho (kg/m^3) of each material, and where
each number comes from. It is data only: the Hertz law that turns them into contact
stiffnesses is ``chainrun.solver.physics.hertz_stiffness``, and the experiment file
(``chainrun.config``) is what picks a preset per ball.

Constants of a real batch of balls differ from these by a few per cent (alloys, heat
treatment, and for polymers the rate of loading); give ``young``, ``poisson`` and
``density`` explicitly when they matter. Each number below is one that the cited source
states (for a range, the middle of it, as the source string says); sources are per
number where one source did not give all three.

References
----------
.. [C3] W. D. Callister and D. G. Rethwisch, *Fundamentals of Materials Science and
   Engineering: An Integrated Approach*, 3rd ed., Wiley (2008), Appendix B: Table B.1
   (density, p. 804) and Table B.2 (modulus of elasticity, pp. 804 and 807); read at
   https://issuhub.com/view/index?id=5550&pageIndex=832 and
   https://issuhub.com/view/index/5550?pageIndex=835.
.. [C8] W. D. Callister and D. G. Rethwisch, *Materials Science and Engineering: An
   Introduction*, 8th ed., Wiley (2010), Appendix B, Table B.3 (Poisson's ratio,
   continued, p. A11); read at
   https://www.yumpu.com/en/document/view/55454363/callister-an-introduction-8th-edition/925.
.. [CB1] Callister, Appendix B, Table B.1 "Room-Temperature Density Values for Various
   Engineering Materials" (p. 441 of the edition reproduced at
   https://ar.scribd.com/document/238232402/Material-Density-Chart-2).
.. [MSO] Metal Suppliers Online, "1020" carbon steel data sheet (physical data: specific
   gravity 7.86, Poisson's ratio 0.3), https://esm.elwd.com/product/1020/.
.. [MW316] MatWeb (ASM), "AISI Type 316 Stainless Steel, annealed bar",
   http://asm.matweb.com/search/SpecificMaterial.asp?bassnum=MQ316J.
.. [MIF] MakeItFrom.com material data sheets: "1/8-Hard 316 Stainless Steel",
   https://makeitfrom.com/material-properties/1-8-Hard-316-Stainless-Steel; "Annealed
   Soda-Lime Glass", https://www.makeitfrom.com/material-properties/Annealed-Soda-Lime-Glass;
   "Tungsten Carbide (WC)",
   https://www.makeitfrom.com/material-properties/Tungsten-Carbide-WC.
.. [ST52100] Steel Tubes India, "Differences Between 52100 & E52100 Steel" (AISI 52100
   physical and mechanical properties),
   https://www.stindia.com/article/difference-between/difference-between-52100-e52100-steel.html.
.. [OLIN] Olin Brass, "C26000 (ASTM B36) Cartridge Brass Alloy Data Specifications",
   http://olinbrass.com/resources/alloy-data-specifications/C26000-%28ASTM-B36%29-Cartridge-Brass.
.. [DOW] N. E. Dowling, *Mechanical Behavior of Materials*, Table 5.2 "Elastic Constants
   for Various Materials at Ambient Temperature" (p. 202 of the copy read at
   https://digilib.universitaspertamina.ac.id/ebook/%20%20Mechanical%20Behavior%20of%20Materials/files/basic-html/page201.html).
.. [AL6061] "Aluminum 6061-T6 Data Sheet", https://www.mfgproto.com/aluminum-6061-t6-data-sheet/.
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
             "plain carbon steel AISI 1020: E = 207 GPa [C3, Table B.2], "
             "rho = 7.85 g/cm^3 [CB1], nu = 0.3 [MSO]"),
    Material("stainless_steel", 193e9, 0.28, 8000.0,
             "stainless steel AISI 316, annealed: E = 193 GPa, rho = 8 g/cc [MW316]; "
             "nu = 0.28 [MIF, 316]"),
    Material("chrome_steel", 200e9, 0.285, 7810.0,
             "chromium bearing steel AISI 52100 (100Cr6): rho = 7.81 g/cm^3; E = 200 GPa, "
             "the middle of the stated 190-210 GPa; nu = 0.285, the middle of the stated "
             "0.27-0.30 [ST52100]"),
    Material("brass", 112e9, 0.35, 8530.0,
             "cartridge brass C26000, 70Cu-30Zn: E = 16e6 psi = 112 kN/mm^2, "
             "rho = 8.53 g/cm^3 [OLIN]; nu = 0.350 (brass, 70Cu-30Zn) [DOW]"),
    Material("aluminium", 68.9e9, 0.33, 2700.0,
             "aluminium alloy 6061-T6: E = 68.9 GPa, nu = 0.33, rho = 2.70 g/cc [AL6061]"),
    Material("glass", 71e9, 0.23, 2400.0,
             "annealed soda-lime glass: E = 71 GPa, nu = 0.23, rho = 2.4 g/cm^3 [MIF]"),
    Material("ptfe", 0.475e9, 0.46, 2170.0,
             "PTFE (Teflon): E = 0.475 GPa, the middle of the stated 0.40-0.55 GPa "
             "[C3, Table B.2]; nu = 0.46 [C8, Table B.3]; rho = 2.17 g/cm^3 "
             "[C3, Table B.1]; a handbook (quasi-static) modulus: a polymer's depends on the "
             "rate of loading, so give young when it matters"),
    Material("tungsten_carbide", 630e9, 0.24, 15000.0,
             "tungsten carbide (WC): E = 630 GPa, nu = 0.24, rho = 15 g/cm^3 [MIF]"),
)}


def material(name: str) -> Material:
    """The preset called ``name``; KeyError (with the known names) if there is none."""
    try:
        return MATERIALS[name]
    except KeyError:
        raise KeyError(f"unknown material {name!r} (known: {', '.join(MATERIALS)})") from None
