"""docs/adding-a-board.md, followed step by step: a board = a board file + a HAL folder.

A toy family ("toy") is made by copying firmware_templates/hal/template, as the page says;
its functions are filled in for the host (POSIX clock, no I2C devices, UART bytes to
stdout); a toy board file names it, with the host cc and a plain executable as its build
steps. ``proleg build`` renders and builds it with no other file touched, and the
executable boots and speaks the protocol. The template itself builds as it is, and
stubs exactly the functions of core/hal.h.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from proleg.errors import BuildError
from proleg.firmware.boards import load_board
from proleg.firmware.build import build
from proleg.protocol import FrameDecoder
from proleg.protocol.definition import EventKind, FaultCode, ResetCause
from proleg.robot import load_robot

ROOT = Path(__file__).resolve().parents[1]
CC = shutil.which("cc")
pytestmark = pytest.mark.skipif(CC is None or shutil.which("make") is None, reason="no host cc/make")

FUNCTION = re.compile(r"^[a-z][\w \*]*?\b(hal_\w+)\(([^)]*)\)\n\{\n(.*?)^\}\n", re.M | re.S)

TOY_BOARD = """\
# A toy board: the firmware as a host program; UART bytes go to stdout, no IMU answers.
[board]
name = "toy-host"
description = "walkthrough toy: docs/adding-a-board.md"
family = "toy"
mcu = "host"
clock_hz = 0
flash_bytes = 0
ram_bytes = 0

[toolchain]
cc = "cc"
cflags = ["-O1", "-D_POSIX_C_SOURCE=200809L"]
ldflags = []
packages = ["gcc"]

[build]
main_loop = true
link = "toy"
artifact = "toy"
size = ["size", "-B", "{link}"]

[i2c]
hz = 400000
imu_addresses = [0x68, 0x69]

[pwm]
pins = ["P0", "P1"]
frequency_hz = 1000

[uart]
port = "stdout"
baud = 115200
"""

# What a porter writes into each stub (step 1 of the page), for the host.
TOY_BODIES = {
    "hal_init": "    clock_gettime(CLOCK_MONOTONIC, &t0);",
    "hal_micros": (
        "    struct timespec t;\n"
        "    uint64_t us;\n"
        "    clock_gettime(CLOCK_MONOTONIC, &t);\n"
        "    us = (uint64_t)(t.tv_sec - t0.tv_sec) * 1000000u + (uint64_t)((t.tv_nsec - t0.tv_nsec) / 1000);\n"
        "    if (us > 300000u) {\n"
        "        exit(0); /* the toy board powers off after 0.3 s */\n"
        "    }\n"
        "    return (uint32_t)us;"
    ),
    "hal_i2c_begin": (
        "    (void)addr7;\n    (void)tx;\n    (void)ntx;\n    (void)rx;\n    (void)nrx;\n"
        "    return 0;"
    ),
    "hal_i2c_begin_bus": (
        "    (void)bus;\n    (void)addr7;\n    (void)tx;\n    (void)ntx;\n    (void)rx;\n    (void)nrx;\n"
        "    return -1; /* the toy has one bus, and nothing on it */"
    ),
    "hal_i2c_poll": "    return -1; /* nothing on the toy's bus */",
    "hal_pwm_set": (
        "    if (channel >= CFG_PWM_CHANNELS) {\n        return;\n    }\n"
        "    duty[pwm_map[channel]] = duty_permyriad;"
    ),
    "hal_uart_tx_start": (
        "    int b;\n"
        "    while ((b = uart_isr_tx()) >= 0) { /* no interrupt: the bytes leave at once */\n"
        "        putchar(b);\n"
        "    }\n"
        "    fflush(stdout);"
    ),
    "hal_reset_cause": "    return HAL_RESET_POWER_ON; /* the toy only ever powers on */",
    "hal_watchdog_feed": "    /* no watchdog on the toy */",
    "hal_tick_mark": "    (void)busy;",
    "hal_nv_read": (
        "    uint8_t i;\n"
        "    for (i = 0; i < n; i++) {\n        dst[i] = 0xFFu; /* nothing on the toy survives: always erased */\n    }"
    ),
    "hal_nv_write": "    (void)src;\n    (void)n;\n    return -1;",
    "hal_nv_poll": "    return 0;",
}
TOY_GLOBALS = (
    "#include <stdio.h>\n#include <stdlib.h>\n#include <time.h>\n\n"
    "static struct timespec t0;\nstatic uint16_t duty[CFG_PWM_CHANNELS];\n"
)


@pytest.fixture
def home(tmp_path, monkeypatch) -> Path:
    """A private PROLEG_HOME, so the toy family never lands in the repository."""
    h = tmp_path / "home"
    for d in ("boards", "firmware_templates", "robots"):
        shutil.copytree(ROOT / d, h / d)
    monkeypatch.setenv("PROLEG_HOME", str(h))
    return h


def hal_functions(text: str) -> dict[str, str]:
    return {m.group(1): m.group(3) for m in FUNCTION.finditer(text)}


def test_the_template_stubs_exactly_the_functions_of_hal_h():
    hal_h = (ROOT / "firmware_templates" / "core" / "hal.h").read_text()
    declared = set(re.findall(r"^\w[\w \*]*?\b(hal_\w+)\(", hal_h, re.M))
    template = (ROOT / "firmware_templates" / "hal" / "template" / "hal_template.c").read_text()
    assert set(hal_functions(template)) == declared
    assert declared >= {"hal_init", "hal_micros", "hal_i2c_begin", "hal_i2c_poll", "hal_pwm_set", "hal_uart_tx_start"}


def copy_template(home: Path, family: str) -> Path:
    """Step 1: cp -r hal/template hal/<family>; mv hal_template.c hal_<family>.c."""
    hal = home / "firmware_templates" / "hal"
    shutil.copytree(hal / "template", hal / family)
    src = hal / family / "hal_template.c"
    dst = hal / family / f"hal_{family}.c"
    src.rename(dst)
    return dst


def fill_in(path: Path) -> None:
    """Step 1, continued: every stub gets its toy body (and every stub must get one)."""
    text = path.read_text()
    stubs = hal_functions(text)
    assert set(stubs) == set(TOY_BODIES)
    for name, body in stubs.items():
        m = re.search(rf"\b{name}\([^)]*\)\n\{{\n", text)
        assert m is not None
        start = m.end()
        text = text[:start] + text[start:].replace(body, TOY_BODIES[name] + "\n", 1)
    text = text.replace('#include "uart.h"\n', '#include "uart.h"\n\n' + TOY_GLOBALS, 1)
    path.write_text(text)


def test_the_template_as_copied_builds_into_an_image(home, tmp_path):
    copy_template(home, "toy")
    board_file = tmp_path / "toy-host.toml"
    board_file.write_text(TOY_BOARD)
    result = build(load_robot(home / "robots" / "paper-r1.toml"), load_board(board_file), tmp_path / "out")
    assert result.artifact.is_file() and result.flash_used > 0
    assert (tmp_path / "out" / "core" / "main.c").is_file()  # main_loop = true: the core's main()


def test_a_toy_board_from_the_template_boots_and_speaks_the_protocol(home, tmp_path):
    fill_in(copy_template(home, "toy"))
    board_file = tmp_path / "toy-host.toml"  # step 2
    board_file.write_text(TOY_BOARD)
    robot = load_robot(home / "robots" / "paper-r1.toml")
    result = build(robot, load_board(board_file), tmp_path / "out")  # step 3

    run = subprocess.run([str(result.artifact)], capture_output=True, timeout=30)
    assert run.returncode == 0, run.stderr
    msgs = FrameDecoder().feed(run.stdout)
    info = next(m for m in msgs if m.name == "INFO")
    assert (info.robot_name, info.board) == (robot.name, "toy-host")
    events = [(m.kind, m.code, m.detail) for m in msgs if m.name == "EVENT"]
    assert events[0] == (EventKind.BOOT, ResetCause.POWER_ON, 0)
    assert (EventKind.FAULT, FaultCode.IMU_NO_ACK, 0) in events  # no IMU on the toy's bus
    assert any(m.name == "TELEMETRY" for m in msgs)  # the core's tick loop ran


def test_a_pin_the_new_family_does_not_list_is_one_clear_error(home, tmp_path):
    copy_template(home, "toy")
    spec = home / "firmware_templates" / "hal" / "toy" / "family.toml"
    spec.write_text(spec.read_text().replace('pins = "any"', '[pwm.pins]\nGP0 = [0, 0]\nGP1 = [0, 1]'))
    board_file = tmp_path / "toy-host.toml"
    board_file.write_text(TOY_BOARD)
    with pytest.raises(BuildError, match=r"\[pwm\] pin 'P0' \(channel = 0\) is not a PWM output .*GP0, GP1"):
        build(load_robot(home / "robots" / "paper-r1.toml"), load_board(board_file), tmp_path / "out")
