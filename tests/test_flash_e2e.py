"""``proleg flash`` end to end: the real flash tool against an emulated board on a
pseudo-terminal, then the flashed firmware answers INFO over the same port.

- Nano: avrdude (-c arduino, 115200 Bd) → optiboot (built from Debian's sources) on
  avr-emu at real time, reset when the port opens (the DTR auto-reset); ~5 s.
- Bluepill: stm32flash → the STM32 ROM bootloader protocol (AN3155) emulated in Python,
  then GO boots arm-emu from the flash it wrote.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
R1 = str(ROOT / "robots" / "paper-r1.toml")
OPTIBOOT_DIR = Path("/usr/share/arduino/hardware/arduino/avr/bootloaders/optiboot")


class PtyServer:
    """A ``python -m MODULE`` pty server in a subprocess: its first line names the pty."""

    def __init__(self, module: str, *args: str):
        self.proc = subprocess.Popen(
            [sys.executable, "-m", module, *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=os.environ.copy(),
        )
        line = self.proc.stdout.readline()  # type: ignore[union-attr]
        if not line.startswith("pty: "):
            self.proc.kill()
            raise AssertionError(f"{module} did not start: {line!r} {self.proc.stderr.read()}")  # type: ignore[union-attr]
        self.path = line[5:].strip()

    def stop(self) -> str:
        self.proc.terminate()
        try:
            _, err = self.proc.communicate(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        return err


def proleg(*args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "proleg", *args], capture_output=True, text=True, timeout=timeout)


def built_ids(out: Path) -> tuple[int, int]:
    """(build id, gait hash) that the build put into the firmware."""
    cfg = (out / "gen" / "robot_config.h").read_text()
    build_id = int(re.search(r"#define\s+CFG_BUILD_ID\s+(0x[0-9A-Fa-f]+)", cfg).group(1), 16)  # type: ignore[union-attr]
    gait_hash = int(json.loads((out / "proleg-build.json").read_text())["gait_table_hash"], 16)
    return build_id, gait_hash


def info_over(port: str):
    from proleg.link.client import RobotClient
    from proleg.link.factory import open_link

    with RobotClient(open_link(port)) as client:
        return client.connect()


@pytest.mark.skipif(
    shutil.which("avrdude") is None
    or shutil.which("avr-gcc") is None
    or not Path("/usr/include/simavr/sim_avr.h").exists()
    or not (OPTIBOOT_DIR / "optiboot.c").exists(),
    reason="needs avrdude, avr-gcc, simavr and arduino-core-avr (make toolchains installs them)",
)
def test_proleg_flash_writes_the_emulated_nano_through_optiboot_and_the_new_firmware_answers(tmp_path):
    out = tmp_path / "r1-nano"
    server = PtyServer("proleg.emu.avr.pty_nano")  # a blank application section
    try:
        flashed = proleg("flash", R1, "--board", "arduino-nano", "--port", server.path, "-o", str(out))  # builds, then avrdude
        assert flashed.returncode == 0, flashed.stdout + flashed.stderr
        assert f"flashed {out / 'firmware.hex'} with avrdude" in flashed.stdout
        assert re.search(r"\d+ bytes of flash verified", flashed.stderr), flashed.stderr
        info = info_over(server.path)  # opening the port resets the Nano again: optiboot, then the firmware
    finally:
        err = server.stop()
    build_id, gait_hash = built_ids(out)
    assert (info.robot_name, info.board) == ("paper-r1", "arduino-nano")
    assert (info.build_id, info.gait_hash) == (build_id, gait_hash)
    assert re.search(r": 2 opens,", err), err  # avrdude's and the client's: each one an auto-reset
