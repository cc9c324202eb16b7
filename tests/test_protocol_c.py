"""The C runtime against the Python codec: shared vectors, round trips, corruption.

A small driver (tests/c/test_proto.c) is compiled with the host ``cc`` against the rendered
proto_gen.[ch] into a tmp dir, warning-free with -std=c99 -Wall -Wextra -Werror -pedantic.
Many messages go through one process invocation to keep this fast.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from proleg.protocol import COUNTERS, FrameDecoder, Message, encode, render_c
from proleg.protocol.testing import corrupted_stream, is_subsequence, messages

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
VECTORS = json.loads((ROOT / "tests" / "vectors" / "protocol.json").read_text())
CFLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1"]
RUNTIME = ["proto.c", "proto_gen.c", "cobs.c", "crc16.c"]

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no host C compiler")


@dataclass
class StreamResult:
    frames: list[bytes]  # re-encoded by C, one per decoded message
    rejects: list[tuple[int, int, int]]  # (id, token, error) of refused CRC-valid frames
    counters: dict[str, int]


class CDriver:
    def __init__(self, exe: Path) -> None:
        self.exe = exe

    def run(self, mode: str, stdin: bytes = b"") -> list[str]:
        res = subprocess.run([str(self.exe), mode], input=stdin, capture_output=True, timeout=60, check=False)
        assert res.returncode == 0, res.stdout.decode() + res.stderr.decode()
        return res.stdout.decode().splitlines()

    def stream(self, data: bytes) -> StreamResult:
        frames, rejects, counters = [], [], {}
        for line in self.run("stream", data):
            tag, *rest = line.split()
            if tag == "M":
                frames.append(bytes.fromhex(rest[0]) if rest else b"")
            elif tag == "R":
                rejects.append(tuple(int(x) for x in rest))
            elif tag == "C":
                counters = dict(zip(COUNTERS, (int(x) for x in rest)))
        return StreamResult(frames, rejects, counters)


#: proto.c's two table layouts: per-field descriptors (ARM, host-sim) and, where structs have
#: no padding (AVR), per-message byte strings; on the host the second packs the structs.
LAYOUTS = {"fields": [], "packed": ["-DPROTO_PACKED_LAYOUT=1"]}


def build_driver(out: Path, max_limbs: int, max_channels: int, layout: str = "fields") -> CDriver:
    out.mkdir(parents=True, exist_ok=True)
    for name, text in render_c(max_limbs, max_channels).items():
        (out / name).write_text(text)
    for name in ["proto.h", "proto.c", "cobs.h", "cobs.c", "crc16.h", "crc16.c"]:
        shutil.copy(CORE / name, out / name)
    shutil.copy(ROOT / "tests" / "c" / "test_proto.c", out / "test_proto.c")
    exe = out / "test_proto"
    subprocess.run(
        ["cc", *CFLAGS, *LAYOUTS[layout], "-o", str(exe), "test_proto.c", *RUNTIME], cwd=out, check=True, capture_output=True, timeout=120
    )
    return CDriver(exe)


@pytest.fixture(scope="module", params=sorted(LAYOUTS))
def c8(tmp_path_factory, request) -> CDriver:
    """Driver built for the protocol ceilings (8 limbs, 8 channels), like the vectors."""
    return build_driver(tmp_path_factory.mktemp("proto8"), 8, 8, request.param)


@pytest.fixture(scope="module", params=sorted(LAYOUTS))
def c2(tmp_path_factory, request) -> CDriver:
    return build_driver(tmp_path_factory.mktemp("proto2"), 2, 2, request.param)


def test_c_runtime_selftest_passes(c8: CDriver) -> None:
    assert c8.run("selftest") == ["OK"]


def test_c_decodes_every_python_vector_and_reencodes_the_same_bytes(c8: CDriver) -> None:
    frames = [bytes.fromhex(v["frame"]) for v in VECTORS["valid"]]
    res = c8.stream(b"".join(frames))
    assert res.frames == frames
    assert res.counters["frames_ok"] == len(frames) and sum(res.counters.values()) == len(frames)


def test_frames_built_field_by_field_in_c_equal_the_python_encoding(c8: CDriver) -> None:
    expected = [bytes.fromhex(v["frame"]) for v in VECTORS["c_encoded"]]
    got = [bytes.fromhex(line.split()[1]) for line in c8.run("emit")]
    assert got == expected
    dec = FrameDecoder()
    assert [m.fields for m in dec.feed(b"".join(got))] == [
        {k: tuple(v) if isinstance(v, list) else v for k, v in e["fields"].items()} for e in VECTORS["c_encoded"]
    ]


@pytest.mark.parametrize("vec", VECTORS["corrupt"], ids=lambda v: v["description"])
def test_corrupt_vector_gives_the_same_frames_and_counters_in_c_and_python(c8: CDriver, vec: dict) -> None:
    stream = bytes.fromhex(vec["stream"])
    res = c8.stream(stream)
    assert res.frames == [bytes.fromhex(h) for h in vec["decoded"]]
    assert res.counters == vec["counters"]
    dec = FrameDecoder()
    assert [encode(m) for m in dec.feed(stream)] == res.frames
    assert dec.counters() == vec["counters"]


def test_c_reports_refused_crc_valid_frames_for_nacking(c8: CDriver) -> None:
    by_desc = {v["description"]: bytes.fromhex(v["stream"]) for v in VECTORS["corrupt"]}
    assert c8.stream(by_desc["unknown id with a valid CRC"]).rejects == [(0x7E, 1, 1)]  # UNKNOWN_MESSAGE
    assert c8.stream(by_desc["LOAD_GAIT with 25 states is a bad value"]).rejects == [(0x07, 5, 6)]  # TOO_LONG
    assert c8.stream(by_desc["command with an empty payload is a bad length"]).rejects == [(0x01, 0, 3)]


@given(st.lists(messages(), min_size=1, max_size=60))
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_every_message_type_round_trips_through_the_c_codec(c8: CDriver, msgs: list[Message]) -> None:
    frames = [encode(m) for m in msgs]
    res = c8.stream(b"".join(frames))
    assert res.frames == frames  # C decoded and re-encoded byte-identical
    assert FrameDecoder().feed(b"".join(res.frames)) == msgs
    assert res.counters["frames_ok"] == len(msgs)


@given(st.lists(messages(), min_size=1, max_size=12), st.data())
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_c_decoder_survives_corruption_and_agrees_with_python_on_every_counter(c8: CDriver, msgs, data) -> None:
    stream, untouched = corrupted_stream(msgs, data)
    res = c8.stream(stream)
    dec = FrameDecoder()
    py = dec.feed(stream)
    assert res.counters == dec.counters()
    assert res.frames == [encode(m) for m in py]
    assert is_subsequence(untouched, py)


@given(st.binary(max_size=3000))
@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
def test_random_bytes_give_identical_counters_in_c_and_python(c8: CDriver, garbage: bytes) -> None:
    res = c8.stream(garbage)
    dec = FrameDecoder()
    py = dec.feed(garbage)
    assert res.counters == dec.counters()
    assert res.frames == [encode(m) for m in py]


def test_build_with_two_limbs_refuses_a_three_limb_telemetry_like_python_does(c2: CDriver) -> None:
    def tele(psi: tuple[int, ...]) -> Message:
        return Message.new(
            "TELEMETRY", seq=1, time_ms=2, measured=0, target=1, gait=0, direction=0, step=0, flags=0, psi=psi, duty=(1, 2)
        )

    stream = encode(tele((1, 2, 3))) + encode(tele((1, 2)))
    res = c2.stream(stream)
    dec = FrameDecoder(max_limbs=2, max_channels=2)
    assert [encode(m) for m in dec.feed(stream)] == res.frames == [encode(tele((1, 2)))]
    assert res.counters == dec.counters() and res.counters["bad_value"] == 1
