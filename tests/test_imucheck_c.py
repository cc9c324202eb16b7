"""core/imucheck.c on the host against a scripted bus (tests/c/test_imucheck.c): each IMU
is read once a tick while the bus has the time, no result is ever dropped or overwritten,
and an IMU that dies faults whatever the phase of its reads against the tick (issue 11:
a round still on the bus at the tick used to restart the in-flight limb, and in phase
with the tick that limb's errors were never counted)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path
from types import SimpleNamespace

import pytest

from proleg.firmware.render import render_config
from proleg.protocol.render import render_c
from proleg.robot import robot_from_dict

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
SIM = ROOT / "firmware_templates" / "hal" / "sim"
CDIR = Path(__file__).resolve().parent / "c"
CC = shutil.which("cc") or shutil.which("gcc")

BOARD = {
    "name": "host-sim",
    "family": "sim",
    "pwm_channels": ["SIM0", "SIM1"],
    "i2c": {"hz": 400000, "imu_addresses": [0x68, 0x69]},
    "uart_baud": 115200,
    "clock_hz": 0,
}

ROBOT = {
    "robot": {"name": "imucheck-test"},
    "limb": [
        {"name": "left", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a0"},
        {"name": "right", "psi_star_deg": [20.0], "hysteresis_deg": 2.0, "actuator": "a1"},
    ],
    "actuator": [{"name": "a0", "channel": 0}, {"name": "a1", "channel": 1}],
    "transitions": {"matrix": [[0, -1, 1, 0], [1, 0, 0, -1], [-1, 0, 0, 1], [0, 0, 0, 0]]},
    "safety": {"max_on_ms": 50, "min_cooldown_ms": 20, "max_duty": 0.8, "state_timeout_ms": 200},
    "control": {"tick_hz": 1000, "drive_duty": 0.6, "debounce_ticks": 3, "hold_ms": 10, "telemetry_hz": 50},
}


@pytest.mark.skipif(CC is None, reason="no host C compiler")
def test_imucheck_reads_every_imu_each_tick_and_drops_no_result(tmp_path):
    robot = robot_from_dict(ROBOT, Path("tests/imucheck-test.toml"))
    gaits = {"+x": [SimpleNamespace(states=(0, 2, 3, 1, 0))], "-x": []}
    for name, text in {**render_config(robot, gaits, BOARD), **render_c(2, 2)}.items():
        (tmp_path / name).write_text(text)
    exe = tmp_path / "test_imucheck"
    sources = [CDIR / "test_imucheck.c", CORE / "imucheck.c", CORE / "imubus.c", CORE / "mpu6050.c", SIM / "sim_mpu6050.c"]
    cmd = [CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-g", "-O1", f"-I{tmp_path}", f"-I{CORE}",
           f"-I{SIM}", f"-I{CDIR}", *map(str, sources), "-o", str(exe), "-lm"]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=120)
    print(run.stdout)
    assert run.returncode == 0 and "FAIL" not in run.stdout, run.stdout
    assert run.stdout.count("ok  ") == 4, run.stdout
