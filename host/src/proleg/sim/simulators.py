"""Which simulator runs a robot's firmware for a board: a board-to-simulator table.

``open_simulated(robot, board)`` returns a ``SimulatedRobot`` (firmware on a simulated
board, in closed loop with the robot's plant) for every board named in ``SIMULATORS``.
Each entry is ``"module:function"``, imported only when that board is asked for (as
python-can's interface registry does); the function takes ``(robot, seed=...,
objective=..., max_transitions=...)``. ``host-sim`` is the generated firmware built for
the host (``proleg.sim.board.SimBoard``). An emulated MCU registers its board here with
one line (e.g. ``"avr-emu": "proleg.emu.avr.robot:open_robot"``).
"""

from __future__ import annotations

import importlib
from typing import Any

from ..errors import SimError
from ..robot import Robot

SIMULATORS: dict[str, str] = {
    "host-sim": "proleg.sim.simulators:open_host_sim",
}


def simulated_boards() -> list[str]:
    return sorted(SIMULATORS)


def open_host_sim(robot: Robot, *, seed: int = 1, objective: str = "total", max_transitions: int | None = None,
                  **plant: Any) -> Any:
    """The robot's firmware built for the host (cached), on SimBoard, with its plant."""
    from ..firmware.boards import load_board
    from .closed_loop import SimulatedRobot, sim_library

    library = sim_library(robot, objective=objective, max_transitions=max_transitions)
    return SimulatedRobot(robot, library, seed=seed, board_info=load_board("host-sim"), **plant)


def open_simulated(robot: Robot, board: str = "host-sim", *, seed: int = 1, objective: str = "total",
                   max_transitions: int | None = None, **plant: Any) -> Any:
    """A SimulatedRobot running ``robot``'s firmware on the simulated ``board``; ``plant``:
    ``plant=`` and ``conditions=`` as ``SimulatedRobot`` takes them."""
    entry = SIMULATORS.get(board)
    if entry is None:
        raise SimError(f"board {board!r} has no simulator (simulated boards: {', '.join(simulated_boards())})")
    module, _, name = entry.partition(":")
    try:
        opener = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as e:
        raise SimError(f"board {board!r}: its simulator {entry} cannot be loaded: {e}") from None
    return opener(robot, seed=seed, objective=objective, max_transitions=max_transitions, **plant)
