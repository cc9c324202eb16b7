"""The simulated board over CAN, in virtual time: the host's ``CanLink`` and the board's own
CAN controller on one python-can virtual bus.

``sim_can_link(sim)`` returns a ``SimLink`` whose wire bytes go host → ``CanLink`` (the host's
framing, ``proleg.protocol.can``) → python-can ``virtual`` bus → ``proleg.sim.can_port.CanPort``
→ the firmware's CAN driver (its C framing, core/canlink.c) and back. As with ``SimLink``,
reading advances virtual time until frames arrive, so hil tests run as fast as the CPU
allows and their timeouts are the board's time. The board must run firmware built for a
board with ``[link] transport = "can"`` (host-sim-can, bluepill-can).
"""

from __future__ import annotations

import itertools
import os
from typing import Any

import can

from ..protocol.can import DEFAULT_BASE
from .can_link import CanLink
from .sim_link import SimLink

_channels = itertools.count()


class _CanHop:
    """``SimLink``'s board: host bytes through the host's CAN link, the board through its port."""

    def __init__(self, port: Any, host: CanLink, robot_bus: can.BusABC):
        self.port = port
        self.host = host
        self.robot_bus = robot_bus

    @property
    def plant(self) -> Any:
        return getattr(self.port.sim, "plant", None)

    @property
    def robot(self) -> Any:
        """The simulated robot's description: ``SimLink.truth`` names each coil's temperature by
        it (over CAN the truth had ``displacement_mm`` and no ``temp_<actuator>_c``, unlike UART)."""
        return getattr(self.port.sim, "robot", None)

    @property
    def displacement_mm(self) -> Any:
        return getattr(self.port.sim, "displacement_mm", None)

    def write(self, data: bytes) -> None:
        self.host.write(data)

    def read(self) -> bytes:
        return self.host.read(0.0)

    def advance(self, seconds: float) -> None:
        self.port.advance(seconds)

    def close(self) -> None:
        self.host.close()
        self.robot_bus.shutdown()
        close = getattr(self.port.sim, "close", None)
        if callable(close):
            close()


def sim_can_link(sim: Any, *, node: int = 0, base: int = DEFAULT_BASE, channel: str | None = None,
                 step_s: float = 0.002, speed: float | None = None, description: str | None = None) -> SimLink:
    """A link to ``sim`` (a simulated robot whose firmware speaks CAN) over a python-can
    virtual bus of its own (``channel``: a fresh name unless given)."""
    from ..sim.can_port import CanPort

    channel = channel or f"proleg-sim-{os.getpid()}-{next(_channels)}"
    robot_bus = can.Bus(interface="virtual", channel=channel)
    host = CanLink(channel, "virtual", node=node, base=base)
    hop = _CanHop(CanPort(sim, robot_bus), host, robot_bus)
    return SimLink(hop, step_s=step_s, speed=speed, description=description or f"simulated board on {host.description}")
