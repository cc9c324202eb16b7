"""What a robot answers to the client's commands, as values: ``RobotInfo`` (INFO),
``FirmwareStats`` (STATS), ``CommandRefused`` (a NACK) and ``ReplyTimeout`` (no answer).

``RobotClient`` (``client.py``) makes them; ``proleg.link.client`` re-exports every name here.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..errors import LinkError
from ..protocol.codec import Message
from ..protocol.definition import GAIT_USER, ErrorCode, ParamId


class CommandRefused(LinkError):
    """The robot answered a command with NACK."""

    def __init__(self, command: str, error: int, detail: int, where: str, note: str = ""):
        try:
            self.error: ErrorCode | int = ErrorCode(error)
            code = self.error.name
        except ValueError:
            self.error = error
            code = f"error {error}"
        self.command = command
        self.detail = detail
        why = _explain(self.error, detail, command)
        self.why = why  # the reason in words ("" where none is known)
        super().__init__(f"{where}: robot refused {command}: {code} ({why or f'detail {detail}'}){note}")


#: NOT_ALLOWED's detail per command: why the board would not (core/cmd.c)
_NOT_ALLOWED = {
    "START": {0: "a fault is latched: the FAULT event or `proleg console` names it; clear it (CLEAR_FAULTS, "
                 "console key c) once its cause is fixed",
              1: "a gait is running: STOP it first",
              2: "the limbs' state is not known yet: the board has no reading from every IMU (it has just "
                 "started, or an IMU is bad); wait for telemetry with a known state",
              3: "the firmware's fallback gave up a coil (EVENT FALLBACK), and a built-in gait needs it: run "
                 "the fallback gait (START the loaded gait), or once the coil is mended (or was wrongly "
                 "suspected) take it back: clear faults (console key c, RobotClient.clear: SET_ACTUATOR_MAP "
                 "with no entries) or reset the board"},
    "LOAD_GAIT": {0: "a gait is running: STOP it first"},
    "SET_ACTUATOR_MAP": {0: "a gait is running: STOP it first"},
    "CALIBRATE_LEVEL": {1: "a gait is running (stop it, let the coils cool)",
                        2: "an IMU is marked bad (see the fault; clear it)", 3: "a fault is latched (clear it first)",
                        4: "a calibration is already under way",
                        5: "this firmware was built without level calibration (CFG_LEVEL_CALIBRATION=0)",
                        6: "a gait ran or a fault latched since the robot was last at rest for 2 s (its limbs may "
                           "still be coming down); let the coils cool, then calibrate"},
    "CLEAR_LEVEL": {0: "a gait is running", 5: "this build has no level calibration"},
}


#: SET_PARAM's OUT_OF_RANGE, by the parameter (the NACK's detail; core/param.c)
_OUT_OF_RANGE = {
    int(ParamId.PSI_STAR_CDEG): "no such threshold (the index counts ψ* thresholds limb by limb: a limb of k levels has "
                                "k − 1), or the band ψ* ± hysteresis/2 would leave (−90°, 90°) or meet a neighbouring "
                                "threshold's band; nothing changed",
    int(ParamId.HYSTERESIS_CDEG): "no such limb (the index is the limb), a width outside 0..2000 (0.01°), or a band "
                                  "ψ* ± width/2 of the limb's thresholds would leave (−90°, 90°) or meet the next; "
                                  "nothing changed",
    int(ParamId.MAX_ON_MS): "below 1 ms, or at most min_cooldown_ms / 256 (the firmware cannot pay on-time back "
                            "that slowly; min_cooldown_ms never goes below the build's)",
    int(ParamId.MIN_COOLDOWN_MS): "outside 0..600000 ms, or 256 max_on_ms or more (the firmware cannot pay on-time "
                                  "back that slowly)",
}


#: SET_PARAM's SAFETY_LIMIT, by the parameter (the NACK's detail; core/param.c's safe bounds)
_SAFETY_LIMIT = {
    int(ParamId.DRIVE_DUTY): "above the build's duty ceiling, the robot file's [safety] max_duty",
    int(ParamId.HOLD_DUTY): "above the build's duty ceiling, the robot file's [safety] max_duty",
    int(ParamId.STATE_TIMEOUT_MS): "longer than the build's [safety] state_timeout_ms (it may only be shortened)",
    int(ParamId.MAX_ON_MS): "longer than the build's [safety] max_on_ms (it may only be shortened)",
    int(ParamId.MIN_COOLDOWN_MS): "shorter than the build's [safety] min_cooldown_ms (it may only be lengthened)",
    int(ParamId.LINK_WATCHDOG_MS): "0 (off) or longer than the build's [safety] link_watchdog_ms (it may only be "
                                   "shortened)",
}


def _explain(error: ErrorCode | int, detail: int, command: str = "") -> str:
    """What a NACK's detail means: a measurement, or why the board would not."""
    if error == ErrorCode.NOT_ALLOWED:
        return _NOT_ALLOWED.get(command, {}).get(detail, "")
    if command == "START" and error == ErrorCode.NO_GAIT:
        if detail == GAIT_USER:
            return "no gait is loaded: load one first (proleg load-gait; it lasts until the board resets)"
        return (f"the board has no gait {detail} in that direction (proleg build lists the gaits it carries; a "
                "direction whose optimal gaits the hardware cannot make is left out, with a warning saying why)")
    if command == "SET_PARAM" and error == ErrorCode.SAFETY_LIMIT:
        return (_SAFETY_LIMIT.get(detail, "beyond the safety envelope the firmware was built with (the robot file's "
                                          "[safety])") + ": at run time the envelope can be narrowed, never widened")
    if error == ErrorCode.ESTOP_LATCHED:
        return ("the E-stop is latched: every coil stays off until it is released (CLEAR ESTOP: proleg "
                "console key c, or RobotClient.clear; a reset of the board does not release it, a power cycle does)")
    if command == "LOAD_GAIT" and error == ErrorCode.FORBIDDEN_TRANSITION:
        return (f"step {detail} to the next (the last to the first) is not a transition this robot's firmware "
                "allows: a state that follows itself, or an \"x\" in the robot file's matrix")
    if command == "LOAD_GAIT" and error == ErrorCode.OUT_OF_RANGE:
        if detail == 0:
            return "the gait has no steps, or its step 0 is not one of this robot's states; nothing stored"
        return f"step {detail} is not one of this robot's states (they are numbered from 0); nothing stored"
    if command == "LOAD_GAIT" and error == ErrorCode.TOO_LONG:
        return "more steps than this firmware stores (INFO max_gait_steps); nothing stored"
    if command == "START" and error == ErrorCode.OUT_OF_RANGE:
        return ("the direction is +x (0) or -x (1); only the loaded gait (GAIT_USER) may leave it unstated "
                "(0xFF)")
    if command == "SET_ACTUATOR_MAP" and error == ErrorCode.OUT_OF_RANGE:
        if detail == 0xFFFF:
            return "give one actuator per limb, or none (the build's map); nothing changed"
        return f"limb {detail}'s actuator is not one this build has; nothing changed"
    if command == "SET_ACTUATOR_MAP" and error == ErrorCode.TOO_LONG:
        return "more actuators than this robot has limbs: give one per limb, or none (the build's map); nothing changed"
    if command == "SET_TELEMETRY_RATE" and error == ErrorCode.OUT_OF_RANGE:
        return ("faster than the firmware sends: at most its tick rate, and at most half of what the UART carries "
                "(the rest is kept for replies and events)")
    if command == "CALIBRATE_LEVEL" and error == ErrorCode.OUT_OF_RANGE:
        return "ground is 0 (flat ground: stored) or 1 (this ground: RAM only); nothing began"
    if command == "SET_PARAM" and error == ErrorCode.OUT_OF_RANGE:
        return _OUT_OF_RANGE.get(detail, "outside the parameter's range, or no such limb or index on this robot")
    if error == ErrorCode.TOO_STEEP:
        if detail == TOO_TILTED:
            return ("an end tilts more than 20° at rest: beyond any ground the board levels on, uphill or down "
                    "(docs/calibration.md)")
        return (f"the ground rises {detail / 100:.2f}° in the gait's direction, more than the limit the firmware "
                f"was built with ([control] max_climb_deg); on a gentler slope, or downhill, it starts")
    return ""


#: TOO_STEEP's detail when an end tilts beyond the 20° the board levels on (core/level.h LEVEL_TOO_TILTED)
TOO_TILTED = 0xFFFF


class ReplyTimeout(LinkError):
    """A command got no reply in time (after its retries)."""


@dataclass(frozen=True)
class RobotInfo:
    """The robot's answer to GET_INFO."""

    robot_name: str
    board: str
    build_id: int
    gait_hash: int
    protocol_version: int
    limbs: int
    actuators: int
    gaits: int
    max_gait_steps: int
    tick_hz: int
    telemetry_hz: int

    @classmethod
    def from_message(cls, msg: Message) -> RobotInfo:
        return cls(**{k: msg.fields[k] for k in cls.__dataclass_fields__ if k in msg.fields})  # type: ignore[arg-type]

    def header(self) -> dict[str, str]:
        """Key/value pairs for a recording's header."""
        return {
            "robot": self.robot_name,
            "board": self.board,
            "firmware_build_id": f"{self.build_id:08x}",
            "gait_table_hash": f"{self.gait_hash:08x}",
            "protocol_version": str(self.protocol_version),
            "limbs": str(self.limbs),
            "channels": str(self.actuators),
            "tick_hz": str(self.tick_hz),
            "telemetry_hz": str(self.telemetry_hz),
        }


@dataclass(frozen=True)
class FirmwareStats:
    """The firmware's link counters (reply to GET_STATS)."""

    rx_ok: int
    crc_errors: int
    framing_errors: int
    unknown_ids: int
    bad_length: int
    bad_value: int
    nacks: int
    tx_frames: int
    tx_dropped: int
    tick_overruns: int = 0  # control ticks that overran their period (issue 11)

    @classmethod
    def from_message(cls, msg: Message) -> FirmwareStats:
        return cls(**{k: msg.fields[k] for k in cls.__dataclass_fields__ if k in msg.fields})  # type: ignore[arg-type]
