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


@pytest.mark.skipif(shutil.which("stm32flash") is None or shutil.which("arm-none-eabi-gcc") is None,
                    reason="needs stm32flash and arm-none-eabi-gcc (make toolchains installs them)")
def test_proleg_flash_writes_the_emulated_bluepill_through_its_rom_bootloader_and_the_new_firmware_answers(tmp_path):
    pytest.importorskip("unicorn")
    out = tmp_path / "r1-bluepill"
    server = PtyServer("proleg.emu.arm.rom_bootloader")  # BOOT0 = 1, erased flash
    try:
        flashed = proleg("flash", R1, "--board", "bluepill-f103", "--tool", "stm32flash", "--port", server.path,
                         "-o", str(out))
        assert flashed.returncode == 0, flashed.stdout + flashed.stderr
        assert f"flashed {out / 'firmware.bin'} with stm32flash" in flashed.stdout
        assert "Device ID    : 0x0410" in flashed.stdout
        assert "Wrote and verified address" in flashed.stdout
        assert "Starting execution at address 0x08000000... done." in flashed.stdout
        info = info_over(server.path)  # GO booted arm-emu from the flash stm32flash wrote
    finally:
        err = server.stop()
    build_id, gait_hash = built_ids(out)
    assert (info.robot_name, info.board) == ("paper-r1", "bluepill-f103")
    assert (info.build_id, info.gait_hash) == (build_id, gait_hash)
    assert "GO 0x08000000: arm-emu booted the flash" in err, err


@pytest.mark.skipif(shutil.which("stm32flash") is None, reason="needs stm32flash (make toolchains installs it)")
def test_stm32flash_uses_extended_erase_when_the_bootloader_offers_it(tmp_path):
    image = bytes(range(256)) * 20 + b"\x01\x02\x03"  # 5123 bytes: 6 pages, a tail that is not word-sized
    binfile = tmp_path / "image.bin"
    binfile.write_bytes(image)
    readback = tmp_path / "readback.bin"
    old = tmp_path / "old.bin"
    old.write_bytes(b"\x00" * 8192)  # programmed flash: writing without an erase would fail
    server = PtyServer("proleg.emu.arm.rom_bootloader", "--extended-erase", "--image", str(old))
    try:
        wrote = subprocess.run(["stm32flash", "-m", "8n1", "-S", f"0x08000000:{len(image)}", "-w", str(binfile), "-v", server.path],
                               capture_output=True, text=True, timeout=60)
        assert wrote.returncode == 0, wrote.stdout + wrote.stderr
        assert "Wrote and verified address 0x08001403" in wrote.stdout
        read = subprocess.run(["stm32flash", "-m", "8n1", "-S", f"0x08000000:{8192}", "-r", str(readback), server.path],
                              capture_output=True, text=True, timeout=60)
        assert read.returncode == 0, read.stdout + read.stderr
    finally:
        err = server.stop()
    data = readback.read_bytes()
    assert data[: len(image)] == image
    assert data[len(image) : 6 * 1024] == b"\xff" * (6 * 1024 - len(image))  # erased with the page
    assert data[6 * 1024 :] == b"\x00" * (8192 - 6 * 1024)  # untouched: only the 6 pages written were erased
    assert "EXTENDED ERASE 6 pages: 1" in err, err
