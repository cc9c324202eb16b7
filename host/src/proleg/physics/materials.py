"""Physical constants of the simulated robot's materials, each with its source.

Numbers marked *estimate* are representative values chosen within the published range for
the material class; docs/plant.md lists them all with the reasoning.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..robot_plant import FRICTION_MECHANISMS

# --- NiTi (Nitinol / Toki BioMetal) ------------------------------------------------------------
# Density 6.45 g/cm³, specific heat 0.20 cal/(g·K) = 0.837 J/(g·K), latent heat of
# transformation 5.78 cal/g = 24.2 J/g, resistivity 76 µΩ·cm (martensite) / 82 µΩ·cm
# (austenite): Dynalloy, "Technical characteristics of Flexinol actuator wires" (F1140Rev J),
# table "Physical properties"; the same values in Jackson, Wagner & Wasilewski, "55-Nitinol —
# the alloy with a memory", NASA SP-5110 (1972).
NITI_DENSITY_KG_M3 = 6450.0
NITI_SPECIFIC_HEAT_J_KGK = 837.0
NITI_LATENT_HEAT_J_KG = 24.2e3
#: Above this a coil is being ruined (anneal, loss of memory, fatigue): Dynalloy advises
#: against prolonged heating far above Af (F1140Rev J, "Overheating"); Toki BioMetal's
#: working range ends near 100 °C. The claim bench calls an open-loop run past it overheated.
NITI_OVERHEAT_C = 120.0


def shown_c(t: float) -> str:
    """A temperature to the degree, or to 0.1 °C where the degree would read as the
    ``NITI_OVERHEAT_C`` line itself ("reached 120 °C, past the 120 °C" for 120.3)."""
    return f"{t:.1f}" if f"{t:.0f}" == f"{NITI_OVERHEAT_C:.0f}" else f"{t:.0f}"
#: Where the trained shape itself goes: NiTi wire is shape-set by annealing at about
#: 400–550 °C (Pelton, DiCello & Miyazaki, "Optimisation of processing and properties of
#: medical-grade Nitinol wire", Min. Invas. Ther. & Allied Technol. 9 (2000); Dynalloy
#: F1140Rev J). A supply that can hold a coil there within the safety envelope is a mistake.
NITI_ANNEAL_C = 400.0
#: NiTi melts at about 1310 °C (ASM Handbook vol. 2, "Shape memory alloys"; Fort Wayne Metals'
#: Nitinol data sheet, 1310 °C). A steady state computed past it describes no wire: the wire is gone.
NITI_MELT_C = 1310.0
NITI_RESISTIVITY_OHM_M = 0.80e-6          # between martensite (0.76) and austenite (0.82)

# --- air at a film temperature of ≈ 50 °C (1 atm) -----------------------------------------------
# Incropera & DeWitt, "Fundamentals of Heat and Mass Transfer", 6th ed., Table A.4 (air at 325 K).
AIR_CONDUCTIVITY_W_MK = 0.0282
AIR_KINEMATIC_VISCOSITY_M2_S = 18.2e-6
AIR_THERMAL_DIFFUSIVITY_M2_S = 25.9e-6
AIR_PRANDTL = 0.703
GRAVITY_M_S2 = 9.81

# --- body: TangoPlus (Stratasys PolyJet photopolymer, Shore A 26–28) ------------------------------
# Specific heat of cured acrylic photopolymers ≈ 1.4–1.7 J/(g·K) (*estimate*, PolyJet resins
# are acrylate networks; PMMA is 1.47 J/(g·K), Incropera Table A.3). Natural convection from a
# few-centimetre body: h ≈ 5–10 W/(m²·K) (Incropera §9).
BODY_SPECIFIC_HEAT_J_KGK = 1500.0
BODY_CONVECTION_W_M2K = 8.0


@dataclass(frozen=True)
class Material:
    """Dry-friction coefficients of one contact material on the default ground (paper, card)."""

    name: str
    mu_static: float
    mu_kinetic: float


# Soft elastomer (TangoPlus) conforms to the asperities of the ground (paper §II-C, Gorb 2001):
# μ ≈ 0.8–1.5 for rubber-like solids on paper/wood (Persson, "Sliding Friction", 2000, ch. 12:
# rubber μ ≈ 1). Hard acrylic (VeroClear, PMMA-like) on paper/wood: μ ≈ 0.3–0.5 (Bhushan,
# "Introduction to Tribology", 2013, Table 4.2, polymers on metals/wood). *estimates* within
# those ranges; the paper only says "sticky" and "slippery".
SOFT = Material("soft", mu_static=1.0, mu_kinetic=0.8)
HARD = Material("hard", mu_static=0.35, mu_kinetic=0.25)
MATERIALS = {"soft": SOFT, "hard": HARD}


def material(m: str | tuple[float, float], known: dict[str, Material] = MATERIALS) -> Material:
    """A level's material: a name from ``known``, or a lab's own pad as its (μs, μk) pair
    (``[[limb]] friction``, checked by proleg.robot_plant)."""
    if isinstance(m, str):
        return known[m]
    mu_s, mu_k = m
    return Material(f"pad μs {mu_s:g} / μk {mu_k:g}", mu_static=float(mu_s), mu_kinetic=float(mu_k))

# The paper's two friction mechanisms: the material touching at each level (level 0 = ψ < ψ*).
# The names are the robot file's (``[[limb]] friction``, checked by proleg.robot_plant).
MECHANISMS = dict(FRICTION_MECHANISMS)
