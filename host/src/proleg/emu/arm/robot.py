"""``ArmEmuRobot``: the emulated bluepill in closed loop with proleg's plant.

host-sim's ``SimulatedRobot`` (write/read/advance, fault injection by name) with the
board swapped for ``ArmEmuBoard`` running the exact bluepill image: every plant step, the
plant's true ψ goes into the IMU models, the firmware runs its ticks in emulated time,
and the plant integrates the duties the timer registers produce.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...firmware.boards import load_board
from ...firmware.placement import place_imus, sim_imu_keys
from ...robot import Robot
from ...sim.closed_loop import DEFAULT_PLANT_DT_S, SimulatedRobot
from ...sim.plant import Plant
from .board import ArmEmuBoard
from .firmware import BOARD, bluepill_elf


def ArmEmuRobot(  # noqa: N802 - a factory that reads like the class it returns
    robot: Robot,
    elf: Path | None = None,
    *,
    seed: int = 1,
    plant: Plant | None = None,
    plant_dt_s: float = DEFAULT_PLANT_DT_S,
    conditions: Any = None,
    firmware_board: str = BOARD,
) -> SimulatedRobot:
    board_info = load_board(firmware_board)
    places = place_imus(robot, board_info)
    wiring = tuple((p.bus, p.address, p.mux or 0, p.channel or 0) for p in places)  # I2C1/I2C2, maybe behind a mux
    emu = ArmEmuBoard(elf or bluepill_elf(robot, board=firmware_board), seed, pwm_pins=board_info.pwm_channels,
                      imu_addresses=sim_imu_keys(places), imu_wiring=wiring)
    return SimulatedRobot(robot, seed=seed, plant=plant, conditions=conditions, plant_dt_s=plant_dt_s, board=emu, board_info=board_info)
