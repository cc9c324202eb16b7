"""docs/adding-a-message.md, followed step by step: a message = its definition + its handler.

A toy command ECHO (token, value) is added to a copy of the protocol definition and
rendered; the rendered command list (PROTO_COMMANDS in proto_gen.h) names its handler
cmd_echo. The host-sim firmware then does not build until cmd_echo is written in
core/cmd.c, and with it the firmware answers ECHO through the dispatch, on the wire.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from binascii import crc_hqx
from pathlib import Path

import pytest
from cobs import cobs

from proleg.firmware.boards import load_board
from proleg.firmware.build import firmware_gaits, render_project
from proleg.protocol import FrameDecoder
from proleg.protocol.definition import MESSAGES, ErrorCode, Field, MessageSpec
from proleg.protocol.render import handler_name, render_c
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
pytestmark = pytest.mark.skipif(shutil.which("cc") is None or shutil.which("make") is None, reason="no cc/make")

# Step 1: the definition (in definition.py this is one more MessageSpec in MESSAGES).
ECHO = MessageSpec(
    0x3E,
    "ECHO",
    "h2r",
    (Field("token", "u8", "echoed in the reply"), Field("value", "u8", "ACKed when 42, else NACKed with it")),
    "Toy command of the walkthrough.",
)
TOY_MESSAGES = MESSAGES + (ECHO,)

# Step 2: the handler, in core/cmd.c.
HANDLER = """
static void cmd_echo(void)
{
    if (msg.u.echo.value == 42u) {
        ack();
    } else {
        nack(PROTO_ERR_OUT_OF_RANGE, msg.u.echo.value);
    }
}
"""


def frame(msg_id: int, payload: bytes) -> bytes:
    raw = bytes([msg_id]) + payload
    crc = crc_hqx(raw, 0xFFFF)
    return cobs.encode(raw + bytes((crc & 0xFF, crc >> 8))) + b"\0"


def write_project(out: Path, with_handler: bool) -> subprocess.CompletedProcess:
    robot, board = load_robot(ROOT / "robots" / "paper-r1.toml"), load_board("host-sim")
    files = render_project(robot, board, firmware_gaits(robot))
    files.update({f"gen/{k}": v for k, v in render_c(len(robot.limbs), len(robot.actuators), TOY_MESSAGES).items()})
    if with_handler:
        files["core/cmd.c"] += HANDLER
    for rel, text in files.items():
        (out / rel).parent.mkdir(parents=True, exist_ok=True)
        (out / rel).write_text(text)
    return subprocess.run(["make", "-C", str(out), "-j2", "all"], capture_output=True, text=True)


def test_the_rendered_command_list_names_one_handler_per_command():
    h = render_c(2, 2, TOY_MESSAGES)["proto_gen.h"]
    listed = h[h.index("#define PROTO_COMMANDS(X)"):].split("\n\n")[0]
    for m in TOY_MESSAGES:
        assert (f"X(PROTO_ID_{m.name}, {handler_name(m)})" in listed) == (m.direction == "h2r"), m.name
    assert "X(PROTO_ID_ECHO, cmd_echo)" in listed
    assert "ECHO" not in render_c(2, 2)["proto_gen.h"]  # the real definition is untouched


def test_a_command_without_its_handler_does_not_build(tmp_path):
    made = write_project(tmp_path, with_handler=False)
    assert made.returncode != 0
    assert "cmd_echo" in made.stdout + made.stderr


def test_the_dispatch_picks_up_the_new_handler(tmp_path):
    made = write_project(tmp_path, with_handler=True)
    assert made.returncode == 0, made.stdout + made.stderr
    lib = ctypes.CDLL(str(tmp_path / "libfirmware.so"))
    lib.sim_uart_read.restype = ctypes.c_uint32
    lib.sim_reset(1)
    lib.sim_run_ticks(5)
    buf = ctypes.create_string_buffer(65536)
    lib.sim_uart_read(buf, 65536)  # boot chatter

    wire = frame(ECHO.id, bytes([7, 42])) + frame(ECHO.id, bytes([8, 5]))
    lib.sim_uart_write(wire, len(wire))
    lib.sim_run_ticks(20)
    n = lib.sim_uart_read(buf, 65536)
    replies = [m for m in FrameDecoder().feed(buf.raw[:n]) if m.name in ("ACK", "NACK")]
    assert [(m.name, m.token, m.cmd) for m in replies] == [("ACK", 7, ECHO.id), ("NACK", 8, ECHO.id)]
    assert (replies[1].error, replies[1].detail) == (ErrorCode.OUT_OF_RANGE, 5)
