"""The STM32 start-up retry on arm-emu: an MPU-6050 that answers late after power-up.

The firmware (core/imucheck.c) waits the MPU-6050's typical start-up time (20 ms), then
retries WHO_AM_I every tick until its maximum (100 ms) plus 50 ms of margin, i.e. until
170 ms after power-on; then IMU_NO_ACK names the limb (MPU-6000/6050 Product
Specification rev. 3.4, table 6.3). The arm-emu model does not acknowledge before the
time ``imu_startup`` gives it, like avr-emu's (test_emu_avr_firmware.py).
"""

from __future__ import annotations

import shutil

import pytest

from proleg.errors import ProlegError
from proleg.paths import robots_dir
from proleg.protocol import FrameDecoder
from proleg.protocol.definition import EventKind, FaultCode

pytest.importorskip("unicorn")

pytestmark = pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None, reason="no arm-none-eabi-gcc")

IMU0, IMU1 = 0x68, 0x69
PWR_MGMT_1 = 0x6B
DEADLINE_S = 0.020 + 0.100 + 0.050  # typical start-up wait + maximum start-up time + margin


@pytest.fixture(scope="module")
def elf():
    from proleg.emu.arm import bluepill_elf
    from proleg.robot import load_robot

    try:
        return bluepill_elf(load_robot(robots_dir() / "paper-r1.toml"))
    except ProlegError as e:  # pragma: no cover - toolchain broken
        pytest.skip(f"bluepill build unavailable: {e}")


def _late_board(elf, addr: int, us: int):
    from proleg.emu.arm import ArmEmuBoard

    b = ArmEmuBoard(elf, 1)
    b.imu_startup(addr, us)
    b.reset()
    return b


def _faults(b, dec):
    return [(m.code, m.detail) for m in dec.feed(b.read()) if m.name == "EVENT" and m.kind == EventKind.FAULT]


def test_an_imu_that_answers_60_ms_after_power_up_is_retried_and_starts(elf):
    b = _late_board(elf, IMU1, 60_000)
    dec = FrameDecoder()
    b.run_us(55_000)
    assert b.imu_register(IMU0, PWR_MGMT_1) == 0x01  # the prompt one is up
    assert b.imu_register(IMU1, PWR_MGMT_1) == 0x40  # the late one not yet: asleep, as at power-up
    b.run_us(245_000)
    assert _faults(b, dec) == []
    assert b.imu_register(IMU1, PWR_MGMT_1) == 0x01  # woken on the PLL clock: its start-up ran
    reads = b.i2c1.transfers
    b.run_ticks(20)
    assert b.i2c1.transfers - reads == 40  # and both are read every tick
    assert _faults(b, dec) == []


def test_an_imu_later_than_the_deadline_faults_no_ack_on_its_limb_at_the_deadline(elf):
    b = _late_board(elf, IMU0, 250_000)
    dec = FrameDecoder()
    b.run_us(round((DEADLINE_S - 0.005) * 1e6))
    assert _faults(b, dec) == []  # still retrying
    b.run_us(10_000)
    assert _faults(b, dec) == [(FaultCode.IMU_NO_ACK, 0)]
    assert b.imu_register(IMU1, PWR_MGMT_1) == 0x01  # the other limb started
    assert all(b.pwm(ch) == 0.0 for ch in range(2))
