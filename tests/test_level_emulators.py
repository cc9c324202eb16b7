"""Level calibration on the emulated MCUs, one short test each: the exact Nano and bluepill
images calibrate, keep the record in their non-volatile memory (simavr's EEPROM; the
arm-emu FPEC flash model) through a power-on reset, and GET_LEVEL returns it."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proleg.link import RobotClient
from proleg.link.level import calibrate_level, get_level
from proleg.link.sim_link import SimLink
from proleg.paths import robots_dir
from proleg.protocol.definition import LevelStatus
from proleg.robot import load_robot

MOUNT = ["imu_offset_deg=left:6", "imu_offset_deg=right:-3"]


@pytest.fixture(scope="module")
def r1():
    return load_robot(robots_dir() / "paper-r1.toml")


def calibrate_reset_read(sim) -> tuple[tuple[int, ...], tuple[int, ...]]:
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
    client.connect()
    assert get_level(client).status == LevelStatus.NONE  # erased memory: no calibration
    outcome = calibrate_level(client)
    assert outcome.ok, outcome
    client.close()
    sim.board.reset(3)  # power cycle: RAM gone, the non-volatile block kept
    client = RobotClient(SimLink(sim, step_s=sim.plant_dt_s))
    client.connect()
    after = get_level(client)
    client.close()
    assert after.status == LevelStatus.STORED
    return outcome.reading.offsets_cdeg, after.offsets_cdeg


@pytest.mark.skipif(not Path("/usr/include/simavr/sim_avr.h").exists() or shutil.which("avr-gcc") is None,
                    reason="needs simavr/libsimavr-dev and avr-gcc (make toolchains installs them)")
def test_the_nano_keeps_its_calibration_in_eeprom_across_a_reset(r1):
    from proleg.emu.avr import AvrEmuRobot

    stored, after = calibrate_reset_read(AvrEmuRobot(r1, conditions=MOUNT))
    assert after == stored and abs(stored[0] - 600) < 20 and abs(stored[1] + 300) < 20


@pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None, reason="needs arm-none-eabi-gcc")
def test_the_bluepill_keeps_its_calibration_in_its_last_flash_page_across_a_reset(r1):
    from proleg.emu.arm import ArmEmuRobot

    sim = ArmEmuRobot(r1, conditions=MOUNT)
    stored, after = calibrate_reset_read(sim)
    assert after == stored and abs(stored[0] - 600) < 20 and abs(stored[1] + 300) < 20
    fpec = sim.board.fpec
    assert fpec.page_erases == 1 and fpec.errors == 0  # one erase of the last page, no programming errors
