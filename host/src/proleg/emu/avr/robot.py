"""The simulated robot on the avr-emu board: the exact arduino-nano firmware in closed
loop with proleg's plant, with the same fault injections and the same board interface
as host-sim, so ``SimSession``, ``SimLink``, the client and hil_tests run on it unchanged.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ...firmware.boards import Board, load_board
from ...firmware.placement import place_imus, sim_imu_keys
from ...robot import Robot
from ...sim.closed_loop import DEFAULT_PLANT_DT_S, SimulatedRobot
from ...sim.plant import Plant
from .board import AvrEmuBoard
from .firmware import nano_elf


def AvrEmuRobot(  # noqa: N802 - a factory that reads like the class it returns
    robot: Robot,
    elf: Path | None = None,
    *,
    seed: int = 1,
    plant: Plant | str | None = None,
    plant_dt_s: float = DEFAULT_PLANT_DT_S,
    conditions: Any = None,
    board: Board | None = None,
) -> SimulatedRobot:
    """``robot``'s arduino-nano firmware (``elf``, built and cached if None) on simavr,
    wired to a plant of ``robot``."""
    board_info = board or load_board("arduino-nano")
    placements = place_imus(robot, board_info)  # where the build put each limb's IMU
    emu = AvrEmuBoard(
        elf or nano_elf(robot, board=board_info),
        seed,
        tick_hz=robot.control.tick_hz,
        board=board_info,
        imu_addresses=sim_imu_keys(placements),
        imu_wiring=tuple((p.address, p.mux or 0, p.channel or 0) for p in placements),
    )
    return SimulatedRobot(robot, seed=seed, plant=plant, conditions=conditions, plant_dt_s=plant_dt_s, board=emu, board_info=board_info)
