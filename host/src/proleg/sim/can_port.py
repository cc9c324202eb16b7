"""A simulated board whose firmware speaks CAN itself, on a python-can bus.

The firmware built for a board with ``[link] transport = "can"`` (host-sim-can, or
bluepill-can on arm-emu) frames the protocol in its own C (core/canlink.c) and its
CAN controller (hal/sim/can_sim.c, or the bxCAN model of arm-emu) offers the frames as
``can_read()`` / ``can_write(id, data)``. ``CanPort`` puts them on a python-can bus and
back, in step with the simulation: ``advance(dt)`` delivers what arrived on the bus, runs
the board and the plant for ``dt`` of virtual time, and sends what the board put on its
bus. Nothing is translated here (unlike ``can_bridge.CanBoardBridge``, which plays the CAN
driver for a firmware that speaks UART).
"""

from __future__ import annotations

from typing import Any

import can

from .paced import PacedLoop


class CanPort:
    """``sim`` (a ``SimulatedRobot`` or bare board whose ``board`` has ``can_read``/``can_write``)
    on the python-can ``bus``."""

    def __init__(self, sim: Any, bus: can.BusABC):
        self.sim = sim
        self.board = getattr(sim, "board", sim)
        self.bus = bus
        self.frames_in = 0
        self.frames_out = 0
        self._loop: PacedLoop | None = None

    def pump_in(self) -> None:
        """Every frame waiting on the bus into the board's controller."""
        while True:
            msg = self.bus.recv(timeout=0.0)
            if msg is None:
                return
            if msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
                continue  # the controller's filter takes standard data frames only
            self.board.can_write(msg.arbitration_id, bytes(msg.data))
            self.frames_in += 1

    def pump_out(self) -> None:
        """Every frame the board sent, onto the bus."""
        for arbitration_id, data in self.board.can_read():
            self.bus.send(can.Message(arbitration_id=arbitration_id, data=data, is_extended_id=False))
            self.frames_out += 1

    def advance(self, seconds: float) -> None:
        self.pump_in()
        self.sim.advance(seconds)
        self.pump_out()

    def start(self, speed: float = 1.0, step_s: float = 0.002) -> CanPort:
        """Serve the bus from a thread, virtual time paced to wall time × ``speed`` (so a host in
        another process, e.g. ``proleg console --can`` on a shared ``udp_multicast`` or
        ``socketcan`` bus, talks to the simulated board as to a real one)."""
        self._loop = PacedLoop(self.advance, step_s, "proleg-can-port").start(speed)
        return self

    def stop(self) -> None:
        if self._loop is not None:
            self._loop.stop()
            self._loop = None
