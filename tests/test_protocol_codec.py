"""Python codec: round trips, framing details, refusals, and garbage tolerance."""

from __future__ import annotations

from binascii import crc_hqx

import pytest
from cobs import cobs
from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.errors import ProtocolError
from proleg.protocol import (
    COUNTERS,
    MESSAGES,
    FrameDecoder,
    Message,
    decode_frame,
    encode,
    pack,
    unpack,
)
from proleg.protocol.definition import MAX_ENCODED_FRAME, MAX_FRAME
from proleg.protocol.testing import corrupted_stream, is_subsequence, messages, nonempty_chunks


def telemetry(seq: int = 1, psi: tuple[int, ...] = (100, -200), duty: tuple[int, ...] = (5000, 0)) -> Message:
    return Message.new(
        "TELEMETRY", seq=seq, time_ms=10, measured=1, target=2, gait=0, direction=0, step=0, flags=0, psi=psi, duty=duty
    )


def test_frame_is_cobs_of_id_payload_and_little_endian_crc_then_zero() -> None:
    frame = encode(Message.new("ACK", token=5, cmd=4))
    assert frame.endswith(b"\0") and b"\0" not in frame[:-1]
    raw = cobs.decode(frame[:-1])
    assert raw[:3] == bytes([0x43, 5, 4])
    assert int.from_bytes(raw[3:], "little") == crc_hqx(raw[:3], 0xFFFF)


def test_crc_is_ccitt_false_check_value() -> None:
    assert crc_hqx(b"123456789", 0xFFFF) == 0x29B1


def test_variable_array_is_preceded_by_its_count() -> None:
    raw = pack(Message.new("LOAD_GAIT", token=1, states=(1, 2, 0x0302)))
    assert raw == bytes([0x07, 1, 3, 1, 0, 2, 0, 2, 3])


def test_text_field_is_nul_padded_to_its_length_and_decodes_back() -> None:
    info = Message.new(
        "INFO", token=0, protocol_version=1, build_id=1, gait_hash=2, robot_name="r1", board="host-sim",
        limbs=2, actuators=2, gaits=1, max_gait_steps=24, tick_hz=1000, telemetry_hz=50,
    )  # fmt: skip
    raw = pack(info)
    assert raw[11:27] == b"r1" + b"\0" * 14
    assert unpack(raw) == info


@pytest.mark.parametrize("spec", MESSAGES, ids=lambda m: m.name)
def test_every_message_fits_64_bytes_before_cobs_at_the_ceilings(spec) -> None:
    assert spec.max_frame() <= MAX_FRAME


@given(messages())
@settings(max_examples=600, deadline=None)
def test_every_message_type_round_trips_through_the_python_codec(msg: Message) -> None:
    frame = encode(msg)
    assert len(frame) <= MAX_ENCODED_FRAME
    dec = FrameDecoder()
    assert dec.feed(frame) == [msg]
    assert dec.frames_ok == 1 and sum(dec.counters().values()) == 1


@given(st.lists(messages(), max_size=20), st.data())
@settings(max_examples=100, deadline=None)
def test_stream_split_at_arbitrary_points_decodes_the_same(msgs: list[Message], data) -> None:
    stream = b"".join(encode(m) for m in msgs)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=10)))
    dec = FrameDecoder()
    out = []
    for a, b in zip([0, *cuts], [*cuts, len(stream)]):
        out += dec.feed(stream[a:b])
    assert out == msgs


@pytest.mark.parametrize(
    ("msg", "match"),
    [
        (Message.new("NOPE", token=1), "unknown message name"),
        (Message.new("PING"), "missing fields"),
        (Message.new("PING", token=1, extra=2), "unknown fields"),
        (Message.new("PING", token=256), "outside 0..255"),
        (Message.new("PING", token=-1), "outside"),
        (Message.new("PING", token=True), "expected int"),
        (Message.new("PING", token="1"), "expected int"),
        (Message.new("SET_PARAM", token=1, param=1, index=0, value=2**31), "outside"),
        (telemetry(psi=(0,) * 9), "at most 8"),
        (telemetry(psi=(40000,)), "outside"),
        (telemetry(psi=5), "sequence"),
        (Message.new("LOAD_GAIT", token=1, states=(0,) * 25), "at most 24"),
    ],
)
def test_encode_refuses_messages_outside_the_definition(msg: Message, match: str) -> None:
    with pytest.raises(ProtocolError, match=match):
        encode(msg)


@pytest.mark.parametrize("name", ["x" * 16, "héllo", "a\0b"])
def test_encode_refuses_text_that_is_too_long_or_not_plain_ascii(name: str) -> None:
    msg = Message.new(
        "INFO", token=0, protocol_version=1, build_id=1, gait_hash=2, robot_name=name, board="b",
        limbs=2, actuators=2, gaits=1, max_gait_steps=24, tick_hz=1000, telemetry_hz=50,
    )  # fmt: skip
    with pytest.raises(ProtocolError, match="robot_name"):
        encode(msg)


def test_message_fields_are_readable_as_attributes_and_items() -> None:
    m = telemetry()
    assert m.psi == m["psi"] == (100, -200)
    assert m.id == 0x41 and m.spec.name == "TELEMETRY"
    with pytest.raises(AttributeError):
        m.nonexistent  # noqa: B018


def test_decode_frame_raises_protocol_error_naming_the_problem() -> None:
    frame = bytearray(encode(Message.new("ACK", token=5, cmd=4)))  # 06 43 05 04 c c 00
    frame[2] ^= 0x01
    with pytest.raises(ProtocolError, match="bad CRC"):
        decode_frame(bytes(frame))
    with pytest.raises(ProtocolError, match="unknown message id"):
        unpack(b"\x7e")


def test_smaller_build_limits_count_longer_arrays_as_bad_value() -> None:
    dec = FrameDecoder(max_limbs=2, max_channels=2)
    assert dec.feed(encode(telemetry(psi=(1, 2, 3))) + encode(telemetry(seq=2))) == [telemetry(seq=2)]
    assert dec.bad_value == 1 and dec.frames_ok == 1


def test_overlong_run_without_delimiter_is_one_framing_error_even_across_feeds() -> None:
    dec = FrameDecoder()
    for _ in range(50):
        assert dec.feed(b"\x55" * 100) == []
    assert dec.feed(b"\0" + encode(telemetry())) == [telemetry()]
    assert dec.framing_errors == 1 and dec.frames_ok == 1


# ----------------------------------------------------------------------------- corruption
@given(st.lists(messages(), min_size=1, max_size=12), st.data())
@settings(max_examples=300, deadline=None)
def test_python_decoder_survives_corruption_and_decodes_every_untouched_frame(msgs, data) -> None:
    stream, untouched = corrupted_stream(msgs, data)
    dec = FrameDecoder()
    out = dec.feed(stream)
    assert is_subsequence(untouched, out)
    # every non-empty chunk between delimiters is either a message or exactly one error
    assert sum(dec.counters().values()) == nonempty_chunks(stream)
    assert dec.frames_ok == len(out)


@given(st.binary(max_size=2000))
@settings(max_examples=300, deadline=None)
def test_random_bytes_never_raise_and_every_chunk_is_counted_once(garbage: bytes) -> None:
    dec = FrameDecoder()
    out = dec.feed(garbage + b"\0")
    assert sum(dec.counters().values()) == nonempty_chunks(garbage + b"\0")
    assert dec.frames_ok == len(out)
    assert set(dec.counters()) == set(COUNTERS)
