"""The table plant's parameters (``proleg.sim.plant.Plant``): limbs, coils, body coupling and the
ground-truth tables, and how a loaded robot file becomes them. Re-exported by
``proleg.sim.plant``; the model itself is documented there."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import SimError
from .sma import SmaParams

DIRECT_GAIN_DEG = 60.0
CROSS_GAIN_DEG = 27.0


@dataclass(frozen=True)
class LimbParams:
    """One friction mechanism (end of the body)."""

    name: str = "limb"
    psi_star_deg: tuple[float, ...] = (20.0,)   # critical angles, increasing; levels = len + 1
    psi_rest_deg: float = 0.0                   # body relaxed and straight: the ends lie flat
    #: width of each ψ*'s band (the robot file's ``hysteresis_deg``): the level goes up at
    #: ψ* + h/2 and down below ψ* − h/2, as the firmware's classifier counts it (psi.h)
    hysteresis_deg: float = 0.0
    actuator: int | None = None                 # index into PlantParams.actuators that raises it


@dataclass(frozen=True)
class PlantParams:
    """Everything the plant needs. Defaults: the paper's R1-class robot (80 mm, ~3 g, two
    overlapping BioMetal Helix coils, ψ* = 20° at both ends).

    With the defaults and drive duty 0.6 from cold (25 °C), ψ crosses 20° after ≈ 0.74 s
    (≈ 0.49 s from the ≈ 45 °C a coil keeps between gait steps); released just after the
    crossing, ψ falls back below 20° after ≈ 0.9 s; a bang-bang ψ controller walks the
    four-transition gait 00 → 10 → 11 → 01 → 00 in ≈ 2.1 s per cycle.
    """

    actuators: tuple[SmaParams, ...] = (
        SmaParams(name="sma-left", channel=0),
        SmaParams(name="sma-right", channel=1),
    )
    limbs: tuple[LimbParams, ...] = (
        LimbParams(name="left", actuator=0),
        LimbParams(name="right", actuator=1),
    )
    # n_limbs × n_actuators, degrees of ψ at full nominal contraction; None → direct_gain_deg
    # on (home limb of actuator j, j), cross_gain_deg elsewhere. An actuator's home limb is
    # the limb at its own position (limb j) if that limb names it, else the first limb that
    # names it: in R1-with-one-coil both limbs name "sma-left", which still bends mainly
    # the left end and lifts the right end only at a stronger bend.
    coupling_deg: tuple[tuple[float, ...], ...] | None = None
    direct_gain_deg: float = DIRECT_GAIN_DEG
    cross_gain_deg: float = CROSS_GAIN_DEG
    mech_tau_s: float = 0.03        # soft body (TangoPlus) settles in tens of ms
    ambient_c: float = 25.0
    step_mm: float = 4.0            # mm per unit of T_true ("steps"); a guess: 5 % of 80 mm
    noise_mm: float = 0.0           # σ of the Gaussian added to each transition's displacement
    simultaneous_s: float = 0.03    # limb changes this close together are one transition

    @property
    def levels(self) -> tuple[int, ...]:
        return tuple(len(limb.psi_star_deg) + 1 for limb in self.limbs)

    def coupling(self) -> list[list[float]]:
        if self.coupling_deg is not None:
            return [list(map(float, row)) for row in self.coupling_deg]
        home = []
        for j in range(len(self.actuators)):
            named = [i for i, limb in enumerate(self.limbs) if limb.actuator == j]
            home.append(j if j in named else (named[0] if named else None))
        return [
            [self.direct_gain_deg if home[j] == i else self.cross_gain_deg for j in range(len(self.actuators))]
            for i in range(len(self.limbs))
        ]

    def check(self) -> str | None:
        """What is wrong with these parameters, or None."""
        if not self.actuators:
            return "at least one actuator is needed"
        if not self.limbs:
            return "at least one limb is needed"
        channels = [a.channel for a in self.actuators]
        if len(set(channels)) != len(channels) or min(channels) < 0:
            return f"actuator channels must be distinct and ≥ 0, got {channels}"
        for a in self.actuators:
            msg = a.check()
            if msg:
                return f"actuator {a.name!r}: {msg}"
        for limb in self.limbs:
            ps = list(limb.psi_star_deg)
            if not ps or any(not -90.0 < p < 90.0 for p in ps) or any(b <= a for a, b in zip(ps, ps[1:])):
                return f"limb {limb.name!r}: psi_star_deg must be increasing angles in (-90, 90), got {ps}"
            h = limb.hysteresis_deg
            if not (math.isfinite(h) and h >= 0) or any(b - a <= h for a, b in zip(ps, ps[1:])):
                return f"limb {limb.name!r}: hysteresis_deg must be ≥ 0 and less than the gaps between its ψ*, got {h!r}"
            if limb.actuator is not None and not 0 <= limb.actuator < len(self.actuators):
                return f"limb {limb.name!r}: actuator index {limb.actuator} out of range"
        g = self.coupling()
        if len(g) != len(self.limbs) or any(len(row) != len(self.actuators) for row in g):
            return f"coupling_deg must be {len(self.limbs)} × {len(self.actuators)} (limbs × actuators)"
        if any(not math.isfinite(x) for row in g for x in row):
            return "coupling_deg must be finite"
        for name in ("mech_tau_s", "step_mm"):
            if not getattr(self, name) > 0:
                return f"{name} must be > 0"
        for name in ("noise_mm", "simultaneous_s"):
            if not getattr(self, name) >= 0:
                return f"{name} must be ≥ 0"
        return None


@dataclass(frozen=True, eq=False)
class PlanarMotion:
    """Per transition (n×n, row = from, column = to, robot-file units / degrees): mean Δy and
    Δθ and the variances of Δx, Δy, Δθ, body frame (the robot file's planar statistics).
    Missing statistics are zero."""

    dy: np.ndarray
    dtheta_deg: np.ndarray
    var_dx: np.ndarray
    var_dy: np.ndarray
    var_dtheta_deg: np.ndarray


# -- robot file ---------------------------------------------------------------------------------
# The [plant] table is checked by the robot loader (proleg.robot_plant, documented in
# docs/robot-file.md); here its resolved values only become PlantParams.


def plant_params_from_robot(robot: Any) -> PlantParams:
    """Plant parameters for a loaded robot: limbs, ψ*, actuators and channels from the robot,
    physics from its checked ``[plant]`` section (``robot.plant``: ``PlantSection``, defaults
    filled in by the loader)."""
    section = robot.plant
    names = [a.name for a in robot.actuators]
    actuators = tuple(
        SmaParams(name=a.name, channel=int(a.channel), **{k: v[j] for k, v in section.actuator.items()})
        for j, a in enumerate(robot.actuators)
    )
    limbs = tuple(
        LimbParams(
            name=lb.name,
            psi_star_deg=tuple(float(p) for p in lb.psi_star_deg),
            psi_rest_deg=section.psi_rest_deg[i],
            hysteresis_deg=float(lb.hysteresis_deg),
            actuator=names.index(lb.actuator),
        )
        for i, lb in enumerate(robot.limbs)
    )
    params = PlantParams(actuators=actuators, limbs=limbs, coupling_deg=section.coupling_deg, **section.scalars())
    msg = params.check()
    if msg:  # the loader checks every key and range; this only fires on a loader bug
        raise SimError(f"{robot.path}: plant: {msg}")
    return params


def true_rewards_from_robot(robot: Any) -> np.ndarray:
    """The plant's ground-truth reward matrix (n×n, NaN = forbidden): ``[plant].true_matrix``
    when the robot file gives one (numbers or "x"), else the robot's own transition table."""
    if robot.plant.true_matrix is not None:
        return robot.plant.true_matrix.copy()
    reward, allowed = robot.transitions.dense()
    out = np.where(allowed, reward, np.nan)
    np.fill_diagonal(out, 0.0)
    return out


def planar_motion_from_robot(robot: Any) -> PlanarMotion | None:
    """The robot file's planar statistics as a ``PlanarMotion`` (missing ones zero), or None
    when ``[transitions]`` has none."""
    table = robot.transitions
    if table.planar is None or not table.planar.given():
        return None
    n = table.n_states
    out = {}
    for k in ("dy", "dtheta_deg", "var_dx", "var_dy", "var_dtheta_deg"):
        m = np.zeros((n, n))
        v = getattr(table.planar, k)
        if v is not None:
            m[table.src, table.dst] = v
        out[k] = m
    return PlanarMotion(**out)
