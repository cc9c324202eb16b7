"""core/imubus.c on the host with a scripted HAL (tests/c/test_imubus.c): the multiplexer
select and the second bus are background transactions (issue 14), never a wait."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "firmware_templates" / "core"
CDIR = Path(__file__).resolve().parent / "c"
CC = shutil.which("cc") or shutil.which("gcc")

CONFIG = """\
#define CFG_N_LIMBS 3
#define CFG_LIMB_IMU_BUS { 0, 1, 1 }
#define CFG_LIMB_IMU_MUX { 0, 0x70, 0x70 }
#define CFG_LIMB_IMU_CHANNEL { 0, 2, 5 }
#define CFG_I2C_BUSES 2u
#define CFG_IMU_MUX_USED 1
"""


@pytest.mark.skipif(CC is None, reason="no host C compiler")
def test_imubus_select_and_second_bus_run_in_the_background(tmp_path):
    (tmp_path / "robot_config.h").write_text(CONFIG)
    exe = tmp_path / "test_imubus"
    cmd = [CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-g", f"-I{tmp_path}", f"-I{CORE}",
           f"-I{CDIR}", str(CDIR / "test_imubus.c"), str(CORE / "imubus.c"), "-o", str(exe)]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    run = subprocess.run([str(exe)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0 and "FAIL" not in run.stdout, run.stdout
