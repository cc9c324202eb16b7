"""Write the checked-in seed corpus of the fuzz harnesses (tests/fuzz/corpus/).

    python tests/fuzz/make_seeds.py

Seeds are programs for fuzz_app (ops documented in fuzz_app.c) built from real protocol
frames (proleg.protocol.codec), among them the three bypasses of issue 12, and the bare
frames for fuzz_proto. Deterministic: the same files every run.
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "host" / "src"))

from proleg.protocol.codec import Message, encode  # noqa: E402

OUT = ROOT / "tests" / "fuzz" / "corpus"
_token = 0


def frame(name: str, **fields) -> bytes:
    global _token
    _token = _token % 255 + 1
    return encode(Message.new(name, token=_token, **fields))


def raw(b: bytes) -> bytes:
    """App op: write these bytes to the UART as they are."""
    assert 1 <= len(b) <= 63
    return bytes([len(b) - 1]) + b


def restart(cause: int) -> bytes:
    """App op: the board resets without losing power (cause 2 external .. 5 software)."""
    assert 2 <= cause <= 5
    return bytes([0x3F, cause - 2])


def ticks(n: int) -> bytes:
    out = b""
    while n >= 64 * 64:
        out += b"\xbf"
        n -= 64 * 64
    while n >= 64:
        k = min(n // 64, 64)
        out += bytes([0x80 + k - 1])
        n -= 64 * k
    while n > 0:
        k = min(n, 64)
        out += bytes([0x40 + k - 1])
        n -= k
    return out


def psi(limb: int, deg: float) -> bytes:
    return bytes([0xC0 | limb, int(round(deg * 2)) + 128])


def imu(limb: int, mode: int) -> bytes:
    return bytes([0xC2 | limb, mode])


def cmd(name: str, **fields) -> bytes:
    return raw(frame(name, **fields))


START = dict(gait=0, direction=0)
USER = dict(gait=0xFF, direction=0)

#: The board up and its IMUs read (an MPU-6050 starts in 20 ms, then the debounce): the
#: firmware refuses START before (NACK NOT_ALLOWED, detail 2), as "start_before_readings" shows.
BOOT = ticks(40)

APP = {
    "start_before_readings": cmd("START", **START) + ticks(600),
    "start_and_wait": BOOT + cmd("START", **START) + ticks(600),
    "walk_r1": BOOT + cmd("START", **START) + ticks(30) + psi(0, 25) + ticks(30) + psi(1, 25) + ticks(30)
    + psi(0, 0) + ticks(30) + psi(1, 0) + ticks(60),
    "bypass1_stop_start_one_tick": BOOT + cmd("LOAD_GAIT", states=(2, 3)) + cmd("START", **USER) + ticks(5)
    + (ticks(45) + cmd("STOP") + cmd("START", **USER) + ticks(1)) * 8,
    "bypass2_one_tick_gap": BOOT + cmd("LOAD_GAIT", states=(2, 3)) + cmd("START", **USER)
    + (ticks(48) + cmd("STOP") + ticks(1) + cmd("START", **USER)) * 8,
    "bypass3_start_resent": BOOT + cmd("START", **START) + (ticks(40) + cmd("START", **START)) * 10,
    "estop_clear_start": BOOT + cmd("START", **START) + ticks(20) + cmd("ESTOP") + cmd("CLEAR", what=7)
    + cmd("START", **START) + ticks(100),
    "set_params": BOOT + cmd("SET_PARAM", param=1, index=0, value=8000) + cmd("SET_PARAM", param=10, index=0, value=3000)
    + cmd("SET_PARAM", param=7, index=0, value=10) + cmd("SET_PARAM", param=8, index=0, value=40)
    + cmd("SET_PARAM", param=4, index=0, value=100)
    + cmd("START", **START) + ticks(300),
    "imu_faults": BOOT + cmd("START", **START) + ticks(10) + imu(0, 2) + ticks(300) + imu(0, 0)
    + cmd("CLEAR", what=7) + cmd("START", **START) + ticks(50) + imu(1, 1) + ticks(10),
    "noise_and_partial_frames": raw(b"\x00\x01\x02\x03garbage\x00") + raw(frame("STOP")[:-3]) + ticks(3)
    + cmd("PING") + ticks(3),
    "reset_and_start_at_once": BOOT + cmd("LOAD_GAIT", states=(2, 3)) + cmd("START", **USER)
    + (ticks(2000) + restart(2) + BOOT + cmd("LOAD_GAIT", states=(2, 3)) + cmd("START", **USER)) * 4
    + restart(3) + BOOT + cmd("START", **START) + ticks(3000),
    "hold_forever": BOOT + cmd("LOAD_GAIT", states=(2, 3)) + cmd("START", **USER) + ticks(20) + psi(0, 25)
    + ticks(4000),
}

PROTO = {
    "start": frame("START", **START),
    "stop": frame("STOP"),
    "estop": frame("ESTOP"),
    "clear": frame("CLEAR", what=7),
    "load_gait": frame("LOAD_GAIT", states=(0, 2, 3, 1)),
    "set_param": frame("SET_PARAM", param=1, index=0, value=-123456),
    "telemetry_rate": frame("SET_TELEMETRY_RATE", hz=50),
    "stream": frame("PING") + b"\x00\x00junk" + frame("GET_INFO") + frame("GET_STATS")[:-2] + frame("STOP"),
}


def main() -> None:
    for sub, seeds in (("app", APP), ("proto", PROTO)):
        d = OUT / sub
        d.mkdir(parents=True, exist_ok=True)
        for old in d.iterdir():
            old.unlink()
        for name, data in seeds.items():
            (d / name).write_bytes(data)
    print(f"{len(APP)} app seeds, {len(PROTO)} proto seeds in {OUT}")


if __name__ == "__main__":
    main()
