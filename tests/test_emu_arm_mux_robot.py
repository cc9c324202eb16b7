"""A robot whose IMUs sit behind a TCA9548A on the bluepill, on arm-emu: the exact image boots,
reads every IMU through the multiplexer each tick, walks, and names the limb whose IMU is lost.

tests/fixtures/paper-r1-mux.toml is paper-r1 with both MPU-6050s at 0x68 behind the
multiplexer at 0x70 on I2C1, channels 0 and 1: the firmware (core/imubus.c) has to switch
channel before every read, in the background between ticks. The multiplexer model itself
is checked against the datasheet in test_emu_arm_mux.py.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from proleg.errors import ProlegError
from proleg.protocol import FrameDecoder
from proleg.protocol.definition import EventKind, FaultCode

pytest.importorskip("unicorn")

pytestmark = pytest.mark.skipif(shutil.which("arm-none-eabi-gcc") is None, reason="no arm-none-eabi-gcc")

ROBOT = Path(__file__).parent / "fixtures" / "paper-r1-mux.toml"
MUX = 0x70
PWR_MGMT_1 = 0x6B


@pytest.fixture(scope="module")
def robot():
    from proleg.robot import load_robot

    return load_robot(ROBOT)


@pytest.fixture(scope="module")
def elf(robot):
    from proleg.emu.arm import bluepill_elf

    try:
        return bluepill_elf(robot)
    except ProlegError as e:  # pragma: no cover - toolchain broken
        pytest.skip(f"bluepill build unavailable: {e}")


def _faults(board):
    msgs = FrameDecoder().feed(board.read())
    return [m for m in msgs if m.name == "EVENT" and m.kind == EventKind.FAULT]


def test_both_imus_behind_the_multiplexer_start_and_are_read_every_tick(robot, elf):
    from proleg.emu.arm import ArmEmuRobot

    sim = ArmEmuRobot(robot, elf)
    b = sim.board
    assert b.imu_addresses == (0x80, 0x81)  # host-sim's keys: limbs behind a multiplexer
    assert b.imu_wiring == ((0, 0x68, MUX, 0), (0, 0x68, MUX, 1))
    b.run_ticks(300)
    assert _faults(b) == []
    for key in b.imu_addresses:  # each woken up on the PLL clock, through its own channel
        assert b.imu_register(key, PWR_MGMT_1) == 0x01
    writes, transfers = b.mux_writes, b.i2c1.transfers
    b.run_ticks(100)
    # two channel switches a tick and two IMU reads: every tick reads both IMUs
    assert b.mux_writes - writes == 200
    assert b.i2c1.transfers - transfers == 400
    controls = set()
    for _ in range(40):  # looked at across the tick (the reads run at the same point of every tick)
        b.run_us(b.tick_us * 7 // 40)
        controls.add(b.mux_control(0, MUX))
    assert controls == {1 << 0, 1 << 1}
    assert b.i2c_violations == 0 and b.resets == []


def test_a_robot_behind_the_multiplexer_walks_and_a_lost_imu_names_its_limb(robot, elf):
    from proleg.emu.arm import ArmEmuRobot
    from proleg.report import SimSession

    sim = ArmEmuRobot(robot, elf)
    session = SimSession(sim)
    session.advance(0.2)
    report = session.run_gait("+x", 0, 12.0)
    assert report.faults == [] and report.cycles >= 1
    assert all(d > 1.0 for d in report.cycle_displacements_mm), report.cycle_displacements_mm  # R1: ~ +1.8 mm
    b = sim.board
    b.read()
    b.imu_fault(0x81, "no-ack")  # the right limb's IMU, on channel 1
    sim.run_ticks(50)
    faults = _faults(b)
    assert faults and all(f.code == FaultCode.IMU_NO_ACK and f.detail == 1 for f in faults), faults
    assert all(b.pwm(ch) == 0.0 for ch in range(2))


def test_at_the_fastest_tick_the_build_allows_every_tick_still_reads_both_imus(tmp_path):
    """The build's I2C rule counts the channel switches (placement.i2c_tick_us: 84 bit times a
    read, 20 a switch, at most 75 % of the tick). At the fastest tick_hz it accepts, the
    background selects and reads still finish every tick on the bluepill image, where the
    bus time is what the I2C peripheral model takes, START to STOP, polls included."""
    from proleg.emu.arm import ArmEmuRobot, bluepill_elf
    from proleg.firmware.boards import load_board
    from proleg.firmware.placement import I2C_TICK_SHARE, i2c_tick_us, place_imus
    from proleg.robot import load_robot

    board = load_board("bluepill-f103")
    need_us = i2c_tick_us(place_imus(load_robot(ROBOT), board), int(board.i2c.get("hz", 400000)))
    hz = int(I2C_TICK_SHARE * 1e6 / need_us)  # the build's own limit (check_tick_budget)
    path = tmp_path / "paper-r1-mux-fast.toml"
    path.write_text(ROBOT.read_text().replace("tick_hz = 1000", f"tick_hz = {hz}"))
    robot = load_robot(path)
    assert robot.control.tick_hz == hz > 1000
    sim = ArmEmuRobot(robot, bluepill_elf(robot))
    b = sim.board
    b.run_ticks(400)
    assert _faults(b) == []
    owned: list[int] = []  # cycles the I2C1 peripheral owns the bus (START to STOP done)
    i2c = b.i2c1
    start, complete = i2c._begin_start, i2c._complete

    def begin_start(now: int) -> None:
        if i2c.phase == "idle":
            owned.append(-now)
        start(now)

    def done(t: int) -> None:
        stopping = i2c.phase == "stop"
        complete(t)
        if stopping and owned and owned[-1] < 0:
            owned[-1] += t

    i2c._begin_start, i2c._complete = begin_start, done
    writes, transfers = b.mux_writes, i2c.transfers
    b.run_ticks(300)
    # every tick: 2 selects, 2 reads; at this tick rate the last read of a tick may complete
    # after the next tick began, so one read may straddle either end of the 300 ticks
    assert b.mux_writes - writes == 600 and abs(i2c.transfers - transfers - 1200) <= 1
    bus_us = sum(c for c in owned if c > 0) / 72 / 300
    assert need_us < bus_us < b.tick_us, (need_us, bus_us, b.tick_us)  # the rule's estimate is a floor; it fits
    assert _faults(b) == []
