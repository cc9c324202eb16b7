"""SimLink's virtual clock: a positive wait always moves time (a sub-nanosecond remainder of a
float deadline once made proleg learn's explorer rest for ever on the simulator)."""

from __future__ import annotations

import functools

from hypothesis import given, settings
from hypothesis import strategies as st

from proleg.link.sim_link import SimLink


class _SilentBoard:
    def __init__(self) -> None:
        self.advanced = 0.0

    def write(self, data: bytes) -> None:
        pass

    def read(self) -> bytes:
        return b""

    def advance(self, seconds: float) -> None:
        self.advanced += seconds


def test_a_sub_nanosecond_timeout_still_advances_the_clock():
    link = SimLink(_SilentBoard())
    link.read(0.123456789)
    before = link.clock()
    assert link.read(1e-10) == b""
    assert link.clock() > before



# --- the simulated robot keeps its caller's clock --------------------------------------------


class _TickBoard:
    """A board that only counts ticks (SimulatedRobot's board interface, no firmware)."""

    def __init__(self, tick_us: int) -> None:
        self.tick_us = tick_us
        self.ticks = 0

    def run_ticks(self, n: int) -> None:
        self.ticks += n

    def pwm(self, channel: int) -> float:
        return 0.0

    def imu_truth(self, *args) -> None:
        pass

    @property
    def time_s(self) -> float:
        return self.ticks * self.tick_us / 1e6

    def write(self, data: bytes) -> None:
        pass

    def read(self) -> bytes:
        return b""


@settings(max_examples=60, deadline=None, derandomize=True)
@given(tick_hz=st.sampled_from([300, 500, 600, 750, 800, 1000, 1200, 2000]),
       link_step_ms=st.sampled_from([0.5, 1.0, 2.0, 2.5, 3.0, 7.0]),
       waits=st.lists(st.floats(min_value=0.0, max_value=0.25), min_size=1, max_size=40))
def test_the_simulated_robot_runs_as_much_virtual_time_as_its_link_asks(tick_hz, link_step_ms, waits):
    """Whatever the robot's tick and the link's step, firmware and plant stay within one plant
    step of the link's clock. (They ran one whole plant step per link step: an 800 Hz robot's
    2.5 ms step on every 2 ms step of the link, so marks on the link's clock, e.g. hil_tests'
    cycle marks, fell 25 % behind the plant's transitions.)"""
    from proleg.sim.closed_loop import SimulatedRobot

    robot = _robot()
    board = _TickBoard(round(1e6 / tick_hz))
    sim = SimulatedRobot(robot, plant="table", board=board)
    link = SimLink(sim, step_s=link_step_ms / 1e3)
    for w in waits:
        link.read(w)
        assert -1e-9 <= link.clock() - board.time_s < sim.plant_dt_s + 1e-9


@functools.cache
def _robot():
    from pathlib import Path

    from proleg.robot import load_robot

    return load_robot(Path(__file__).resolve().parents[1] / "robots" / "paper-r1.toml")


def test_an_800_hz_robots_firmware_clock_keeps_the_link_clock_while_it_walks():
    """End to end on the example robot whose tick does not divide the link's 2 ms step
    (inchworm-3, 800 Hz): every message's firmware time_ms is the link clock at its receipt,
    to within a telemetry frame's transit, over 20 s of walking. Before the simulated robot
    carried its remainder the firmware ran 25 % ahead (time_ms 8,710 at 6.96 s)."""
    from pathlib import Path

    from proleg.link.client import RobotClient
    from proleg.robot import load_robot
    from proleg.sim.closed_loop import SimulatedRobot

    robot = load_robot(Path(__file__).resolve().parents[1] / "robots" / "inchworm-3.toml")
    assert robot.control.tick_hz == 800
    sim = SimulatedRobot(robot)
    client = RobotClient(SimLink(sim), max_limbs=3, max_channels=3)
    client.connect()
    client.start(0, "+x")
    worst, seen = 0.0, 0
    end = client.link.clock() + 20.0
    while client.link.clock() < end:
        rx = client.recv_received(end - client.link.clock())
        if rx is not None and "time_ms" in rx.message.fields:
            worst = max(worst, abs(rx.time - rx.message.fields["time_ms"] / 1e3))
            seen += 1
    client.close()
    assert seen > 500
    assert worst < 0.01, f"firmware clock and link clock {worst * 1e3:.1f} ms apart"
    assert abs(sim.time_s - client.link.clock()) <= sim.plant_dt_s
