"""The physical plant's parameters and the small records it hands out: the fatigue law, the
model constants (``PhysicalParams``; the coil and body thermal models in ``thermal``), a
logged state change (``Transition``) and the table plant's view of actuators and limbs
(``PlantView``) that ``PhysicalPlant.params`` offers its callers."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

from ..body import DEFAULT_WORKING_STRAIN, default_length_mm
from . import materials as mat
from .thermal import BodyThermal, CoilGeometry


@dataclass(frozen=True)
class FatigueLaw:
    """Functional fatigue of NiTi under thermal cycling: recoverable stroke falls and the
    transformation temperatures drift, both saturating (Lagoudas (ed.), "Shape Memory Alloys",
    Springer 2008, ch. 7; Mammano & Dragoni, Int. J. Fatigue 2014: a few % to tens of % stroke
    loss and several K of shift over 10³–10⁵ cycles). Representative values."""

    stroke_loss: float = 0.25        # fraction lost after many cycles
    stroke_cycles: float = 20000.0   # e-folding cycles of the loss
    shift_c: float = 6.0             # transformation temperatures rise by this much
    shift_cycles: float = 5000.0

    def stroke(self, n: float) -> float:
        return 1.0 - self.stroke_loss * (1.0 - math.exp(-n / self.stroke_cycles))

    def shift(self, n: float) -> float:
        return self.shift_c * (1.0 - math.exp(-n / self.shift_cycles))


@dataclass(frozen=True)
class PhysicalParams:
    coil: CoilGeometry = CoilGeometry()
    body_thermal: BodyThermal = BodyThermal()
    length_mm: float | None = None     # None: the robot file's [plant] length_mm (default from its contacts)
    coil_offset_mm: float = 2.0
    working_strain: float | None = None  # None: the robot file's [plant] working_strain (default 0.06)
    mech_tau_s: float = 0.03
    friction_band_deg: float = 12.0     # soft pad peel / bed-in range (estimate)
    materials: dict = field(default_factory=lambda: dict(mat.MATERIALS))
    fatigue: FatigueLaw = FatigueLaw()
    simultaneous_s: float = 0.03


@dataclass(frozen=True)
class Transition:
    t_s: float
    src: int
    dst: int
    reward_mm: float    # centre-of-mass displacement since the previous transition

    def __iter__(self):
        return iter((self.t_s, self.src, self.dst, self.reward_mm))


@dataclass(frozen=True)
class ActView:
    name: str
    channel: int


@dataclass(frozen=True)
class LimbView:
    name: str
    psi_star_deg: tuple[float, ...]


@dataclass(frozen=True)
class PlantView:
    """What callers of the table plant read from ``plant.params``."""

    actuators: tuple[ActView, ...]
    limbs: tuple[LimbView, ...]
    step_mm: float = 1.0


#: The robot file's coil keys (``[plant]``, per actuator) and the ``CoilGeometry`` field each sets.
_COIL_FIELDS = {"wire_diameter_mm": ("wire_diameter_m", 1e-3), "coil_diameter_mm": ("coil_outer_diameter_m", 1e-3),
                "coil_length_mm": ("coil_length_m", 1e-3), "as_c": ("as_c", 1.0), "af_c": ("af_c", 1.0),
                "ms_c": ("ms_c", 1.0), "mf_c": ("mf_c", 1.0)}


def coil_geometries(p: PhysicalParams, robot: Any, n_actuators: int) -> list[CoilGeometry]:
    """Each coil: ``p.coil`` with what the robot file's ``[plant]`` says of that actuator's wire
    and transformation temperatures (``PlantSection.coil``)."""
    given = getattr(getattr(robot, "plant", None), "coil", None) or {}
    return [dataclasses.replace(p.coil, **{_COIL_FIELDS[k][0]: v[j] * _COIL_FIELDS[k][1] for k, v in given.items()})
            for j in range(n_actuators)]


def robot_working_strain(robot: Any) -> float:
    """The robot file's ``[plant] working_strain`` (its default where the robot has no section)."""
    return float(getattr(getattr(robot, "plant", None), "working_strain", DEFAULT_WORKING_STRAIN))


def robot_length_mm(robot: Any, n_limbs: int) -> float:
    section = getattr(robot, "plant", None)
    length = getattr(section, "length_mm", None)
    return float(length) if length is not None else default_length_mm(n_limbs)


def coil_time_constant_s(robot: Any, n_actuators: int, p: PhysicalParams | None = None) -> float:
    """The longest thermal time constant of the robot's coils in still air at 25 °C: heat capacity
    over the conductance to the air (convection at 80 °C, as the plant takes it) and to the body,
    ≈ 1.26 s for the BMX100-class coil. A first-order coil's temperature rise is its duty smoothed
    with it; the firmware of builds that carry the coil's heat (core/sma.h) smooths each coil's
    duty with it. The longest: that coil cools the slowest, and a shorter one settles no hotter."""
    p = p or PhysicalParams()
    return max(g.heat_capacity_j_k / (g.convection_w_k(80.0, 25.0, 1.0) + g.coil_to_body_w_k)
               for g in coil_geometries(p, robot, n_actuators))
