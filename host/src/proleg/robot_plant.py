"""The robot file's optional ``[plant]`` table: the simulated body's physics, checked once.

ONE schema for both simulated plants. Every key is listed in ``PLANT_KEYS`` with its unit,
its allowed range, its default and the plants it applies to (``plants``): ``table`` (the
lookup plant, ``proleg.sim.plant``: its coil model and matrix keys), ``physical`` (the
physical plant, ``proleg.sim.physical``: its conditions — supply, air, wear, sensors and
world) or both (``supply_v``, ``ambient_c``: the same quantity in both; ``supply_v``'s default
differs because the two plants model different coils, ``physical_default``). The same
physical keys are what ``proleg sim --condition KEY=VALUE`` takes
(``proleg.sim.physical.conditions`` reads them from here). The table plant's defaults are
``proleg.sim.sma.SmaParams`` and ``proleg.sim.plant.PlantParams`` (a test keeps them in step);
the physical ones are documented with their sources in docs/plant.md. ``plant_section`` checks a ``[plant]`` table when the robot file
is loaded, so a misspelt key or a value out of range fails ``proleg gait`` and ``proleg build``
as it fails ``proleg sim``: one line naming the file, the key and what was expected.
The result, ``PlantSection``, holds every value resolved (defaults filled in, one number per
actuator or per limb where the key is per actuator or per limb); the simulator only consumes it.
docs/robot-file.md documents the same keys for users.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .body import DEFAULT_WORKING_STRAIN, default_length_mm
from .errors import RobotFileError
from .names import counted
from .robot_fields import toml_text
from .robot_transitions import UNIT_MM

FORBIDDEN = "x"


@dataclass(frozen=True)
class PlantKey:
    """One ``[plant]`` key: unit, range (``lo``..``hi``, open at ``lo`` when ``open_lo``,
    open at both ends when ``open_hi`` too), default, and whether it is per actuator or
    per limb (one number for all, or a list with one per [[actuator]] / [[limb]])."""

    name: str
    unit: str
    lo: float
    hi: float
    default: float | None
    per: str = ""            # "actuator", "limb" or "" (one number)
    open_lo: bool = False
    open_hi: bool = False
    doc: str = ""
    plants: tuple[str, ...] = ("table",)   # which simulated plants read it
    physical_default: float | None = None  # the physical plant's default when it differs

    def default_for(self, plant: str) -> float | None:
        if plant == "physical" and self.physical_default is not None:
            return self.physical_default
        return self.default

    def range_text(self) -> str:
        left = "(" if self.open_lo else "["
        right = ")" if self.open_hi else "]"
        unit = f" {self.unit}" if self.unit else ""
        return f"{left}{_g(self.lo)}, {_g(self.hi)}{right}{unit}"

    def accepts(self, v: float) -> bool:
        above = v > self.lo if self.open_lo else v >= self.lo
        below = v < self.hi if self.open_hi else v <= self.hi
        return above and below


def _g(x: float) -> str:
    return f"{x:g}"


BOTH = ("table", "physical")
PHYS = ("physical",)

# Defaults: a Toki BioMetal Helix BMX100-class coil and the paper's R1-class body; the sources
# of every number are in proleg/sim/sma.py (SmaParams) and proleg/sim/plant.py (PlantParams).
_KEYS = (
    PlantKey("resistance_ohm", "Ω", 0.0, 10_000.0, 36.0, "actuator", open_lo=True, doc="coil resistance"),
    PlantKey("supply_v", "V", 0.0, 60.0, 5.0, "actuator", open_lo=True, doc="supply voltage across the coil at duty 1",
             plants=BOTH, physical_default=7.4),
    PlantKey("heat_capacity_j_per_k", "J/K", 0.0, 10.0, 4.6e-3, "actuator", open_lo=True, doc="coil heat capacity C"),
    PlantKey("conductance_w_per_k", "W/K", 0.0, 10.0, 4.6e-3, "actuator", open_lo=True,
             doc="heat loss hA to the surroundings (τ = C / hA)"),
    PlantKey("as_c", "°C", -100.0, 300.0, 64.0, "actuator", doc="austenite start temperature (heating)", plants=BOTH),
    PlantKey("af_c", "°C", -100.0, 300.0, 82.0, "actuator", doc="austenite finish temperature (heating)", plants=BOTH),
    PlantKey("ms_c", "°C", -100.0, 300.0, 56.0, "actuator", doc="martensite start temperature (cooling)", plants=BOTH),
    PlantKey("mf_c", "°C", -100.0, 300.0, 38.0, "actuator", doc="martensite finish temperature (cooling)", plants=BOTH),
    PlantKey("max_strain", "", 0.0, 1.0, 0.3, "actuator", open_lo=True,
             doc="coil contraction at full transformation, fraction of its installed length"),
    PlantKey("psi_rest_deg", "°", -90.0, 90.0, 0.0, "limb", open_lo=True, open_hi=True,
             doc="contact angle ψ of the end with its coil cold"),
    PlantKey("direct_gain_deg", "°", -360.0, 360.0, 60.0,
             doc="ψ of an actuator's own end at full contraction (used when coupling_deg is not given)"),
    PlantKey("cross_gain_deg", "°", -360.0, 360.0, 27.0,
             doc="ψ of every other end at full contraction (used when coupling_deg is not given)"),
    PlantKey("coupling_deg", "°", -360.0, 360.0, None,
             doc="limbs × actuators matrix: ψ of limb i at full contraction of actuator j"),
    PlantKey("mech_tau_s", "s", 0.0, 10.0, 0.03, open_lo=True, doc="first-order lag of the soft body's ψ"),
    PlantKey("ambient_c", "°C", -50.0, 100.0, 25.0, doc="ambient (air and ground) temperature", plants=BOTH),
    PlantKey("step_mm", "mm", 0.0, 1000.0, 4.0, open_lo=True, doc="displacement per unit of the reward matrix"),
    PlantKey("noise_mm", "mm", 0.0, 1000.0, 0.0, doc="σ of the Gaussian noise added to each transition's displacement"),
    PlantKey("simultaneous_s", "s", 0.0, 10.0, 0.03, doc="limb changes this close together form one transition"),
    PlantKey("true_matrix", "reward units", -1e9, 1e9, None,
             doc="n × n ground-truth rewards for the simulator (numbers or 'x'); default: [transitions]"),
    # -- the physical plant's conditions (docs/plant.md: model, constants and sources) ----------
    PlantKey("power", "×", 0.2, 2.0, 1.0, plants=PHYS,
             doc="heating power factor at the coils (supply voltage² / nominal): supply sag or boost"),
    PlantKey("supply_ohm", "Ω", 0.0, 50.0, 0.0, plants=PHYS,
             doc="source resistance shared by all coils (a coil's supply sags while it draws, more when several draw "
                 "together)"),
    PlantKey("convection", "×", 0.2, 5.0, 1.0, plants=PHYS,
             doc="convective heat transfer factor (draught > 1, enclosure < 1)"),
    PlantKey("fatigue_cycles", "cycles", 0.0, 1e6, 0.0, plants=PHYS,
             doc="transformation cycles the coils have already made (stroke loss, temperature shift)"),
    PlantKey("fatigue_speedup", "×", 1.0, 1e5, 1.0, plants=PHYS,
             doc="each cycle made during the run counts this many times (accelerated wear)"),
    PlantKey("coil_mismatch", "", 0.0, 0.5, 0.0, plants=PHYS,
             doc="wire-length mismatch: first coil +m, last coil −m (resistance, mass, surface)"),
    PlantKey("power_scale", "×", 0.2, 2.0, 1.0, "actuator", plants=PHYS,
             doc="heating power factor of one coil (contact resistance, crimp)"),
    PlantKey("overlap_mm", "mm", 0.0, 30.0, 8.0, "actuator", plants=PHYS,
             doc="how far a coil reaches past its half of the body (coil-to-coil coupling, asymmetric if they differ)"),
    PlantKey("imu_offset_deg", "°", -20.0, 20.0, 0.0, "limb", plants=PHYS, doc="IMU mounting tilt on the limb"),
    PlantKey("imu_bias_deg", "°", -20.0, 20.0, 0.0, "limb", plants=PHYS, doc="IMU accelerometer bias, as an angle"),
    PlantKey("imu_noise_deg", "° rms", 0.0, 5.0, 0.0, plants=PHYS, doc="white noise on every IMU angle sample"),
    PlantKey("incline_deg", "°", -12.0, 12.0, 0.0, plants=PHYS, doc="ground slope, rising towards +x"),
    PlantKey("psi_star_shift_deg", "°", -15.0, 15.0, 0.0, "limb", plants=PHYS,
             doc="true critical angle ψ* − the configured one"),
    PlantKey("friction", "×", 0.2, 3.0, 1.0, plants=PHYS, doc="scale of every friction coefficient (the ground; on level ground it changes nothing: every contact scales alike)"),
    PlantKey("mass_g", "g", 1.0, 20.0, 3.3, plants=PHYS,
             doc="robot mass: the body node's heat capacity (every force scales with it, so nothing else)"),
    PlantKey("length_mm", "mm", 20.0, 2000.0, None, plants=PHYS,
             doc="body length, first contact to last (contacts evenly spaced); default 80 for two limbs, "
                 "40 per gap between neighbouring limbs for more"),
    PlantKey("wire_diameter_mm", "mm", 0.0, 2.0, 0.1, "actuator", open_lo=True, plants=PHYS,
             doc="the NiTi wire's diameter"),
    PlantKey("coil_diameter_mm", "mm", 0.0, 20.0, 0.4, "actuator", open_lo=True, plants=PHYS,
             doc="the coil's outer diameter, at least twice the wire's; the wire's own for a straight wire"),
    PlantKey("coil_length_mm", "mm", 0.0, 1000.0, 30.0, "actuator", open_lo=True, plants=PHYS,
             doc="the coil's installed length (a straight wire's length)"),
    PlantKey("working_strain", "", 0.0, 0.2, DEFAULT_WORKING_STRAIN, open_lo=True, plants=PHYS,
             doc="how much a fully transformed coil shortens the body's fibre it runs along (2 mm above the "
                 "neutral axis): the body's curvature at full stroke is this / 2 mm; halve it and a coil bends "
                 "its end about half as far"),
)
PLANT_KEYS: dict[str, PlantKey] = {k.name: k for k in _KEYS}
PER_ACTUATOR = tuple(k.name for k in _KEYS if k.per == "actuator" and "table" in k.plants)
# The body's own dimensions and stiffness, and its coils' wire: physical-plant keys of the robot
# file, not run conditions (so are the transformation temperatures, which both plants read).
BODY_KEYS = ("length_mm", "working_strain")
COIL_KEYS = ("wire_diameter_mm", "coil_diameter_mm", "coil_length_mm")
TRANSFORMATION_KEYS = ("as_c", "af_c", "ms_c", "mf_c")
PHYSICAL_KEYS = tuple(k.name for k in _KEYS if "physical" in k.plants
                      and k.name not in BODY_KEYS + COIL_KEYS + TRANSFORMATION_KEYS)
SCALARS = ("direct_gain_deg", "cross_gain_deg", "mech_tau_s", "ambient_c", "step_mm", "noise_mm", "simultaneous_s")


@dataclass(frozen=True, eq=False)
class PlantSection:
    """A checked ``[plant]`` table, every value resolved (see ``PLANT_KEYS`` for units).

    ``actuator[key]`` holds one value per [[actuator]] (file order) for each per-actuator key;
    ``psi_rest_deg`` one per [[limb]]; ``coupling_deg`` is None unless the file gives it (then
    the simulator derives it from ``direct_gain_deg`` / ``cross_gain_deg``); ``true_matrix`` is
    None unless given (n × n, NaN = forbidden). ``given`` names the keys the file set.
    """

    actuator: dict[str, tuple[float, ...]]
    psi_rest_deg: tuple[float, ...]
    coupling_deg: tuple[tuple[float, ...], ...] | None
    direct_gain_deg: float
    cross_gain_deg: float
    mech_tau_s: float
    ambient_c: float
    step_mm: float
    noise_mm: float
    simultaneous_s: float
    true_matrix: np.ndarray | None = None
    given: frozenset[str] = field(default_factory=frozenset)
    physical: dict[str, float | tuple[float, ...]] = field(default_factory=dict)
    """The physical plant's keys the file gives (``supply_v`` and ``ambient_c`` included):
    one number, or one per actuator / per limb for a per-actuator / per-limb key."""
    length_mm: float = 80.0
    """The physical plant's body length (given, or ``proleg.body.default_length_mm``)."""
    working_strain: float = DEFAULT_WORKING_STRAIN
    """The physical plant's working strain (``proleg.body.BodyGeometry``)."""
    coil: dict[str, tuple[float, ...]] = field(default_factory=dict)
    """The physical plant's coils: ``COIL_KEYS`` and ``TRANSFORMATION_KEYS`` the file gives,
    one value per actuator (a key it does not give is the plant's default coil's)."""

    def scalars(self) -> dict[str, float]:
        return {k: getattr(self, k) for k in SCALARS}


def default_plant_section(n_actuators: int, n_limbs: int) -> PlantSection:
    """The section a robot file without ``[plant]`` gets."""
    return plant_section(Path("<defaults>"), {}, [f"a{j}" for j in range(n_actuators)], n_limbs, 0)


def geometric_coupling(limb_actuators: list[int], n_actuators: int, direct: float, cross: float
                       ) -> tuple[tuple[float, ...], ...]:
    """The default coupling of a robot with more than two limbs, from its geometry.

    Limbs sit in a row in file order; actuator j bends the body at its home limb h(j)
    (the first limb that names it). It tilts its home limb by ``direct`` and every other
    limb i by a share of ``cross`` that falls off with the distance |i − h(j)| (weights
    1/distance), the shares onto each limb summing to ``cross``: with two limbs this is
    the paper's R1 coupling (``cross`` onto the other end), and with more limbs a limb
    whose own coil is off stays below its ψ* while its neighbours' coils hold theirs
    (so any single-limb transition the matrix allows can happen)."""
    n = len(limb_actuators)
    home = [limb_actuators.index(j) if j in limb_actuators else 0 for j in range(n_actuators)]
    rows = []
    for i in range(n):
        weights = [0.0 if home[j] == i else 1.0 / abs(i - home[j]) for j in range(n_actuators)]
        total = sum(weights) or 1.0
        rows.append(tuple(direct if home[j] == i else round(cross * w / total, 3) for j, w in enumerate(weights)))
    return tuple(rows)


def plant_section(path: Path, table: Any, actuators: list[str], n_limbs: int, n_states: int,
                  limb_actuators: list[int] | None = None, units: str = "steps") -> PlantSection:
    """Check a ``[plant]`` table; RobotFileError names the file and the key.

    ``limb_actuators`` (the actuator index of each limb) lets a robot with more than two
    limbs get its coupling from its geometry (``geometric_coupling``) when the file gives
    none; with a length unit (``units = "mm"``, ``"cm"``, ``"m"``) ``step_mm`` is that unit in
    millimetres (any other value is an error)."""
    if not isinstance(table, dict):
        raise RobotFileError(f"{path}: plant: expected a table")
    unknown = sorted(set(table) - set(PLANT_KEYS))
    if unknown:
        near = difflib.get_close_matches(unknown[0], list(PLANT_KEYS), n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else f" (expected one of: {', '.join(PLANT_KEYS)})"
        raise RobotFileError(f"{path}: plant.{unknown[0]}: unknown key{hint}")
    na = len(actuators)
    per_act = {k: _per(path, PLANT_KEYS[k], table.get(k), na) for k in PER_ACTUATOR}
    _check_transformation(path, per_act, actuators)
    rest = _per(path, PLANT_KEYS["psi_rest_deg"], table.get("psi_rest_deg"), n_limbs)
    scalars = {k: _scalar(path, PLANT_KEYS[k], table.get(k)) for k in SCALARS}
    coupling = _coupling(path, table["coupling_deg"], n_limbs, na) if "coupling_deg" in table else None
    if coupling is None and limb_actuators is not None and n_limbs > 2:
        coupling = geometric_coupling(limb_actuators, na, scalars["direct_gain_deg"], scalars["cross_gain_deg"])
    if units in UNIT_MM:  # a length: the entry's millimetres are fixed by the unit
        if "step_mm" in table and scalars["step_mm"] != UNIT_MM[units]:
            raise RobotFileError(
                f"{path}: plant.step_mm: expected {UNIT_MM[units]:g} (or no step_mm) when transitions.units = "
                f"\"{units}\" (the matrix is in {units}), got {table['step_mm']!r}"
            )
        scalars["step_mm"] = UNIT_MM[units]
    truth = _true_matrix(path, table["true_matrix"], n_states) if "true_matrix" in table else None
    physical: dict[str, float | tuple[float, ...]] = {}
    for k in PHYSICAL_KEYS:
        if k not in table:
            continue
        spec = PLANT_KEYS[k]
        if spec.per:
            vals = _per(path, spec, table[k], na if spec.per == "actuator" else n_limbs)
            physical[k] = vals if isinstance(table[k], list) else vals[0]
        else:
            physical[k] = _scalar(path, spec, table[k])
    length = _scalar(path, PLANT_KEYS["length_mm"], table["length_mm"]) if "length_mm" in table \
        else default_length_mm(n_limbs)
    strain = _scalar(path, PLANT_KEYS["working_strain"], table.get("working_strain"))
    coil = {k: _per(path, PLANT_KEYS[k], table[k], na) for k in COIL_KEYS if k in table}
    coil.update({k: per_act[k] for k in TRANSFORMATION_KEYS if k in table})
    _check_wire(path, coil, actuators)
    return PlantSection(
        actuator=per_act, psi_rest_deg=rest, coupling_deg=coupling, true_matrix=truth,
        given=frozenset(table), physical=physical, length_mm=length, working_strain=strain, coil=coil, **scalars,
    )


def _check_wire(path: Path, coil: dict[str, tuple[float, ...]], actuators: list[str]) -> None:
    """A straight wire (the coil as wide as its wire) or a helix, at least twice as wide as its
    wire (its inner diameter, outer − 2 × wire, not below 0). Between the two there is no coil:
    the wire-length formula gave a 0.1 mm wire in a 0.12 mm coil 9 mm of wire for 30 mm of coil
    (1 Ω, 415 °C in `proleg sim`), and one in a 0.1001 mm coil 0.09 mm (0.01 Ω)."""
    spec = {k: PLANT_KEYS[k].default for k in ("wire_diameter_mm", "coil_diameter_mm")}
    for j, name in enumerate(actuators):
        d, od = (coil[k][j] if k in coil else spec[k] for k in spec)
        if od != d and od < 2.0 * d:
            default = "" if "coil_diameter_mm" in coil else " (the default: give coil_diameter_mm)"
            raise RobotFileError(f"{path}: plant.coil_diameter_mm: expected, for actuator {name!r} and its "
                                 f"{_g(d)} mm wire, {_g(d)} (a straight wire) or at least {_g(2.0 * d)} (a coil: "
                                 f"its inner diameter, outer − 2 × wire, is not negative), got {_g(od)}{default}")


def _fail(path: Path, key: str, expected: str, got: Any) -> None:
    raise RobotFileError(f"{path}: plant.{key}: expected {expected}, got {toml_text(got)}")


def _value(path: Path, spec: PlantKey, key: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or not spec.accepts(v):
        _fail(path, key, f"a number in {spec.range_text()}", v)
    return float(v)


def _scalar(path: Path, spec: PlantKey, v: Any) -> float:
    if v is None:
        assert spec.default is not None
        return spec.default
    return _value(path, spec, spec.name, v)


def _per(path: Path, spec: PlantKey, v: Any, n: int) -> tuple[float, ...]:
    if v is None:
        assert spec.default is not None
        return (spec.default,) * n
    if isinstance(v, list):
        if len(v) != n:
            _fail(path, spec.name, f"one number or a list of {n} (one per {spec.per})", v)
        return tuple(_value(path, spec, f"{spec.name}[{i + 1}]", x) for i, x in enumerate(v))
    if isinstance(v, bool) or not isinstance(v, (int, float)):  # a string or a table: say a list is taken too
        _fail(path, spec.name, f"a number in {spec.range_text()}, or a list of {n} (one per {spec.per})", v)
    return (_value(path, spec, spec.name, v),) * n


def _check_transformation(path: Path, per_act: dict[str, tuple[float, ...]], actuators: list[str]) -> None:
    """Mf < Ms ≤ Af, Mf ≤ As < Af for each coil (the hysteresis model needs that order)."""
    for j, name in enumerate(actuators):
        as_c, af_c, ms_c, mf_c = (per_act[k][j] for k in ("as_c", "af_c", "ms_c", "mf_c"))
        for ok, what in (
            (mf_c < ms_c, f"mf_c ({_g(mf_c)}) below ms_c ({_g(ms_c)})"),
            (as_c < af_c, f"as_c ({_g(as_c)}) below af_c ({_g(af_c)})"),
            (ms_c <= af_c, f"ms_c ({_g(ms_c)}) at most af_c ({_g(af_c)})"),
            (mf_c <= as_c, f"mf_c ({_g(mf_c)}) at most as_c ({_g(as_c)})"),
        ):
            if not ok:
                raise RobotFileError(f"{path}: plant: actuator {name!r}: expected {what}")


def _coupling(path: Path, g: Any, n_limbs: int, na: int) -> tuple[tuple[float, ...], ...]:
    spec = PLANT_KEYS["coupling_deg"]
    if not isinstance(g, list) or len(g) != n_limbs or any(not isinstance(r, list) or len(r) != na for r in g):
        raise RobotFileError(f"{path}: plant.coupling_deg: expected {counted(n_limbs, 'row')} (limbs) of {counted(na, 'number')} (actuators)")
    return tuple(
        tuple(_value(path, spec, f"coupling_deg[{i + 1}][{j + 1}]", x) for j, x in enumerate(r))
        for i, r in enumerate(g)
    )


def _true_matrix(path: Path, m: Any, n: int) -> np.ndarray:
    spec = PLANT_KEYS["true_matrix"]
    if not isinstance(m, list) or len(m) != n or any(not isinstance(r, list) or len(r) != n for r in m):
        raise RobotFileError(f"{path}: plant.true_matrix: expected {n} rows of {n} entries (numbers or 'x')")
    out = np.empty((n, n))
    for a, row in enumerate(m):
        for b, x in enumerate(row):
            if isinstance(x, str) and x.strip().lower() == FORBIDDEN:
                out[a, b] = np.nan
            else:
                out[a, b] = _value(path, spec, f"true_matrix[{a + 1}][{b + 1}]", x)
    return out


# -- [[limb]] friction: which friction mechanism a limb carries ----------------------------------
#: Contact materials the physical plant knows (``proleg.physics.materials`` holds their
#: friction coefficients) and the paper's two mechanisms: the material touching at each level,
#: level 0 (ψ < ψ*) first. D1: soft/sticky then hard/slippery; D2 the reverse.
FRICTION_MATERIALS = ("soft", "hard")
FRICTION_MECHANISMS = {"D1": ("soft", "hard"), "D2": ("hard", "soft")}

#: The physical plant infers D1/D2 from the matrix's signs for robots of at most this many
#: limbs when the file gives no ``friction``: every one of the 2^n assignments is scored over
#: every transition (n·2^n of them; one kinematic sweep, replayed per assignment). Measured on
#: this machine: 0.1 s for two limbs, 0.9 s for three, 3.7 s for four, 15 s for five, and
#: about four times as long per limb beyond. Larger robots take D1 on every limb (the example
#: robots' convention) and say so.
INFER_MAX_LIMBS = 4


def too_many_to_infer(limbs: list[Any]) -> bool:
    """The file gives no friction, every limb has two levels (what inference covers), and
    there are more than INFER_MAX_LIMBS of them: the plant takes D1 instead."""
    return (len(limbs) > INFER_MAX_LIMBS and all(len(lb.psi_star_deg) == 1 for lb in limbs)
            and all(getattr(lb, "friction", None) is None for lb in limbs))


def inference_warning(path: Path, limbs: list[Any], unmeasured: bool = False) -> str | None:
    """The warning for a robot whose friction mechanisms the plant cannot infer from its
    matrix, too large or with the matrix unmeasured (None if the file gives them, or the plant
    infers them)."""
    if unmeasured and any(getattr(lb, "friction", None) is None for lb in limbs):
        return (f"{path}: the matrix is unmeasured and not every [[limb]] says its friction: the physical plant "
                "takes D1 (soft at rest) on a two-level limb and alternates soft/hard from level 0 on a "
                "multi-level one, since there are no signs to infer them from; say friction on every limb "
                "(\"D1\", \"D2\" or its materials) so that what it measures is your robot")
    if not too_many_to_infer(limbs):
        return None
    return (f"{path}: {len(limbs)} limbs and no [[limb]] friction: the physical plant takes D1 (soft at rest) on "
            f"every limb; it infers D1/D2 from the matrix's signs only up to {INFER_MAX_LIMBS} limbs. "
            'Say friction = "D1" or "D2" on every limb.')


#: A pad of the lab's own: its friction coefficients on the ground, in place of a material name.
#: Rubber-like solids reach μ ≈ 1–3 (Persson, "Sliding Friction", ch. 12); past 5 is no pad.
PAD_MU_MAX = 5.0


def limb_friction(path: Path, where: str, value: Any, levels: int) -> str | tuple[str | tuple[float, float], ...]:
    """A limb's ``friction``: ``"D1"``/``"D2"`` (two-level limbs) or a list of ``levels``
    materials, lowest level first, each a name (``FRICTION_MATERIALS``) or a pad's own
    coefficients ``{ mu_static = …, mu_kinetic = … }`` (kept as a ``(μs, μk)`` pair); one line
    naming the limb otherwise."""
    if isinstance(value, str):
        if value not in FRICTION_MECHANISMS:
            raise RobotFileError(f"{path}: {where}: friction: expected one of {', '.join(FRICTION_MECHANISMS)} "
                                 f"or a list of materials ({', '.join(FRICTION_MATERIALS)}), got {toml_text(value)}")
        if levels != 2:
            raise RobotFileError(f"{path}: {where}: friction: {value} describes 2 levels, the limb has {levels}; "
                                 f"give a list of {levels} materials ({', '.join(FRICTION_MATERIALS)})")
        return value
    if not isinstance(value, list) or len(value) != levels or not all(isinstance(m, (str, dict)) for m in value):
        raise RobotFileError(f"{path}: {where}: friction: expected D1, D2 or a list of {levels} materials "
                             f"(one per level, level 0 first), each {' or '.join(FRICTION_MATERIALS)} or "
                             f"{{ mu_static = …, mu_kinetic = … }}, got {toml_text(value)}")
    return tuple(_pad(path, f"{where}: friction[{k + 1}]", k, m) for k, m in enumerate(value))


def _pad(path: Path, field: str, level: int, m: str | dict) -> str | tuple[float, float]:
    """Level ``level``'s material, ``field`` its place in the file (counted from 1, as every list
    of the robot file is; the level, from 0, beside it)."""
    at = f"(level {level})"
    if isinstance(m, str):
        if m not in FRICTION_MATERIALS:
            raise RobotFileError(f"{path}: {field} {at}: expected a material ({', '.join(FRICTION_MATERIALS)}) or "
                                 f"{{ mu_static = …, mu_kinetic = … }}, got {toml_text(m)}")
        return m
    if set(m) != {"mu_static", "mu_kinetic"}:
        raise RobotFileError(f"{path}: {field} {at}: expected the keys mu_static and mu_kinetic, got {toml_text(m)}")
    mu = {}
    for k in ("mu_static", "mu_kinetic"):
        v = m[k]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0.0 < v <= PAD_MU_MAX:
            raise RobotFileError(f"{path}: {field}.{k} {at}: expected a number in (0, {PAD_MU_MAX:g}], "
                                 f"got {toml_text(v)}")
        mu[k] = float(v)
    if mu["mu_kinetic"] > mu["mu_static"]:  # a contact that has started to slide grips less (docs/plant.md)
        raise RobotFileError(f"{path}: {field}.mu_kinetic {at}: expected at most mu_static ({mu['mu_static']:g}), "
                             f"got {mu['mu_kinetic']:g}")
    return mu["mu_static"], mu["mu_kinetic"]


def rest_warnings(path: Path, limbs: list[Any], section: PlantSection) -> list[str]:
    """A ``psi_rest_deg`` the file gives that puts a cold limb in its level 1 or above: the
    table plant's (the physical body rests flat, and its own load check says when level 0
    cannot be held there). Loaded silently, every ``--plant table`` run timed out."""
    if "psi_rest_deg" not in section.given:
        return []
    out = []
    for limb, rest in zip(limbs, section.psi_rest_deg):
        edge = limb.psi_star_deg[0] - limb.hysteresis_deg / 2
        if rest >= edge:
            out.append(f"{path}: plant.psi_rest_deg: limb {limb.name!r} rests at {rest:g}°, in its level 1 or above "
                       f"(from {edge:g}°: psi* {limb.psi_star_deg[0]:g}° − hysteresis/2): on the table plant "
                       "(--plant table) its level 0 cannot be reached with every coil cold, and a state that needs "
                       "it times out")
    return out
