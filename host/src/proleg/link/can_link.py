"""CAN links through python-can: ``can.Bus(interface=…, channel=…)``, any interface python-can
supports (socketcan, pcan, kvaser, slcan, virtual...). The frame layout is protocol data, in
``proleg.protocol.can``.

``CanLink`` is the host side: it turns the client's wire bytes into CAN frames and the
robot's CAN frames back into wire bytes, so ``RobotClient`` works unchanged. The robot side for
a simulated board is ``proleg.sim.can_bridge.CanBoardBridge``.
"""

from __future__ import annotations

import time
from typing import Any

import can

from ..errors import LinkError
from ..protocol.can import DEFAULT_BASE, CanIds, CanToWire, WireToCan
from .base import Link


def open_bus(channel: str, interface: str, bitrate: int | None = None, **kwargs: Any) -> can.BusABC:
    """``can.Bus`` with python-can's failures turned into one ``LinkError`` line."""
    if bitrate is not None:
        kwargs["bitrate"] = bitrate
    try:
        return can.Bus(interface=interface, channel=channel, **kwargs)
    except can.exceptions.CanInterfaceNotImplementedError as e:
        known = ", ".join(sorted(can.VALID_INTERFACES))
        raise LinkError(f"unknown or unavailable CAN interface {interface!r} ({_first_line(e)}); "
                        f"python-can knows: {known}") from None
    except (can.CanError, OSError, ValueError, ImportError, NotImplementedError, TypeError) as e:
        raise LinkError(f"cannot open CAN channel {channel!r} on interface {interface!r}: {_first_line(e)}") from None


def _first_line(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__


def _filters(ids: CanIds) -> list[dict[str, int]]:
    return [{"can_id": ids.id(slot), "can_mask": 0x7FF, "extended": False} for slot in range(8)]


class CanLink(Link):
    """Host side of one robot (``node``) on a CAN bus."""

    def __init__(self, channel: str = "can0", interface: str = "socketcan", *, node: int = 0,
                 base: int = DEFAULT_BASE, bitrate: int | None = None, bus: can.BusABC | None = None,
                 **bus_kwargs: Any):
        self.ids = CanIds(node=node, base=base)
        self.description = f"CAN {channel} ({interface}) node {node}"
        self.bus = bus if bus is not None else open_bus(channel, interface, bitrate, **bus_kwargs)
        try:
            self.bus.set_filters(_filters(self.ids))
        except (can.CanError, NotImplementedError):
            pass  # software filtering below is enough
        self._tx = WireToCan(self.ids, from_host=True)
        self._rx = CanToWire(self.ids, from_host=False)
        self._closed = False

    @property
    def dropped(self) -> int:
        """Messages lost while assembling CAN frames (missing or out-of-order frames)."""
        return self._rx.dropped

    def write(self, data: bytes) -> None:
        for arbitration_id, payload in self._tx.feed(bytes(data)):
            try:
                self.bus.send(can.Message(arbitration_id=arbitration_id, data=payload, is_extended_id=False),
                              timeout=1.0)
            except can.CanError as e:
                raise LinkError(f"{self.description}: send failed: {_first_line(e)}") from None

    def read(self, timeout: float) -> bytes:
        deadline = time.monotonic() + max(0.0, timeout)
        out = bytearray()
        while True:
            remaining = deadline - time.monotonic()
            try:
                frame = self.bus.recv(timeout=max(0.0, remaining) if not out else 0.0)
            except can.CanError as e:
                raise LinkError(f"{self.description}: receive failed: {_first_line(e)}") from None
            if frame is None:
                return bytes(out)
            if frame.is_extended_id or frame.is_remote_frame or frame.is_error_frame:
                continue
            out += self._rx.feed(frame.arbitration_id, bytes(frame.data))
            if out and len(out) > 4096:
                return bytes(out)

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self.bus.shutdown()
