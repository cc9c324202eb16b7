"""SMA coil thermal model: Joule heating, natural convection, latent heat, a body node.

One node per coil and one for the body::

    C_c dT_c/dt + m_c L dα/dt = P − hA (T_c − T_amb) − G_cb (T_c − T_b)
    C_b dT_b/dt = Σ_c G_cb (T_c − T_b) − (hA)_b (T_b − T_amb)

P = duty · V² / R. The latent heat L of the martensite↔austenite transformation is absorbed
while α rises (As→Af) and given back while it falls (Ms→Mf): each step first integrates the
sensible part exactly (exponential step), lets the hysteresis model move α, then takes
m_c L Δα out of (or puts it back into) the coil's temperature. Coil geometry gives the numbers:

* wire length = turns × π × mean coil diameter, turns = coil length / wire diameter
  (close-wound helix; a straight wire, as wide as its coil, is its coil length);
  R = ρ L / (π d²/4); C = ρ_NiTi · volume · c_p.
* convection: Churchill & Chu (1975) correlation for a horizontal cylinder in still air,
  Nu = {0.60 + 0.387 Ra^(1/6) / [1 + (0.559/Pr)^(9/16)]^(8/27)}², applied to the bare wire,
  times the fraction of the wire surface a close-wound coil exposes to the air (*estimate*
  0.6; a straight wire exposes all of it), plus linearised radiation 4 ε σ T³ (ε ≈ 0.3, oxidised NiTi, *estimate*).
* conduction coil → body through the channel it lies in: G_cb (*estimate* 1.5 mW/K).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from . import materials as mat

STEFAN_BOLTZMANN = 5.670e-8


@dataclass(frozen=True)
class CoilGeometry:
    """A Toki BioMetal Helix BMX100-class coil: 0.1 mm NiTi wire, 0.4 mm outer diameter,
    installed length 30 mm (the coil spans a little over half the 80 mm body)."""

    wire_diameter_m: float = 0.1e-3
    coil_outer_diameter_m: float = 0.4e-3
    coil_length_m: float = 30e-3
    exposed_fraction: float = 0.6
    emissivity: float = 0.3
    coil_to_body_w_k: float = 1.5e-3
    # transformation temperatures, °C (BioMetal "70 °C" alloy, band widened for a coil that is
    # not uniformly hot; see proleg.sim.sma.SmaParams)
    as_c: float = 64.0
    af_c: float = 82.0
    ms_c: float = 56.0
    mf_c: float = 38.0

    @property
    def turns(self) -> float:
        return self.coil_length_m / self.wire_diameter_m

    @property
    def straight(self) -> bool:
        """A straight wire (Flexinol-style): the coil is as wide as its wire."""
        return self.coil_outer_diameter_m <= self.wire_diameter_m

    @property
    def wire_length_m(self) -> float:
        if self.straight:
            return self.coil_length_m
        mean_d = self.coil_outer_diameter_m - self.wire_diameter_m
        return self.turns * math.pi * mean_d

    @property
    def wire_area_m2(self) -> float:
        return math.pi * self.wire_diameter_m ** 2 / 4.0

    @property
    def resistance_ohm(self) -> float:
        return mat.NITI_RESISTIVITY_OHM_M * self.wire_length_m / self.wire_area_m2

    @property
    def mass_kg(self) -> float:
        return mat.NITI_DENSITY_KG_M3 * self.wire_area_m2 * self.wire_length_m

    @property
    def heat_capacity_j_k(self) -> float:
        return self.mass_kg * mat.NITI_SPECIFIC_HEAT_J_KGK

    @property
    def latent_j(self) -> float:
        """Heat absorbed by a full martensite → austenite transformation."""
        return self.mass_kg * mat.NITI_LATENT_HEAT_J_KG

    def convection_w_k(self, t_wire_c: float = 80.0, t_air_c: float = 25.0, scale: float = 1.0) -> float:
        """hA of the coil to the air (Churchill–Chu + radiation), at a representative wire
        temperature; ``scale`` is the convection condition (draught, enclosure)."""
        d = self.wire_diameter_m
        dt = max(t_wire_c - t_air_c, 1.0)
        t_film_k = (t_wire_c + t_air_c) / 2.0 + 273.15
        ra = (mat.GRAVITY_M_S2 * (1.0 / t_film_k) * dt * d ** 3
              / (mat.AIR_KINEMATIC_VISCOSITY_M2_S * mat.AIR_THERMAL_DIFFUSIVITY_M2_S))
        nu = (0.60 + 0.387 * ra ** (1.0 / 6.0) / (1.0 + (0.559 / mat.AIR_PRANDTL) ** (9.0 / 16.0)) ** (8.0 / 27.0)) ** 2
        h = nu * mat.AIR_CONDUCTIVITY_W_MK / d
        exposed = 1.0 if self.straight else self.exposed_fraction  # a close-wound coil shades its own turns
        area = math.pi * d * self.wire_length_m * exposed
        t_mean_k = (t_wire_c + t_air_c) / 2.0 + 273.15
        h_rad = 4.0 * self.emissivity * STEFAN_BOLTZMANN * t_mean_k ** 3
        return (h * scale + h_rad) * area


@dataclass(frozen=True)
class BodyThermal:
    """The body as one lumped node: 3.3 g of TangoPlus, 80 × 8 × 4 mm outer surface."""

    mass_kg: float = 3.3e-3
    area_m2: float = 2 * (80e-3 * 8e-3 + 80e-3 * 4e-3 + 8e-3 * 4e-3)

    def heat_capacity_j_k(self) -> float:
        return self.mass_kg * mat.BODY_SPECIFIC_HEAT_J_KGK

    def convection_w_k(self, scale: float = 1.0) -> float:
        return mat.BODY_CONVECTION_W_M2K * self.area_m2 * scale
