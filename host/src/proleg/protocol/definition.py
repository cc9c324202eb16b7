"""The link protocol's single definition: messages, fields and enums.

Everything else is derived from this module: the Python codec (``codec.py``) interprets
``MESSAGES``, and ``render.py`` turns the same tables into the C header/tables
(``proto_gen.h``/``proto_gen.c``) that the hand-written C runtime (``proto.c``) interprets.
Change a message here, bump ``PROTOCOL_VERSION``, regenerate ``tests/vectors/protocol.json``.

Wire format of one frame: ``COBS(msg_id:u8 | payload | crc16:u16-le) 0x00``, CRC-16/CCITT-FALSE
over msg_id + payload, payload fields little-endian and packed, in the order listed here.

The definition spans three modules: this one (``PROTOCOL_VERSION``, frame and field sizes, the
message table ``MESSAGES``, which reply answers which command), ``enums.py`` (the value sets:
``EventKind``, ``ErrorCode``, ``Flag``... and ``ENUMS``, the ones rendered into C) and
``layout.py`` (field types, ``Field``, ``MessageSpec``, the limb/channel ceilings). Import
everything from here.

Field kinds
- scalar: ``u8 u16 u32 i16 i32``
- text: ``char`` with a fixed ``length`` (NUL-padded; at most ``length - 1`` characters, ASCII)
- variable array: ``max_count`` set (an int, or ``"limbs"`` / ``"channels"`` resolved against
  the build's limits). On the wire a ``u8`` count precedes the elements; in C the struct has
  ``uint8_t <name>_count`` before ``<type> <name>[max]``; in Python the value is a tuple.

Conventions
- Every host→robot command starts with ``token`` (u8, 1..255 chosen by the host; 0 is what the
  robot uses for unsolicited messages). Every command is answered by exactly one reply that
  echoes the token: the reply its ``MessageSpec.reply`` names (``INFO`` for ``GET_INFO``,
  ``STATS`` for ``GET_STATS``, ``ACK`` for the others), or ``NACK``. ``ACK`` and ``NACK`` also
  carry the command's id, so a host matches a reply by token *and* command
  (``reply_answers``).
- Ids 0x01..0x3F host→robot, 0x40..0x7F robot→host.
"""

from __future__ import annotations

from enum import IntEnum, IntFlag

# The value sets and the layout classes live in their own modules; every name is re-exported
# here, so ``from proleg.protocol.definition import EventKind, Field, LIMB_CEILING`` still works.
from .enums import (
    ENUMS,
    ClearWhat,
    Direction,
    ErrorCode,
    EventKind,
    FaultCode,
    Flag,
    LevelResult,
    LevelStatus,
    ParamId,
    ResetCause,
    StopReason,
)
from .layout import CHANNEL_CEILING, LIMB_CEILING, TYPES, Field, MessageSpec, ScalarType

#: 2: STATS.tick_overruns; CALIBRATE_LEVEL / GET_LEVEL / CLEAR_LEVEL and LEVEL; SET_ACTUATOR_MAP /
#: GET_ACTUATOR_MAP and ACTUATOR_MAP; EVENT kinds SUSPECT, FALLBACK, LEVEL_DONE. 3: START of the
#: loaded gait states its way (or DIR_UNSTATED), which the climb guard checks.
PROTOCOL_VERSION = 3

#: Largest frame before COBS (msg_id + payload + crc) for any build of up to
#: ``LIMB_CEILING`` limbs and ``CHANNEL_CEILING`` channels. The C receive buffer has this size.
MAX_FRAME = 64
#: Largest frame on the wire: COBS adds one byte per 254 (here: one), plus the 0x00 delimiter.
MAX_ENCODED_FRAME = MAX_FRAME + 2
#: Longest state sequence LOAD_GAIT carries (states are u16).
MAX_GAIT_STEPS = 24
#: ``START.gait`` value that selects the sequence sent by LOAD_GAIT.
GAIT_USER = 0xFF
#: ``START.direction`` of a LOAD_GAIT sequence whose way the host does not state (a learning
#: probe, a planar heading): the climb guard does not check it. PLUS_X / MINUS_X there state
#: which way the loaded sequence walks, and the guard checks that way as for a built-in gait.
DIR_UNSTATED = 0xFF
#: Fixed text field sizes (bytes incl. the terminating NUL).
ROBOT_NAME_LEN = 16
BOARD_NAME_LEN = 16


def _u8(name: str, doc: str = "", enum: type[IntEnum] | type[IntFlag] | None = None) -> Field:
    return Field(name, "u8", doc, enum=enum)


_TOKEN = _u8("token", "echoed in the reply (1..255; 0 = unsolicited)")

MESSAGES: tuple[MessageSpec, ...] = (
    # ---------------------------------------------------------------- host → robot
    MessageSpec(0x01, "PING", "h2r", (_TOKEN,), "Liveness check; answered by ACK.", reply="ACK"),
    MessageSpec(0x02, "GET_INFO", "h2r", (_TOKEN,), "Answered by INFO.", reply="INFO"),
    MessageSpec(0x03, "GET_STATS", "h2r", (_TOKEN,), "Answered by STATS (link counters).", reply="STATS"),
    MessageSpec(
        0x04,
        "START",
        "h2r",
        (
            _TOKEN,
            _u8("gait", "gait table index, or GAIT_USER (0xFF) for the LOAD_GAIT sequence"),
            _u8("direction", "Direction; with GAIT_USER the way the loaded sequence walks, or DIR_UNSTATED "
                "(0xFF): not stated, not climb-guarded", Direction),
        ),
        "Run a gait; NACK NO_GAIT (detail = gait) / ESTOP_LATCHED / NOT_ALLOWED (detail 0: a fault is latched, 1: a "
        "gait runs, 2: the state is not known: no reading from every IMU yet, 3: a built-in gait while the fallback "
        "has given up a coil, until SET_ACTUATOR_MAP with no entries takes it back) / OUT_OF_RANGE (detail 2: a "
        "direction other than PLUS_X / MINUS_X, or DIR_UNSTATED for a built-in gait) / TOO_STEEP (the ground rises "
        "more than the build's max_climb_deg in the gait's direction: detail = that climb in 0.01°). Where several "
        "apply, the first of: ESTOP_LATCHED, NOT_ALLOWED 0, 2, 1, OUT_OF_RANGE, NO_GAIT, NOT_ALLOWED 3, TOO_STEEP.",
        reply="ACK",
    ),
    MessageSpec(0x05, "STOP", "h2r", (_TOKEN,), "Stop the gait, all actuators off.", reply="ACK"),
    MessageSpec(0x06, "ESTOP", "h2r", (_TOKEN,), "Latch E-stop: MOSFETs off until CLEAR(ESTOP).", reply="ACK"),
    MessageSpec(
        0x07,
        "LOAD_GAIT",
        "h2r",
        (
            _TOKEN,
            Field("states", "u16", "closed walk without the repeated start state", max_count=MAX_GAIT_STEPS),
        ),
        "Store the user gait; firmware checks each step against the allowed transitions "
        "(NACK FORBIDDEN_TRANSITION, detail = step index; a state that follows itself, a one-state walk "
        "included, is one). A last state equal to the first closes the walk and is dropped. NACK NOT_ALLOWED "
        "(detail 0) while a gait runs, OUT_OF_RANGE for a state the robot does not have (detail = its step) or "
        "no steps (detail 0), TOO_LONG above the build's max_gait_steps. Nothing is stored on a NACK.",
        reply="ACK",
    ),
    MessageSpec(
        0x08,
        "SET_PARAM",
        "h2r",
        (
            _TOKEN,
            _u8("param", "ParamId", ParamId),
            _u8("index", "limb/channel/level index where the param has one, else 0"),
            Field("value", "i32", "in the param's unit"),
        ),
        "Change a whitelisted parameter inside the build's safety envelope; NACK SAFETY_LIMIT for a value "
        "that would widen it, OUT_OF_RANGE for an unknown param, a value outside its range or no such index "
        "(detail = param, both).",
        reply="ACK",
    ),
    MessageSpec(
        0x09,
        "SET_TELEMETRY_RATE",
        "h2r",
        (_TOKEN, Field("hz", "u16", "0 = telemetry off; NACK OUT_OF_RANGE above tick_hz or above half what the "
                            "UART carries")),
        "Change the TELEMETRY rate.",
        reply="ACK",
    ),
    MessageSpec(
        0x0A,
        "CLEAR",
        "h2r",
        (_TOKEN, _u8("what", "ClearWhat bits", ClearWhat)),
        "Clear latched faults / E-stop / link counters.",
        reply="ACK",
    ),
    MessageSpec(
        0x0B,
        "CALIBRATE_LEVEL",
        "h2r",
        (_TOKEN, _u8("ground", "0: on flat ground, store the result; 1: level on this ground (a slope), RAM only")),
        "Record each IMU's rest tilt (the mean of 64 ticks' samples; robot at rest, coils cold): "
        "on flat ground as its level offset, stored in non-volatile memory; with ground = 1 as "
        "this ground's tilt on top of it, until a power-on (a reset that keeps the coils' budget keeps it). ACK when sampling begins, then EVENT LEVEL_DONE. NACK NOT_ALLOWED while a gait runs (detail 1), an IMU is bad (2), "
        "a fault is latched (3), a calibration is under way (4), the build leaves level "
        "calibration out (5), or a gait ran or a fault latched since the robot was last at rest for 2 s (6); "
        "OUT_OF_RANGE (detail 1) for a ground other than 0 or 1, checked first.",
        reply="ACK",
    ),
    MessageSpec(0x0C, "GET_LEVEL", "h2r", (_TOKEN,), "Answered by LEVEL.", reply="LEVEL"),
    MessageSpec(
        0x0D,
        "CLEAR_LEVEL",
        "h2r",
        (_TOKEN,),
        "Erase the stored level record: offsets 0 (NACK NOT_ALLOWED while a gait runs or a "
        "calibration is under way; detail 5: the build leaves level calibration out).",
        reply="ACK",
    ),
    # ---------------------------------------------------------------- robot → host
    MessageSpec(
        0x40,
        "INFO",
        "r2h",
        (
            _TOKEN,
            _u8("protocol_version"),
            Field("build_id", "u32", "firmware build id"),
            Field("gait_hash", "u32", "hash of the compiled gait table"),
            Field("robot_name", "char", "robot file name", length=ROBOT_NAME_LEN),
            Field("board", "char", "board name", length=BOARD_NAME_LEN),
            _u8("limbs"),
            _u8("actuators"),
            _u8("gaits", "number of compiled gaits"),
            _u8("max_gait_steps", "LOAD_GAIT capacity of this build"),
            Field("tick_hz", "u16"),
            Field("telemetry_hz", "u16"),
        ),
        "Reply to GET_INFO; also sent unsolicited (token 0) after reset.",
    ),
    MessageSpec(
        0x41,
        "TELEMETRY",
        "r2h",
        (
            Field("seq", "u16", "increments per TELEMETRY frame, wraps"),
            Field("time_ms", "u32", "firmware time"),
            Field("measured", "u16", "measured (debounced) state index"),
            Field("target", "u16", "target state index of the current step"),
            _u8("gait", "running gait index (GAIT_USER for the loaded one)"),
            _u8("direction", "Direction", Direction),
            _u8("step", "gait step index"),
            Field("flags", "u16", "Flag bits", enum=Flag),
            Field("psi", "i16", "contact angle per limb, 0.01°", max_count="limbs"),
            Field("duty", "u16", "SMA duty per channel, permyriad", max_count="channels"),
        ),
        "Periodic state, at telemetry_hz.",
    ),
    MessageSpec(
        0x42,
        "EVENT",
        "r2h",
        (
            Field("time_ms", "u32"),
            _u8("kind", "EventKind", EventKind),
            _u8("code", "meaning per kind"),
            Field("detail", "u16", "meaning per kind"),
        ),
        "Something happened (state reached, fault, gait started/stopped, E-stop...).",
    ),
    MessageSpec(
        0x43,
        "ACK",
        "r2h",
        (_TOKEN, _u8("cmd", "id of the acknowledged command")),
        "Command accepted.",
    ),
    MessageSpec(
        0x44,
        "NACK",
        "r2h",
        (
            _TOKEN,
            _u8("cmd", "id of the refused command"),
            _u8("error", "ErrorCode", ErrorCode),
            Field("detail", "u16", "offending index / param id, else 0"),
        ),
        "Command refused.",
    ),
    MessageSpec(
        0x45,
        "STATS",
        "r2h",
        (
            _TOKEN,
            Field("rx_ok", "u32", "valid frames received"),
            Field("crc_errors", "u32"),
            Field("framing_errors", "u32", "bad COBS, too short, too long"),
            Field("unknown_ids", "u32"),
            Field("bad_length", "u32"),
            Field("bad_value", "u32", "array count above the build maximum"),
            Field("nacks", "u32", "NACKs sent"),
            Field("tx_frames", "u32", "frames queued for sending"),
            Field("tx_dropped", "u32", "frames dropped because the TX queue was full"),
            Field("tick_overruns", "u32", "control ticks whose work did not end within the tick period"),
        ),
        "Reply to GET_STATS: the firmware's link counters and its tick overruns.",
    ),
    # ---------------------------------------------------------------- limb→actuator map (issue 15)
    MessageSpec(
        0x14,
        "SET_ACTUATOR_MAP",
        "h2r",
        (_TOKEN, Field("actuators", "u8", "actuator index per limb, first limb first; empty: the build's map "
                       "(a coil the fallback gave up taken back)",
                       max_count="limbs")),
        "Set which actuator raises each limb (the safety envelope stays per actuator); NACK NOT_ALLOWED "
        "while a gait runs, OUT_OF_RANGE (detail = limb index; 0xFFFF: fewer than one per limb) for a bad value, "
        "TOO_LONG (detail 0) for more entries than the build has limbs (refused as it is received, before NOT_ALLOWED).",
        reply="ACK",
    ),
    MessageSpec(0x15, "GET_ACTUATOR_MAP", "h2r", (_TOKEN,), "Answered by ACTUATOR_MAP.", reply="ACTUATOR_MAP"),
    MessageSpec(
        0x4A,
        "ACTUATOR_MAP",
        "r2h",
        (
            _TOKEN,
            _u8("lost", "actuator the firmware's fallback gave up (FALLBACK event), 0xFF: none"),
            Field("actuators", "u8", "actuator index per limb, first limb first", max_count="limbs"),
        ),
        "Reply to GET_ACTUATOR_MAP: the limb→actuator map in use.",
    ),
    MessageSpec(
        0x46,
        "LEVEL",
        "r2h",
        (
            _TOKEN,
            _u8("status", "LevelStatus", LevelStatus),
            Field("offset", "i16", "stored rest tilt per limb subtracted from ψ, 0.01° (0 unless STORED)",
                  max_count="limbs"),
            Field("ground", "i16", "this ground's tilt per limb subtracted on top (CALIBRATE_LEVEL ground = 1; "
                  "0 after reset), 0.01°", max_count="limbs"),
        ),
        "Reply to GET_LEVEL: the level calibration in use.",
    ),
)

__all__ = [
    "BOARD_NAME_LEN",
    "BY_ID",
    "BY_NAME",
    "CHANNEL_CEILING",
    "DIR_UNSTATED",
    "ENUMS",
    "GAIT_USER",
    "LIMB_CEILING",
    "MAX_ENCODED_FRAME",
    "MAX_FRAME",
    "MAX_GAIT_STEPS",
    "MESSAGES",
    "PROTOCOL_VERSION",
    "REPLIES_WITH_CMD",
    "ROBOT_NAME_LEN",
    "TYPES",
    "ClearWhat",
    "Direction",
    "ErrorCode",
    "EventKind",
    "FaultCode",
    "Field",
    "Flag",
    "LevelResult",
    "LevelStatus",
    "MessageSpec",
    "ParamId",
    "ResetCause",
    "ScalarType",
    "StopReason",
    "check_definition",
    "reply_answers",
]

BY_NAME: dict[str, MessageSpec] = {m.name: m for m in MESSAGES}
BY_ID: dict[int, MessageSpec] = {m.id: m for m in MESSAGES}


#: replies that echo the command's id in a ``cmd`` field
REPLIES_WITH_CMD = ("ACK", "NACK")


def reply_answers(reply_name: str, fields: dict, command: MessageSpec) -> bool:
    """Whether a reply (already matched by token) answers ``command``: it is the command's
    declared reply or NACK, and, where the reply carries ``cmd``, for this command. A stale ACK
    for another command with the same token does not answer it."""
    if reply_name != command.reply and reply_name != "NACK":
        return False
    if reply_name in REPLIES_WITH_CMD:
        return fields.get("cmd") == command.id
    return True


def check_definition() -> None:
    """Assert the table's invariants (unique ids/names, sizes, frame limit); raises ValueError."""
    if len(BY_NAME) != len(MESSAGES) or len(BY_ID) != len(MESSAGES):
        raise ValueError("duplicate message id or name")
    for m in MESSAGES:
        if not 0 < m.id < 0x80:
            raise ValueError(f"{m.name}: id {m.id:#x} outside 0x01..0x7F")
        if (m.direction == "h2r") != (m.id < 0x40):
            raise ValueError(f"{m.name}: id {m.id:#x} in the wrong direction range")
        if m.direction == "h2r" and (not m.fields or m.fields[0].name != "token"):
            raise ValueError(f"{m.name}: commands must start with token")
        if m.direction == "h2r":
            r = BY_NAME.get(m.reply or "")
            if r is None or r.direction != "r2h" or not r.fields or r.fields[0].name != "token":
                raise ValueError(f"{m.name}: reply {m.reply!r} is not a robot->host message starting with token")
        elif m.reply is not None:
            raise ValueError(f"{m.name}: only commands have a reply")
        names = [f.name for f in m.fields]
        if len(set(names)) != len(names):
            raise ValueError(f"{m.name}: duplicate field name")
        for f in m.fields:
            if f.type not in TYPES:
                raise ValueError(f"{m.name}.{f.name}: unknown type {f.type}")
            if (f.type == "char") != (f.length is not None):
                raise ValueError(f"{m.name}.{f.name}: char fields need a length (and only they)")
            if f.is_array and f.resolved_max(LIMB_CEILING, CHANNEL_CEILING) > 255:
                raise ValueError(f"{m.name}.{f.name}: array max above 255")
        if m.max_frame() > MAX_FRAME:
            raise ValueError(f"{m.name}: {m.max_frame()} bytes > MAX_FRAME {MAX_FRAME}")


check_definition()
