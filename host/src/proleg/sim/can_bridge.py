"""The robot's end of a CAN link, for a simulated board: ``CanBoardBridge`` serves a board
object (``write``/``read``/``advance``, e.g. ``SimulatedRobot``) on a python-can bus, framed as
``proleg.protocol.can`` says. It plays the firmware's CAN driver, so it sits with the simulator,
not with the host's links (which it would otherwise import upward); the host side is
``proleg.link.can_link.CanLink``.
"""

from __future__ import annotations

from typing import Any

import can

from ..protocol.can import DEFAULT_BASE, CanIds, CanToWire, WireToCan
from .paced import PacedLoop


class CanBoardBridge:
    """Robot side: serve a board object (``write``/``read``/``advance``) on a CAN bus.

    ``step(dt)`` moves commands from the bus into the board, advances it by ``dt`` seconds
    and sends what it produced; ``start()`` does that on a thread in (roughly) real time.
    """

    def __init__(self, board: Any, bus: can.BusABC, *, node: int = 0, base: int = DEFAULT_BASE,
                 step_s: float = 0.002):
        self.board = board
        self.bus = bus
        self.ids = CanIds(node=node, base=base)
        self.step_s = step_s
        self._rx = CanToWire(self.ids, from_host=True)
        self._tx = WireToCan(self.ids, from_host=False)
        self._loop = PacedLoop(self.step, step_s, "proleg-can-bridge")
        self.frames_sent = 0

    def step(self, dt: float) -> None:
        while True:
            frame = self.bus.recv(timeout=0.0)
            if frame is None:
                break
            if frame.is_extended_id or frame.is_error_frame:
                continue
            data = self._rx.feed(frame.arbitration_id, bytes(frame.data))
            if data:
                self.board.write(data)
        self.board.advance(dt)
        out = self.board.read()
        if out:
            for arbitration_id, payload in self._tx.feed(out):
                self.bus.send(can.Message(arbitration_id=arbitration_id, data=payload, is_extended_id=False))
                self.frames_sent += 1

    def start(self, speed: float = 1.0) -> CanBoardBridge:
        """Run ``step`` on a thread, virtual time paced to wall time × ``speed``."""
        self._loop.start(speed)
        return self

    def stop(self) -> None:
        self._loop.stop()
