"""Names for what the robot reports as numbers: event kinds, fault codes, stop reasons, and
the limb and actuator an event's ``detail`` points at (from the robot file when one is
given, ``limb #1`` / ``actuator #1`` otherwise: counted from 1, in the robot file's order).
The console, its plain mode, its status line and the run reports show these, never a raw
code. Every ordinal shown (a gait step, a limb without a name) counts from 1."""

from __future__ import annotations

from dataclasses import dataclass

from ..link.direction import direction_text
from ..names import counted
from ..protocol.definition import (
    GAIT_USER,
    ClearWhat,
    EventKind,
    FaultCode,
    LevelResult,
    ResetCause,
    StopReason,
)

#: faults whose ``detail`` is an actuator index; the other faults name a limb (or nothing)
_ACTUATOR_FAULTS = frozenset({FaultCode.SMA_ON_LIMIT})
_NO_DETAIL_FAULTS = frozenset({FaultCode.LINK_WATCHDOG, FaultCode.NONE, FaultCode.INTERNAL})
#: STATE_TIMEOUT's detail when no limb is off its level (core/drive.h DRIVE_NO_LIMB)
TIMEOUT_UNSETTLED = 0xFF


@dataclass(frozen=True)
class RobotNames:
    """Limb and actuator names in the firmware's index order."""

    limbs: tuple[str, ...] = ()
    actuators: tuple[str, ...] = ()
    n_states: int = 0  # to read EVENT SUSPECT's transition (0: unknown)

    @classmethod
    def for_robot(cls, robot: object | None) -> RobotNames:
        if robot is None:
            return cls()
        return cls(tuple(limb.name for limb in robot.limbs),  # type: ignore[attr-defined]
                   tuple(a.name for a in robot.actuators),  # type: ignore[attr-defined]
                   int(getattr(robot, "n_states", 0) or 0))

    def limb(self, i: int) -> str:
        """The name of limb ``i`` (the firmware's 0-based index), else ``limb #i+1``."""
        return self.limbs[i] if 0 <= i < len(self.limbs) else f"limb #{i + 1}"

    def actuator(self, i: int) -> str:
        return self.actuators[i] if 0 <= i < len(self.actuators) else f"actuator #{i + 1}"

    def limb_set(self, mask: int) -> str:
        """``left, right`` for a bit-per-limb mask."""
        return ", ".join(self.limb(i) for i in range(8) if mask >> i & 1) or "none"


def enum_name(enum: type, value: int) -> str:
    """``FaultCode.IMU_NO_ACK`` → ``IMU_NO_ACK``; an unknown value → ``unknown 17``."""
    try:
        return enum(value).name
    except ValueError:
        return f"unknown {value}"


def gait_text(gait: int) -> str:
    return "user" if gait == GAIT_USER else str(gait)


#: the step the firmware reports while it walks the entry path from rest into a gait
ENTRY_STEPS = (0xFF, 0xFFFF)


def step_text(step: int) -> str:
    """A gait step as shown: ``step 1`` for the firmware's step 0; ``entry path``."""
    return "entry path" if step in ENTRY_STEPS else f"step {step + 1}"


def fault_name_text(code: str, detail: int, names: RobotNames = RobotNames()) -> str:
    """``fault_text`` for a fault already named (a report's ``Fault.code``)."""
    try:
        return fault_text(int(FaultCode[code]), detail, names)
    except KeyError:
        return f"{code} (detail {detail})"


def fault_text(code: int, detail: int, names: RobotNames = RobotNames()) -> str:
    """``IMU_NO_ACK on left``, ``SMA_ON_LIMIT on sma-right``, ``LINK_WATCHDOG``."""
    what = enum_name(FaultCode, code)
    try:
        fc = FaultCode(code)
    except ValueError:
        return f"{what} (detail {detail})"
    if fc in _NO_DETAIL_FAULTS:
        return what
    if fc == FaultCode.STATE_TIMEOUT and detail == TIMEOUT_UNSETTLED:
        return f"{what}: every limb at its level, one would not settle (no coil suspected)"
    return f"{what} on {names.actuator(detail) if fc in _ACTUATOR_FAULTS else names.limb(detail)}"


def describe_event(f: dict, names: RobotNames = RobotNames(), state_label: object = None) -> str:
    """One line for an EVENT's fields: time, then what happened in words (``event_text``)."""
    return f"{f['time_ms'] / 1000:8.3f}s {event_text(f, names, state_label)}"


def event_text(f: dict, names: RobotNames = RobotNames(), state_label: object = None) -> str:
    """What an EVENT says, in words: kinds, faults and reasons by name, the limb or actuator by
    its name in ``names``, states through ``state_label``. The console and recordings' ``text``."""
    kind, code, detail = f["kind"], f["code"], f["detail"]
    try:
        k = EventKind(kind)
    except ValueError:
        return f"unknown event {kind} (code {code}, detail {detail})"
    if k == EventKind.FAULT:
        return f"FAULT {fault_text(code, detail, names)}"
    if k == EventKind.GAIT_STOPPED:
        return f"gait stopped: {enum_name(StopReason, code)} after {counted(detail, 'cycle')}"
    if k == EventKind.GAIT_STARTED:
        return f"gait {gait_text(code)} started {direction_text(detail)}"
    if k == EventKind.STATE_REACHED:
        state = state_label(detail) if callable(state_label) else str(detail)
        return f"{step_text(code)} reached state {state}"
    if k == EventKind.FAULT_CLEARED:
        cleared = " ".join(c.name.lower() for c in ClearWhat if c & code and c.name) or "nothing"
        return f"cleared {cleared}"
    if k == EventKind.ESTOP:
        return f"E-STOP ({'hardware input' if code else 'command'})"
    if k == EventKind.GAIT_LOADED:
        return f"user gait loaded ({counted(detail, 'step')})"
    if k == EventKind.SUSPECT:
        who = "no actuator" if code == 0xFF else names.actuator(code)
        n = names.n_states
        if n and detail != 0xFFFF and detail < n * n:
            lab = state_label if callable(state_label) else str
            if detail // n == detail % n:  # the robot is in the step's target: no transition failed
                return f"suspects {who} (in state {lab(detail % n)}, the step's target)"
            return f"suspects {who} (transition {lab(detail // n)}→{lab(detail % n)} failed)"
        return f"suspects {who} (transition {'unknown' if detail == 0xFFFF else detail})"
    if k == EventKind.FALLBACK:
        return f"FALLBACK: gave up {names.actuator(code)}, runs its {detail}-step fallback gait"
    if k == EventKind.LEVEL_DONE:
        if code == LevelResult.STORED:
            return "level calibration done"
        on = f" ({names.limb_set(detail)})" if code in (LevelResult.TOO_TILTED, LevelResult.IMU) else ""
        return f"level calibration refused: {enum_name(LevelResult, code)}{on}"
    if k == EventKind.BOOT:
        kept = "; the envelope kept what the coils spent" if detail == 1 else ""
        return f"boot (reset cause {enum_name(ResetCause, code)}{kept})"
    return f"{k.name.lower()} (code {code}, detail {detail})"

