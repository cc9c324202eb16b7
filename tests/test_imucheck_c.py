"""core/imucheck.c on the host against a scripted bus (tests/c/test_imucheck.c): each IMU
is read once a tick while the bus has the time, no result is ever dropped or overwritten,
and an IMU that dies faults whatever the phase of its reads against the tick (issue 11:
a round still on the bus at the tick used to restart the in-flight limb, and in phase
with the tick that limb's errors were never counted)."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from proleg.firmware.render import render_config
from proleg.protocol.render import render_c
from core_configs import r1_fast

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
SIM = ROOT / "firmware_templates" / "hal" / "sim"
CDIR = Path(__file__).resolve().parent / "c"
CC = shutil.which("cc") or shutil.which("gcc")


@pytest.mark.skipif(CC is None, reason="no host C compiler")
def test_imucheck_reads_every_imu_each_tick_and_drops_no_result(tmp_path):
    robot, gaits, board = r1_fast()  # the C unit tests' two-limb robot on host-sim
    for name, text in {**render_config(robot, gaits, board), **render_c(2, 2)}.items():
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
