"""Open a robot's firmware on a simulated board by name, with the gait selection and plant.

``open_simulated(robot, board)`` returns a ``SimulatedRobot`` (firmware on a simulated
board, in closed loop with the robot's plant) for every board in
``proleg.sim.simulated_boards.SIMULATED_BOARDS`` (the registry: host-sim, avr-emu, arm-emu).
``host-sim`` is the generated firmware built for the host (``proleg.sim.board.SimBoard``)
with any gait selection; the emulated MCUs run the exact MCU image.
"""

from __future__ import annotations

from typing import Any

from ..errors import SimError
from ..robot import Robot

def simulated_boards() -> list[str]:
    from .simulated_boards import SIMULATED_BOARDS

    return sorted(SIMULATED_BOARDS)


def open_simulated(robot: Robot, board: str = "host-sim", *, seed: int = 1, objective: str = "total",
                   max_transitions: int | None = None, link: str = "uart", **plant: Any) -> Any:
    """A SimulatedRobot running ``robot``'s firmware on the simulated ``board`` (a name in
    ``proleg.sim.simulated_boards.SIMULATED_BOARDS``); ``plant``: ``plant=`` and
    ``conditions=`` as ``SimulatedRobot`` takes them. The emulated MCUs run the board's
    default gait selection: another ``objective`` or ``max_transitions`` is host-sim's.
    ``link="can"``: the firmware built for the board's CAN variant (its host link on CAN:
    drive it through ``proleg.sim.can_port`` / ``proleg.link.sim_can_link``)."""
    from .simulated_boards import simulated_board, simulated_robot

    entry = simulated_board(board)  # SimError naming the boards there are
    firmware_board = entry.firmware_board_for(link)
    if board == "host-sim":
        return open_host_sim(robot, seed=seed, objective=objective, max_transitions=max_transitions,
                             firmware_board=firmware_board, **plant)
    if objective != "total" or max_transitions is not None:
        raise SimError(f"board {board!r}: --objective and --max-transitions are host-sim's for now "
                       f"({entry.firmware_board} firmware carries the default gait selection)")
    options = {k: v for k, v in plant.items() if v}
    if firmware_board != entry.firmware_board:
        options["firmware_board"] = firmware_board
    return simulated_robot(board, robot, seed=seed, **options)


def open_host_sim(robot: Robot, *, seed: int = 1, objective: str = "total", max_transitions: int | None = None,
                  firmware_board: str = "host-sim", **plant: Any) -> Any:
    """The robot's firmware built for the host (cached), on SimBoard, with its plant."""
    from ..firmware.boards import load_board
    from .closed_loop import SimulatedRobot, sim_library

    library = sim_library(robot, objective=objective, max_transitions=max_transitions, board=firmware_board)
    return SimulatedRobot(robot, library, seed=seed, board_info=load_board(firmware_board), **plant)
