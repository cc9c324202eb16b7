"""Hardware-in-the-loop tests: the simulated board by default, an emulated MCU or a real
board on request.

    pytest hil_tests                                   # host-sim, the paper's robots
    pytest hil_tests --robot robots/inchworm-3.toml    # one robot (every test runs on it)
    pytest hil_tests --target avr-emu                  # the exact arduino-nano firmware.elf on simavr
    pytest hil_tests --target arm-emu                  # the exact bluepill firmware.elf on unicorn
    pytest hil_tests --target avr-emu -m "not emu_long"   # the focused subset `make test` runs
    pytest hil_tests --target serial:/dev/ttyUSB0 --robot robots/paper-r1.toml --board arduino-nano
    pytest hil_tests --link can                        # host-sim's firmware speaking CAN, python-can virtual bus
    pytest hil_tests --target arm-emu --link can       # the exact bluepill-can image, bxCAN model

The tests talk to the robot only through ``proleg.link.RobotClient`` (the same client the
console uses). Tests marked ``plant`` also need the simulated plant's ground truth
(displacement, PWM at tick resolution, injected faults): they run on host-sim and on the
emulated MCUs (which have the plant) and are skipped on hardware. Tests marked
``emu_long`` take minutes on an emulated MCU; ``make test`` deselects them there and
``make emu`` runs them (``emu_long_on("arm-emu")``: only on the emulated MCUs named, where
the emulator is slow for them). ``--robot`` is honoured on every target: given a robot, every test
runs on it (the gait tests on its gaits); a test that shows one robot's behaviour (marked
``robot("paper-r1")``) is deselected for another. With ``--target sim``, ``--board`` may
name the simulated board instead (``proleg.sim.simulated_boards.SIMULATED_BOARDS``).
``--link can`` runs a simulated board's CAN firmware (host-sim-can, bluepill-can): the
client talks to it through python-can's virtual bus (``proleg.link.sim_can_link``), frames
framed by the firmware's own CAN driver; ``fresh_sim`` boards (tests of the safety envelope
that drive the bare board) keep the UART. The ``can_link`` marker names the short subset
``make test`` runs over CAN.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import pytest

from proleg.firmware.boards import Board, load_board
from proleg.errors import BuildError
from proleg.firmware.build import firmware_gaits, gait_table_hash, render_project
from proleg.link import RobotClient
from proleg.robot import Robot, load_robot
from proleg.sim.simulated_boards import SIMULATED_BOARDS

ROBOTS = Path(__file__).resolve().parents[1] / "robots"
PAPER_ROBOTS = ("paper-r1", "paper-r2", "paper-r3", "paper-r1-one-actuator")


def pytest_addoption(parser):
    group = parser.getgroup("proleg hardware-in-the-loop")
    group.addoption("--target", default="sim",
                    help="'sim' or 'host-sim' (default), 'avr-emu', 'arm-emu' (an emulated MCU running the exact "
                         "firmware image), or 'serial:PORT' for a real board")
    group.addoption("--robot", default=None, help="robot file under test (on a real board: the one flashed)")
    group.addoption("--link", default="uart", choices=("uart", "can"),
                    help="the simulated board's host link: uart (default) or can (its CAN firmware on python-can's "
                         "virtual bus)")
    group.addoption("--board", default=None,
                    help="board: of the real robot (e.g. arduino-nano), or with --target sim the simulated one")


def pytest_configure(config):
    config.addinivalue_line("markers", "robot(*names): shows these robots' own behaviour (deselected for another --robot)")
    config.addinivalue_line("markers", "gait_cases(opposing): parametrised over the robots' firmware gaits")
    config.addinivalue_line("markers", "can_link: in the short subset `make test` runs with --link can")


def robot_paths(config) -> list[Path]:
    """The robots under test: --robot, else the paper's robots."""
    given = config.getoption("--robot")
    return [Path(given)] if given else [ROBOTS / f"{name}.toml" for name in PAPER_ROBOTS]


def pytest_generate_tests(metafunc):
    """Tests marked gait_cases(opposing) run once per firmware gait of the robots under
    test whose steps do (or do not) raise one limb while lowering another."""
    mark = metafunc.definition.get_closest_marker("gait_cases")
    if mark is None:
        return
    from proleg.states import opposing_steps

    opposing = mark.kwargs.get("opposing", False)
    xfail = mark.kwargs.get("xfail", {})  # (robot name, direction) -> reason: a known strict xfail
    cases = []
    for path in robot_paths(metafunc.config):
        robot = load_robot(path)
        for direction, gaits in firmware_gaits(robot).items():
            for i, gait in enumerate(gaits):
                if bool(opposing_steps(gait.states, robot.levels)) == opposing:
                    walk = "-".join(robot.transitions.label(s) for s in gait.states)
                    reason = xfail.get((robot.name, direction))
                    marks = [pytest.mark.xfail(strict=True, reason=reason)] if reason else []
                    cases.append(pytest.param(str(path), direction, i, id=f"{robot.name}{direction}:{walk}",
                                              marks=marks))
    if mark.kwargs.get("focused_first"):  # an emulated MCU's focused subset walks one gait
        cases = cases[:1] + [pytest.param(*c.values, id=c.id, marks=[*c.marks, pytest.mark.emu_long])
                             for c in cases[1:]]
    metafunc.parametrize("robot_name,direction,gait_index", cases)


def simulated_board_name(config) -> str | None:
    """The simulated board ``--target`` names (``sim``: ``--board`` if it names a simulated
    board, else host-sim), None for a real board."""
    target = config.getoption("--target")
    if target == "sim":
        board = config.getoption("--board")
        return board if board in SIMULATED_BOARDS else "host-sim"
    if target in SIMULATED_BOARDS:
        return target
    if target.startswith("serial:"):
        return None
    raise pytest.UsageError(
        f"--target {target}: expected sim, {', '.join(SIMULATED_BOARDS)} or serial:PORT"
    )


@pytest.hookimpl(tryfirst=True)  # before ``-m`` selects on the marks added here
def pytest_collection_modifyitems(config, items):
    target = simulated_board_name(config)  # --target arm-emu, or --target sim --board arm-emu
    for item in items:  # minutes on these emulated MCUs only: emu_long there
        mark = item.get_closest_marker("emu_long_on")
        if mark is not None and target in mark.args:
            item.add_marker(pytest.mark.emu_long)
    given = config.getoption("--robot")
    name = load_robot(given).name if given else None
    kept, other_robots = [], []
    for item in items:
        mark = item.get_closest_marker("robot")
        (other_robots if name and mark and name not in mark.args else kept).append(item)
    if other_robots:  # another robot's own behaviour: not a test of this one at all
        config.hook.pytest_deselected(items=other_robots)
        items[:] = kept
    here = Path(__file__).resolve().parent
    hil = [item for item in items if here in Path(str(item.fspath)).resolve().parents]
    board = simulated_board_name(config)
    if board is None:
        skip = pytest.mark.skip(reason="needs the simulated plant's ground truth")
        for item in hil:
            if "plant" in item.keywords:
                item.add_marker(skip)
        return
    missing = SIMULATED_BOARDS[board].missing()
    if missing:
        for item in hil:
            item.add_marker(pytest.mark.skip(reason=missing))


@dataclass
class Target:
    """One robot under test: its description, a connected client and (simulated) its truth."""

    robot: Robot
    board: Board
    client: RobotClient
    sim: object | None  # proleg.sim.closed_loop.SimulatedRobot on a simulated board, None on hardware
    simulated_board: str | None = None  # host-sim, avr-emu, arm-emu; None on hardware
    link: str = "uart"  # the host link: "uart", or "can" (--link can)

    @property
    def emulated(self) -> bool:
        """The exact MCU firmware image on an instruction-level emulator."""
        return self.simulated_board is not None and SIMULATED_BOARDS[self.simulated_board].emulated

    def fresh_sim(self, robot: Robot | None = None, seed: int = 1, plant: str | None = None):
        """Another simulated robot on the same simulated board, from power-on."""
        from proleg.sim.simulators import open_simulated

        if self.simulated_board is None:
            pytest.skip("needs a simulated board")
        return open_simulated(robot or self.robot, self.simulated_board, seed=seed, plant=plant)

    @property
    def expected_gait_hash(self) -> int:
        files = render_project(self.robot, self.board, firmware_gaits(self.robot))
        return int(gait_table_hash(files), 16)

    def step(self) -> None:
        """One plant step of the simulated robot, with its host link carried along (on CAN
        the frames it sent reach the bus, and the bus's frames reach it)."""
        board = self.client.link.board if self.link == "can" else None
        if board is not None:
            board.advance(self.sim.plant_dt_s)
        else:
            self.sim.step()

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


def _open_sim(robot: Robot, board: str = "host-sim", seed: int = 1, plant: str | None = None,
              link: str = "uart") -> Target:
    from proleg.link.sim_link import SimLink
    from proleg.sim.simulators import open_simulated

    firmware_board = load_board(SIMULATED_BOARDS[board].firmware_board_for(link))
    try:
        sim = open_simulated(robot, board, seed=seed, plant=plant, link=link)  # plant None: the default (physical)
    except BuildError as e:  # the board cannot host this robot (flash, RAM, pins, tick budget): say why
        pytest.skip(f"{robot.name} does not run on {board}: {str(e).splitlines()[0]}")
    if link == "can":
        from proleg.link.sim_can_link import sim_can_link

        can = firmware_board.can
        transport = sim_can_link(sim, node=can.node, base=can.base_id,
                                 description=f"{robot.name} on {board} over CAN (python-can virtual bus)")
    else:
        transport = SimLink(sim, description=f"{robot.name} on {board}")
    # the heartbeat fits the robot's link watchdog: at 100 ms (the least a file may say) the default
    # 0.5 s heartbeat let every test that waits trip LINK_WATCHDOG
    client = RobotClient(transport, max_limbs=len(robot.limbs), max_channels=len(robot.actuators),
                         watchdog_ms=robot.safety.link_watchdog_ms)
    client.connect()
    return Target(robot, firmware_board, client, sim, board, link)


def _open_serial(config, robot: Robot) -> Target:
    from proleg.link.serial_link import SerialLink

    board_name = config.getoption("--board")
    if not board_name:
        pytest.exit("--target serial:PORT needs --board", returncode=4)
    port = config.getoption("--target").split(":", 1)[1]
    client = RobotClient(SerialLink(port), max_limbs=len(robot.limbs), max_channels=len(robot.actuators),
                         watchdog_ms=robot.safety.link_watchdog_ms)
    client.connect()
    return Target(robot, load_board(board_name), client, None)


@pytest.fixture
def open_target(request):
    """Factory: ``open_target("paper-r1")`` → a connected Target (closed after the test);
    ``plant="table"`` on a simulated board for tests where the lookup plant is the point.

    The robot is the one given with --robot, whatever the test asks for, on every target,
    except in a test of named robots' own behaviour (marker ``robot``): asking there for a
    robot other than --robot's skips the test, with that reason;
    without --robot, a simulated board runs the robot the test names (a name in robots/ or
    a robot file's path)."""
    config = request.config
    opened: list[Target] = []
    own = request.node.get_closest_marker("robot")  # a test of these robots' own behaviour

    def open_(robot_name: str = "paper-r1", seed: int = 1, plant: str | None = None) -> Target:
        given = config.getoption("--robot")
        if own is not None and given and not robot_name.endswith(".toml"):
            name = load_robot(given).name
            if robot_name != name:  # e.g. a comparison of R1 with R2 under --robot R1: R2 is not here
                pytest.skip(f"--robot {name}: this test also needs {robot_name}'s own behaviour")
        board = simulated_board_name(config)
        if board is not None:
            given = config.getoption("--robot")
            path = Path(given) if given else (
                Path(robot_name) if robot_name.endswith(".toml") else ROBOTS / f"{robot_name}.toml")
            t = _open_sim(load_robot(path), board, seed, plant, config.getoption("--link"))
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
