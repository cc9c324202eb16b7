"""The bluepill's background I2C on arm-emu (issue 11 ARM side, issue 14 second bus).

The tick never waits on a bus: its work reads the I2C status a handful of times at most
(the blocking HAL polled SR1 hundreds of times per tick); IMUs on I2C2 (PB10/PB11) are
set up and read like those on I2C1, with no START/STOP misuse on either peripheral.
"""

from __future__ import annotations

import shutil

import pytest

from proleg.errors import ProlegError
from proleg.paths import robots_dir
from proleg.protocol import FrameDecoder
from proleg.protocol.definition import EventKind

pytest.importorskip("unicorn")

pytestmark = pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None, reason="no arm-none-eabi-gcc")

PWR_MGMT_1 = 0x6B
SR1 = {0x40005414, 0x40005814}
MARK = 0x40006C04


def _elf(name):
    from proleg.emu.arm import bluepill_elf
    from proleg.robot import load_robot

    robot = load_robot(robots_dir() / f"{name}.toml")
    try:
        return robot, bluepill_elf(robot)
    except ProlegError as e:  # pragma: no cover - toolchain broken
        pytest.skip(f"bluepill build unavailable: {e}")


def test_the_tick_reads_the_i2c_status_a_few_times_and_never_polls_a_transfer():
    from proleg.emu.arm import ArmEmuBoard

    _, elf = _elf("paper-r1")
    b = ArmEmuBoard(elf, 1)
    b.run_ticks(60)  # past the IMUs' start-up
    b.trace = []
    b.run_ticks(30)
    in_tick, per_tick = False, []
    for _, kind, addr, value in b.trace:
        if kind == "W" and addr == MARK:
            in_tick = bool(value)
            if in_tick:
                per_tick.append(0)
        elif in_tick and kind == "R" and addr in SR1:
            per_tick[-1] += 1
    assert len(per_tick) >= 29
    assert max(per_tick) <= 8, per_tick  # one hal_i2c_poll's worth: the transfers run between ticks
    assert b.i2c1.transfers > 30 and b.i2c_violations == 0


def test_imus_on_the_second_bus_start_and_are_read_in_the_background():
    from proleg.emu.arm import ArmEmuRobot

    robot, elf = _elf("inchworm-3")
    sim = ArmEmuRobot(robot, elf)
    b = sim.board
    assert len(robot.limbs) == 3 and b.imu_addresses == (0x68, 0x69, 0x82)  # the head (limb 2) on I2C2
    assert b.imu_wiring[2] == (1, 0x68, 0, 0)  # I2C2 at 0x68, directly
    b.run_ticks(200)
    msgs = FrameDecoder().feed(b.read())
    assert [m for m in msgs if m.name == "EVENT" and m.kind == EventKind.FAULT] == []
    head = sim.imu_addresses[2]
    assert b.imu_register(head, PWR_MGMT_1) == 0x01  # woken up on the PLL clock through I2C2
    assert b.i2c2.violations == 0 and b.i2c1.violations == 0
    before = b.i2c2.bus.recoveries
    b.imu_fault(head, "no-ack")
    b.run_ticks(20)
    faults = [m for m in FrameDecoder().feed(b.read()) if m.name == "EVENT" and m.kind == EventKind.FAULT]
    assert [f.detail for f in faults] == [2]  # the head, and only it
    assert b.i2c2.bus.recoveries == before and b.resets == []
