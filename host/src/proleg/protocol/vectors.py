"""Shared byte-level test vectors for the Python and C codecs.

``python -m proleg.protocol.vectors > tests/vectors/protocol.json`` regenerates the checked-in
file; ``tests/test_protocol_vectors.py`` checks that doing so gives the same bytes. The
frames are made by the Python encoder. Sections:

- ``valid``: one message → its frame (hex). C decodes each and re-encodes the same bytes.
- ``c_encoded``: messages the C test driver (``tests/c/test_proto.c emit``) builds field by
  field, with the frame Python makes of the same values: C must produce exactly these bytes.
- ``corrupt``: byte streams mixing valid frames and damage, with the messages that must still
  decode and the counters both codecs must end with (build of 8 limbs / 8 channels).
"""

from __future__ import annotations

import json
import sys
from binascii import crc_hqx
from typing import Any

from cobs import cobs

from proleg.protocol.codec import COUNTERS, FrameDecoder, Message, encode
from proleg.protocol.definition import (
    DIR_UNSTATED,
    GAIT_USER,
    MAX_GAIT_STEPS,
    PROTOCOL_VERSION,
    ErrorCode,
    EventKind,
    Flag,
    LevelResult,
    LevelStatus,
)

TOKEN_ONLY = ("PING", "GET_INFO", "GET_STATS", "STOP", "ESTOP", "GET_LEVEL", "CLEAR_LEVEL")


def _telemetry(seq: int, psi: tuple[int, ...] = (1234, -567), duty: tuple[int, ...] = (6000, 0)) -> Message:
    return Message.new(
        "TELEMETRY",
        seq=seq,
        time_ms=1000 + seq,
        measured=1,
        target=3,
        gait=0,
        direction=0,
        step=2,
        flags=int(Flag.RUNNING),
        psi=psi,
        duty=duty,
    )


def valid_messages() -> list[Message]:
    """At least one message per type, with edge values (zero, max, empty/full arrays)."""
    msgs: list[Message] = [Message.new(n, token=t) for n in TOKEN_ONLY for t in (1, 255)]
    msgs += [
        Message.new("PING", token=0),
        Message.new("START", token=3, gait=1, direction=1),
        Message.new("START", token=4, gait=GAIT_USER, direction=0),
        Message.new("START", token=7, gait=GAIT_USER, direction=DIR_UNSTATED),
        Message.new("LOAD_GAIT", token=5, states=(0, 1, 3, 2)),
        Message.new("LOAD_GAIT", token=6, states=()),
        Message.new("LOAD_GAIT", token=7, states=tuple(range(65535, 65535 - MAX_GAIT_STEPS, -1))),
        Message.new("SET_PARAM", token=8, param=1, index=0, value=6000),
        Message.new("SET_PARAM", token=9, param=5, index=3, value=-2147483648),
        Message.new("SET_PARAM", token=10, param=2, index=255, value=2147483647),
        Message.new("SET_TELEMETRY_RATE", token=11, hz=50),
        Message.new("SET_TELEMETRY_RATE", token=12, hz=0),
        Message.new("CLEAR", token=13, what=7),
        Message.new(
            "INFO",
            token=0,
            protocol_version=PROTOCOL_VERSION,
            build_id=0x12345678,
            gait_hash=0xFFFFFFFF,
            robot_name="paper-r1",
            board="arduino-nano",
            limbs=2,
            actuators=2,
            gaits=4,
            max_gait_steps=MAX_GAIT_STEPS,
            tick_hz=1000,
            telemetry_hz=50,
        ),
        Message.new(
            "INFO",
            token=14,
            protocol_version=255,
            build_id=0,
            gait_hash=0,
            robot_name="abcdefghijklmno",
            board="",
            limbs=8,
            actuators=8,
            gaits=0,
            max_gait_steps=0,
            tick_hz=65535,
            telemetry_hz=0,
        ),
        _telemetry(0),
        _telemetry(65535, psi=(-32768, 32767, 0, 1, -1, 9000, -9000, 256), duty=(10000,) * 8),
        _telemetry(7, psi=(), duty=()),
        Message.new("EVENT", time_ms=0, kind=int(EventKind.STATE_REACHED), code=1, detail=2),
        Message.new("EVENT", time_ms=4294967295, kind=255, code=255, detail=65535),
        Message.new("ACK", token=1, cmd=4),
        Message.new("NACK", token=2, cmd=7, error=int(ErrorCode.FORBIDDEN_TRANSITION), detail=3),
        Message.new(
            "STATS",
            token=15,
            rx_ok=4294967295,
            crc_errors=0,
            framing_errors=1,
            unknown_ids=2,
            bad_length=3,
            bad_value=4,
            nacks=5,
            tx_frames=6,
            tx_dropped=0,
            tick_overruns=4294967295,
        ),
        # limb→actuator map and limb loss (issue 15)
        Message.new("SET_ACTUATOR_MAP", token=16, actuators=(0, 0)),
        Message.new("SET_ACTUATOR_MAP", token=17, actuators=()),
        Message.new("SET_ACTUATOR_MAP", token=18, actuators=(7, 6, 5, 4, 3, 2, 1, 255)),
        Message.new("GET_ACTUATOR_MAP", token=19),
        Message.new("ACTUATOR_MAP", token=19, lost=1, actuators=(0, 0)),
        Message.new("ACTUATOR_MAP", token=20, lost=255, actuators=()),
        Message.new("EVENT", time_ms=20000, kind=int(EventKind.SUSPECT), code=1, detail=2 * 4 + 3),
        Message.new("EVENT", time_ms=20001, kind=int(EventKind.FALLBACK), code=1, detail=2),
        Message.new("CALIBRATE_LEVEL", token=1, ground=0),
        Message.new("CALIBRATE_LEVEL", token=255, ground=1),
        Message.new("LEVEL", token=16, status=int(LevelStatus.STORED), offset=(312, -2000), ground=(1000, -1000)),
        Message.new("LEVEL", token=255, status=int(LevelStatus.NONE), offset=(0,) * 8, ground=(0,) * 8),
        Message.new("LEVEL", token=1, status=int(LevelStatus.CORRUPT), offset=(), ground=()),
        Message.new("LEVEL", token=2, status=int(LevelStatus.CALIBRATING), offset=(-32768, 32767, 1, -1), ground=(7,)),
        Message.new("EVENT", time_ms=5000, kind=int(EventKind.LEVEL_DONE), code=int(LevelResult.STORED), detail=3),
    ]
    return msgs


#: What ``test_proto emit`` builds in C (keep the two in step).
C_ENCODED: tuple[Message, ...] = (
    Message.new(
        "TELEMETRY",
        seq=65535,
        time_ms=4000000000,
        measured=2,
        target=3,
        gait=GAIT_USER,
        direction=1,
        step=1,
        flags=int(Flag.RUNNING | Flag.USER_GAIT),
        psi=(-2050, 3000),
        duty=(6000, 0),
    ),
    Message.new(
        "INFO",
        token=0,
        protocol_version=PROTOCOL_VERSION,
        build_id=0xDEADBEEF,
        gait_hash=0x01020304,
        robot_name="paper-r1",
        board="arduino-nano",
        limbs=2,
        actuators=2,
        gaits=4,
        max_gait_steps=MAX_GAIT_STEPS,
        tick_hz=1000,
        telemetry_hz=50,
    ),
    Message.new("NACK", token=7, cmd=0x07, error=int(ErrorCode.FORBIDDEN_TRANSITION), detail=3),
    Message.new("EVENT", time_ms=123456, kind=int(EventKind.FAULT), code=1, detail=1),
    Message.new(
        "STATS",
        token=9,
        rx_ok=100000,
        crc_errors=1,
        framing_errors=2,
        unknown_ids=3,
        bad_length=4,
        bad_value=5,
        nacks=6,
        tx_frames=7,
        tx_dropped=8,
        tick_overruns=9,
    ),
    Message.new("SET_PARAM", token=255, param=5, index=1, value=-2147483648),
    Message.new("SET_ACTUATOR_MAP", token=16, actuators=(0, 0)),
    Message.new("ACTUATOR_MAP", token=19, lost=1, actuators=(1, 0)),
    Message.new("EVENT", time_ms=20000, kind=int(EventKind.SUSPECT), code=1, detail=2 * 4 + 3),
    Message.new("LEVEL", token=17, status=int(LevelStatus.STORED), offset=(312, -2000), ground=(-995, 1003)),
    Message.new("EVENT", time_ms=70000, kind=int(EventKind.LEVEL_DONE), code=int(LevelResult.TOO_TILTED), detail=2),
)


def _frame(raw: bytes) -> bytes:
    """Frame arbitrary msg_id+payload bytes with a correct CRC (for structurally bad payloads)."""
    crc = crc_hqx(raw, 0xFFFF)
    return cobs.encode(raw + bytes((crc & 0xFF, crc >> 8))) + b"\0"


def corrupt_streams() -> list[tuple[str, bytes]]:
    """(description, stream) pairs; expected outcomes are computed by the Python decoder
    and must be matched by C."""
    a = encode(_telemetry(1))
    b = encode(Message.new("ACK", token=1, cmd=4))
    c = encode(Message.new("LOAD_GAIT", token=5, states=(0, 1, 3, 2)))
    flipped = bytearray(a)
    flipped[5] ^= 0x01
    bad_cobs = bytearray(a)
    bad_cobs[0] = 0x30  # first block claims more bytes than the frame has
    tele_raw = cobs.decode(a[:-1])[:-2]
    return [
        ("clean frames back to back", a + b + c),
        ("empty frames (00 00) are ignored", b"\0\0" + a + b"\0\0\0" + b),
        ("leading garbage without a delimiter is one broken frame", b"\x13\x37\xaa" + a + b),
        ("one flipped payload bit is a CRC error", a + bytes(flipped) + b),
        ("COBS code pointing past the frame end is a framing error", a + bytes(bad_cobs) + b),
        ("frame cut short (tail lost) is one framing error, the next decodes", a[:10] + b"\0" + b),
        ("two-byte frame is too short", b"\x03\x41\x42\x00" + a),
        ("frame longer than 64 bytes is a framing error", bytes(range(1, 120)) + b"\0" + a),
        ("very long garbage run without 0x00", bytes([0x55]) * 1000 + b"\0" + b + a),
        ("unknown id with a valid CRC", _frame(b"\x7e\x01") + a),
        ("telemetry with one byte missing is a bad length", _frame(tele_raw[:-1]) + a),
        ("telemetry with one extra byte is a bad length", _frame(tele_raw + b"\x00") + a),
        ("command with an empty payload is a bad length", _frame(b"\x01") + a),
        (
            "psi count 9 above the 8-limb ceiling is a bad value",
            _frame(tele_raw[:16] + b"\x09" + b"\x00" * 18 + b"\x00") + a,
        ),
        (
            "LOAD_GAIT with 25 states is a bad value",
            _frame(b"\x07\x05\x19" + b"\x01\x00" * 25) + c,
        ),
        ("array count present but elements missing is a bad length", _frame(b"\x07\x05\x03\x01\x00") + b),
        ("garbage with zeros between frames", a + b"\xff\x00\x01\x02\x00\xfe\xfd\x00" + b + a),
    ]


def _fields_json(msg: Message) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in msg.fields.items()}


def build() -> dict[str, Any]:
    """The whole vectors document."""
    corrupt = []
    for desc, stream in corrupt_streams():
        dec = FrameDecoder()
        msgs = dec.feed(stream)
        corrupt.append(
            {
                "description": desc,
                "stream": stream.hex(),
                "decoded": [encode(m).hex() for m in msgs],
                "counters": {k: getattr(dec, k) for k in COUNTERS},
            }
        )
    return {
        "comment": "generated by python -m proleg.protocol.vectors - do not edit",
        "protocol_version": PROTOCOL_VERSION,
        "limits": {"max_limbs": 8, "max_channels": 8},
        "valid": [{"name": m.name, "fields": _fields_json(m), "frame": encode(m).hex()} for m in valid_messages()],
        "c_encoded": [{"name": m.name, "fields": _fields_json(m), "frame": encode(m).hex()} for m in C_ENCODED],
        "corrupt": corrupt,
    }


def dumps() -> str:
    return json.dumps(build(), indent=1) + "\n"


if __name__ == "__main__":
    sys.stdout.write(dumps())
