"""``ArmEmuRobot``: the emulated bluepill in closed loop with proleg's plant.

The same loop as host-sim's ``proleg.sim.run.SimulatedRobot`` (and its write/read/advance,
fault injection by name), with the board swapped for ``ArmEmuBoard`` running the exact
bluepill image: every plant step, the plant's true ψ goes into the IMU models, the
firmware runs its ticks in emulated time, and the plant integrates the duties the
timer registers produce.
"""

from __future__ import annotations

from pathlib import Path

from ...firmware.boards import load_board
from ...robot import Robot
from ...sim.plant import Plant, plant_params_from_robot, true_rewards_from_robot
from ...sim.run import DEFAULT_PLANT_DT_S, LinkFaults, SimulatedRobot
from .board import ArmEmuBoard
from .firmware import BOARD, bluepill_elf


class ArmEmuRobot(SimulatedRobot):
    def __init__(self, robot: Robot, elf: Path | None = None, *, seed: int = 1, plant: Plant | None = None,
                 plant_dt_s: float = DEFAULT_PLANT_DT_S):
        self.robot = robot
        self.board_info = load_board(BOARD)
        addrs = tuple(self.board_info.i2c.get("imu_addresses", [0x68, 0x69]))
        self.board = ArmEmuBoard(elf or bluepill_elf(robot), seed, pwm_pins=self.board_info.pwm_channels,
                                 imu_addresses=addrs)
        if plant is None:
            plant = Plant(plant_params_from_robot(robot), true_rewards_from_robot(robot), robot.levels, seed)
        self.plant = plant
        self.imu_addresses = addrs[: len(robot.limbs)]
        self.channels = tuple(range(max(a.channel for a in robot.actuators) + 1))
        self.ticks_per_step = max(1, round(plant_dt_s * 1e6 / self.board.tick_us))
        self.plant_dt_s = self.ticks_per_step * self.board.tick_us / 1e6
        self.link_faults = LinkFaults()
        self._push_truth()
