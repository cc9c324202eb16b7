"""Hardware-in-the-loop tests: the simulated board by default, a real board on request.

    pytest hil_tests                                   # simulated boards, every example robot
    pytest hil_tests --target serial:/dev/ttyUSB0 --robot robots/paper-r1.toml --board arduino-nano

The tests talk to the robot only through ``proleg.link.RobotClient`` (the same client the
console uses). Tests marked ``plant`` also need the simulated plant's ground truth
(displacement, PWM at tick resolution, injected faults) and are skipped on hardware.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from proleg.firmware.boards import Board, load_board
from proleg.firmware.build import firmware_gaits, gait_table_hash, render_project
from proleg.link import RobotClient
from proleg.robot import Robot, load_robot

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
PAPER_ROBOTS = ("paper-r1", "paper-r2", "paper-r3", "paper-r1-one-actuator")


def pytest_addoption(parser):
    group = parser.getgroup("proleg hardware-in-the-loop")
    group.addoption("--target", default="sim", help="'sim' (default) or 'serial:PORT' for a real board")
    group.addoption("--robot", default=None, help="robot file flashed on the real board")
    group.addoption("--board", default=None, help="board of the real robot (e.g. arduino-nano)")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--target") == "sim":
        return
    skip = pytest.mark.skip(reason="needs the simulated plant's ground truth")
    for item in items:
        if "plant" in item.keywords:
            item.add_marker(skip)


@dataclass
class Target:
    """One robot under test: its description, a connected client and (simulated) its truth."""

    robot: Robot
    board: Board
    client: RobotClient
    sim: object | None  # proleg.sim.closed_loop.SimulatedRobot on the simulator, None on hardware

    @property
    def expected_gait_hash(self) -> int:
        files = render_project(self.robot, self.board, firmware_gaits(self.robot))
        return int(gait_table_hash(files), 16)

    def wait(self, seconds: float) -> list:
        """Let ``seconds`` pass on the link's clock; every message that arrived, as
        ``Received`` (message, time, ground truth)."""
        client = self.client
        deadline = client.link.clock() + seconds
        out = []
        while True:
            rx = client.recv_received(max(0.0, deadline - client.link.clock()))
            if rx is not None:
                out.append(rx)
            elif client.link.clock() >= deadline - 1e-9:
                return out


def _open_sim(robot: Robot, seed: int = 1, plant: str | None = None) -> Target:
    from proleg.link.sim_link import SimLink
    from proleg.sim.closed_loop import SimulatedRobot

    sim = SimulatedRobot(robot, seed=seed, plant=plant)  # None: the default (physical) plant
    client = RobotClient(SimLink(sim, description=f"simulated {robot.name}"),
                         max_limbs=len(robot.limbs), max_channels=len(robot.actuators))
    client.connect()
    return Target(robot, load_board("host-sim"), client, sim)


def _open_serial(config, robot: Robot) -> Target:
    from proleg.link.serial_link import SerialLink

    board_name = config.getoption("--board")
    if not board_name:
        pytest.exit("--target serial:PORT needs --board", returncode=4)
    port = config.getoption("--target").split(":", 1)[1]
    client = RobotClient(SerialLink(port), max_limbs=len(robot.limbs), max_channels=len(robot.actuators))
    client.connect()
    return Target(robot, load_board(board_name), client, None)


@pytest.fixture
def open_target(request):
    """Factory: ``open_target("paper-r1")`` → a connected Target (closed after the test);
    ``plant="table"`` on the simulator for tests where the lookup plant is the point.

    On hardware, the robot is the one given with --robot, whatever the test asks for;
    tests that need a particular robot's behaviour are marked ``plant``."""
    config = request.config
    opened: list[Target] = []

    def open_(robot_name: str = "paper-r1", seed: int = 1, plant: str | None = None) -> Target:
        if config.getoption("--target") == "sim":
            t = _open_sim(load_robot(ROBOTS / f"{robot_name}.toml"), seed, plant)
        else:
            path = config.getoption("--robot")
            if not path:
                pytest.exit("--target serial:PORT needs --robot ROBOT.toml", returncode=4)
            t = _open_serial(config, load_robot(path))
        opened.append(t)
        return t

    yield open_
    for t in opened:
        try:
            t.client.stop()
        except Exception:
            pass
        t.client.close()


@pytest.fixture
def target(open_target) -> Target:
    return open_target("paper-r1")
