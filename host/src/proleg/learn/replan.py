"""Limb loss: what the robot can still do when an actuator is suspected dead, and its best gait.

The firmware reports a coil that cannot do its job as SMA_ON_LIMIT (detail: the channel)
and then STATE_TIMEOUT (detail: the limb that did not reach its level). ``suspect`` turns
such a fault into the actuator to suspect; ``without_actuator`` is the robot's transition
table with every transition forbidden that needs that actuator to heat, under the
firmware's compiled limb→actuator map (each limb is raised and held by its own actuator):
a state in which a limb of that actuator is above its lowest level can no longer be
reached nor held, so every transition into such a state goes, and so does every transition
out of one (the robot cannot be there to make it). ``replan`` is the best gait of what is
left, in ``direction``, or None with the reason.

What this cannot do (issue 15): a robot whose remaining coil could raise the other end too
(R1: the left coil bends the body enough to lift the right end at α ≈ 0.74; the paper's
one-actuator experiment, robots/paper-r1-one-actuator.toml) needs the limb→actuator map as
a run-time setting of the firmware; with the compiled map R1 without ``sma-right`` can only
go 00 ↔ 10, which does not move it on balance.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..protocol.definition import FaultCode
from ..robot import Robot
from ..transitions import TransitionTable


@dataclass(frozen=True)
class Replan:
    actuator: str
    table: TransitionTable            # what the robot can still do
    states: tuple[int, ...] | None    # best closed walk (first state repeated at the end), None: none
    rate: float                       # its reward per transition (0 when none)
    reason: str                       # one line for the user


def suspect(robot: Robot, code: int, detail: int) -> str | None:
    """The actuator a fault points at: SMA_ON_LIMIT names the channel, STATE_TIMEOUT the limb."""
    if code == FaultCode.SMA_ON_LIMIT:
        return next((a.name for a in robot.actuators if a.channel == detail), None)
    if code == FaultCode.STATE_TIMEOUT and 0 <= detail < len(robot.limbs):
        return robot.limbs[detail].actuator
    return None


def without_actuator(robot: Robot, actuator: str) -> TransitionTable:
    """``robot``'s table without the transitions that need ``actuator`` (module docstring)."""
    from ..states import limb_levels

    t = robot.transitions
    driven = [i for i, limb in enumerate(robot.limbs) if limb.actuator == actuator]
    if not driven:
        raise ValueError(f"no limb of {robot.name} is driven by {actuator!r}")
    lost = np.array([any(limb_levels(s, robot.levels)[i] > 0 for i in driven) for s in range(t.n_states)])
    keep = ~(lost[t.src] | lost[t.dst])
    planar = None
    if t.planar is not None:
        planar = type(t.planar)(**{k: np.asarray(v)[keep] for k, v in t.planar.given().items()})
    return TransitionTable(t.levels, t.src[keep], t.dst[keep], t.reward[keep],
                           None if t.duration is None else t.duration[keep], planar)


def replan(robot: Robot, actuator: str, direction: str = "+x") -> Replan:
    """The best gait (rate: reward per transition) of ``robot`` without ``actuator``."""
    from ..errors import GaitError
    from ..gait import optimal_gaits

    table = without_actuator(robot, actuator)
    sign = 1.0 if direction == "+x" else -1.0
    try:
        res = optimal_gaits(table, "rate", direction) if table.n_transitions else None
    except GaitError:
        res = None
    if res is None or not res.gaits or res.value is None or sign * float(res.value) <= 0:
        return Replan(actuator, table, None, 0.0,
                      f"without {actuator} no gait moves {robot.name} in {direction} with the firmware's compiled "
                      "limb→actuator map (the remaining coils could only raise their own limbs; a run-time map "
                      "is needed for a coil to raise another limb)")
    g = res.gaits[0]
    states = tuple(g.states) if g.states[0] == g.states[-1] else tuple(g.states) + (g.states[0],)
    labels = "→".join(table.label(s) for s in states)
    return Replan(actuator, table, states, float(res.value), f"without {actuator}: gait {labels}, "
                  f"rate {float(res.value):+.3g} per transition")
