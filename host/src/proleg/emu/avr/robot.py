"""The simulated robot on the avr-emu board: the exact arduino-nano firmware in closed
loop with proleg's plant, with the same fault injections and the same duck-typed
board interface (``write``/``read``/``advance``) as host-sim's ``SimulatedRobot``, so
``SimSession``, ``SimLink``, the client and hil_tests run on it unchanged.

``SimulatedRobot`` builds its own host-sim board; until it accepts a board object this
subclass sets the same attributes with an ``AvrEmuBoard`` in its place.
"""

from __future__ import annotations

from pathlib import Path

from ...firmware.boards import Board, load_board
from ...robot import Robot
from ...sim.plant import Plant, plant_params_from_robot, true_rewards_from_robot
from ...sim.run import DEFAULT_PLANT_DT_S, LinkFaults, SimulatedRobot
from .board import AvrEmuBoard
from .firmware import nano_elf


class AvrEmuRobot(SimulatedRobot):
    """``robot``'s arduino-nano firmware on simavr, wired to a plant of ``robot``."""

    def __init__(
        self,
        robot: Robot,
        elf: Path | None = None,
        *,
        seed: int = 1,
        plant: Plant | None = None,
        plant_dt_s: float = DEFAULT_PLANT_DT_S,
        board: Board | None = None,
    ):
        self.robot = robot
        self.board_info = board or load_board("arduino-nano")
        addrs = list(self.board_info.i2c.get("imu_addresses", [0x68, 0x69]))
        self.imu_addresses = tuple(addrs[: len(robot.limbs)])
        self.board = AvrEmuBoard(
            elf or nano_elf(robot, board=self.board_info),
            seed,
            tick_hz=robot.control.tick_hz,
            board=self.board_info,
            imu_addresses=self.imu_addresses,
        )
        if plant is None:
            plant = Plant(plant_params_from_robot(robot), true_rewards_from_robot(robot), robot.levels, seed)
        self.plant = plant
        self.channels = tuple(range(max(a.channel for a in robot.actuators) + 1))
        self.ticks_per_step = max(1, round(plant_dt_s * 1e6 / self.board.tick_us))
        self.plant_dt_s = self.ticks_per_step * self.board.tick_us / 1e6
        self.link_faults = LinkFaults()
        self._push_truth()
