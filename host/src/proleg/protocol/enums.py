"""The protocol's value sets: what the numbers in ``EVENT``, ``NACK``, ``TELEMETRY.flags``,
``SET_PARAM`` and ``CLEAR`` mean.

Part of the protocol definition (``definition.py`` re-exports every name here, so
``from proleg.protocol.definition import EventKind`` keeps working). ``ENUMS`` lists the sets
``render.py`` turns into ``PROTO_<PREFIX><MEMBER>`` defines; a new set goes there too.
"""

from __future__ import annotations

from enum import IntEnum, IntFlag


class Direction(IntEnum):
    """Which way a gait moves the robot (the gait table holds gaits per direction)."""

    PLUS_X = 0
    MINUS_X = 1


class ErrorCode(IntEnum):
    """``NACK.error``: why a command was refused."""

    UNKNOWN_MESSAGE = 1  # CRC-valid frame with an id this firmware does not decode
    BAD_CRC = 2  # reserved: frames with a bad CRC are dropped silently (counted), never NACKed
    BAD_LENGTH = 3  # payload length does not match the message layout
    OUT_OF_RANGE = 4  # a value outside its allowed range (detail per command: param id, field, step or limb index)
    FORBIDDEN_TRANSITION = 5  # LOAD_GAIT step not an allowed transition (detail = step index)
    TOO_LONG = 6  # array count above this build's maximum
    NOT_ALLOWED = 7  # not allowed in the current mode (e.g. LOAD_GAIT while running)
    SAFETY_LIMIT = 8  # would widen the build's safety envelope
    NO_GAIT = 9  # START of a gait index that does not exist / user gait not loaded
    ESTOP_LATCHED = 10  # E-stop latched: CLEAR it first
    TOO_STEEP = 11  # START uphill steeper than the build's [control] max_climb_deg (detail = the climb, 0.01°; 0xFFFF: an end beyond the 20° levelled on)


class FaultCode(IntEnum):
    """``EVENT.code`` when ``kind == FAULT``; ``detail`` is the limb index (STATE_TIMEOUT: the
    first limb off its target, 0xFF when every limb is at its level; IMU_NO_ACK, IMU_BAD_DATA:
    the limb whose IMU), the actuator index (SMA_ON_LIMIT: the robot file's [[actuator]] order,
    not its PWM channel), else 0."""

    NONE = 0
    STATE_TIMEOUT = 1  # target state not reached within state_timeout_ms
    IMU_NO_ACK = 2  # IMU stopped answering on I2C
    IMU_BAD_DATA = 3  # IMU answers nonsense (WHO_AM_I, stuck, implausible |g|)
    SMA_ON_LIMIT = 4  # SMA on-time hit max_on_ms (cool-down enforced)
    LINK_WATCHDOG = 5  # no valid frame within link_watchdog_ms
    INTERNAL = 6  # firmware invariant violated
    TICK_OVERRUN = 7  # [control] overrun_fault consecutive ticks overran their period (detail = 0)


class EventKind(IntEnum):
    """``EVENT.kind``; the meaning of ``code``/``detail`` per kind is in the comment."""

    BOOT = 0  # code = ResetCause, detail = 1 if the safety envelope kept what the coils spent before the reset, else 0
    STATE_REACHED = 1  # code = gait step index, detail = state index
    FAULT = 2  # code = FaultCode, detail = limb or actuator index (FaultCode)
    GAIT_STARTED = 3  # code = gait index, detail = Direction (DIR_UNSTATED for a loaded gait's unstated way)
    GAIT_STOPPED = 4  # code = StopReason, detail = completed cycles (saturating)
    ESTOP = 5  # code = 0 command / 1 hardware input, detail = 0
    FAULT_CLEARED = 6  # code = ClearWhat bits that were cleared, detail = 0
    GAIT_LOADED = 7  # code = 0, detail = number of steps
    SUSPECT = 8  # after a FAULT STATE_TIMEOUT / SMA_ON_LIMIT: code = suspected actuator index (0xFF: none),
    #              detail = the failed transition, from-state × n_states + to-state (0xFFFF: not representable)
    FALLBACK = 9  # the firmware switched by itself to its fallback gait: code = lost actuator, detail = steps
    LEVEL_DONE = 10  # CALIBRATE_LEVEL finished: code = LevelResult, detail = bit per limb stored


class ResetCause(IntEnum):
    """``EVENT.code`` when ``kind == BOOT``: why the MCU last reset (its reset flags; a
    board that cannot tell reports UNKNOWN; host-sim POWER_ON, or the cause ``SimBoard.restart`` gave)."""

    UNKNOWN = 0
    POWER_ON = 1
    EXTERNAL = 2  # reset pin
    BROWN_OUT = 3
    WATCHDOG = 4  # the hardware watchdog: a tick or a bus wait hung
    SOFTWARE = 5


class LevelStatus(IntEnum):
    """``LEVEL.status``: what the board's non-volatile level record holds."""

    NONE = 0  # blank (never calibrated, or CLEAR_LEVEL): offsets 0, nothing applied
    STORED = 1  # a valid record (magic, version, limb count, CRC): its offsets are applied
    CORRUPT = 2  # a record whose magic/version, limb count or CRC is wrong: ignored, offsets 0
    CALIBRATING = 3  # CALIBRATE_LEVEL is sampling or writing


class LevelResult(IntEnum):
    """``EVENT.code`` when ``kind == LEVEL_DONE``."""

    STORED = 0  # every limb measured, the record written and read back valid (ground: applied)
    TOO_TILTED = 1  # a limb's rest tilt is beyond the build's limit (detail = bit per such limb)
    IMU = 2  # an IMU is bad, or gave no samples (detail = bit per such limb)
    INTERRUPTED = 3  # a gait started or a fault latched while sampling
    WRITE_FAILED = 4  # the non-volatile write did not verify


class StopReason(IntEnum):
    """``EVENT.code`` when ``kind == GAIT_STOPPED``."""

    COMMAND = 0
    FAULT = 1
    ESTOP = 2
    WATCHDOG = 3


class ParamId(IntEnum):
    """``SET_PARAM.param`` whitelist. The firmware checks each value against the build's
    safety envelope (NACK SAFETY_LIMIT) and sane ranges (NACK OUT_OF_RANGE)."""

    DRIVE_DUTY = 1  # permyriad, ≤ build max_duty
    HOLD_MS = 2
    DEBOUNCE_TICKS = 3
    STATE_TIMEOUT_MS = 4  # ≤ build value
    PSI_STAR_CDEG = 5  # index = the threshold, counted limb by limb (a limb of k levels has k-1); 0.01°
    HYSTERESIS_CDEG = 6  # index = limb; 0.01°
    MAX_ON_MS = 7  # never above the build's value
    MIN_COOLDOWN_MS = 8  # never below the build's value
    LINK_WATCHDOG_MS = 9  # never above the build's value (0 only if the build has it off)
    HOLD_DUTY = 10  # permyriad, ≤ build max_duty; 0 = hold by bang-bang only


class Flag(IntFlag):
    """``TELEMETRY.flags`` bits."""

    RUNNING = 1 << 0  # a gait is running
    HOLDING = 1 << 1  # the step's target state is measured now, held before the next step (clear once lost)
    FAULT = 1 << 2  # a fault is latched (see the FAULT event)
    ESTOP = 1 << 3  # E-stop latched, all MOSFETs off
    COOLDOWN = 1 << 4  # a channel is in enforced cool-down
    DUTY_CLAMPED = 1 << 5  # a requested duty was clamped to the envelope
    IMU_FAULT = 1 << 6
    LINK_WATCHDOG = 1 << 7  # stopped by the link watchdog
    USER_GAIT = 1 << 8  # a LOAD_GAIT sequence is stored
    STATE_UNKNOWN = 1 << 9  # measured state not yet debounced


class ClearWhat(IntFlag):
    """``CLEAR.what`` bits."""

    FAULTS = 1 << 0
    ESTOP = 1 << 1
    COUNTERS = 1 << 2


#: Enums rendered into C: (class, C prefix). Flags render as bit masks.
ENUMS: tuple[tuple[type[IntEnum] | type[IntFlag], str], ...] = (
    (Direction, "PROTO_DIR_"),
    (ErrorCode, "PROTO_ERR_"),
    (FaultCode, "PROTO_FAULT_"),
    (EventKind, "PROTO_EV_"),
    (StopReason, "PROTO_STOP_"),
    (LevelStatus, "PROTO_LEVEL_"),
    (LevelResult, "PROTO_LEVEL_RES_"),
    (ResetCause, "PROTO_RESET_"),
    (ParamId, "PROTO_PARAM_"),
    (Flag, "PROTO_FLAG_"),
    (ClearWhat, "PROTO_CLEAR_"),
)
