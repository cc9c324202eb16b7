"""CAN links through python-can: ``can.Bus(interface=…, channel=…)``, any interface python-can
supports (socketcan, pcan, kvaser, slcan, virtual...). The frame layout is protocol data, in
``proleg.protocol.can``.

``CanLink`` is the host side: it turns the client's wire bytes into CAN frames and the
robot's CAN frames back into wire bytes, so ``RobotClient`` works unchanged. The robot side for
a simulated board is ``proleg.sim.can_bridge.CanBoardBridge``.

What is not given (interface, channel, bit rate) comes from python-can's own configuration,
read by ``can.util.load_config`` in its order: the ``CAN_INTERFACE`` / ``CAN_CHANNEL`` /
``CAN_BITRATE`` (and ``CAN_CONFIG``) environment, then ``~/.canrc`` / ``can.ini``
(``[default]`` section). Only when none of them names an interface is it ``socketcan``.
"""

from __future__ import annotations

import time
from typing import Any

import can

from ..errors import LinkError, UsageError
from ..protocol.can import DEFAULT_BASE, N_SLOTS, CanIds, CanToWire, WireToCan
from .base import Link


#: the interface when neither the caller nor python-can's configuration names one
FALLBACK_INTERFACE = "socketcan"
#: The fastest CAN bit rate the host asks for: classic CAN's 1 Mbit/s (CAN FD's faster data
#: phase is not a ``bitrate``).
MAX_BITRATE = 1_000_000


def bus_config(channel: str | None = None, interface: str | None = None, bitrate: int | None = None,
               **kwargs: Any) -> dict[str, Any]:
    """The bus settings: what is given, completed from python-can's configuration
    (environment, ``~/.canrc``) by ``can.util.load_config``; ``LinkError`` for a bad file or value."""
    given = {k: v for k, v in {"channel": channel, "interface": interface, "bitrate": bitrate, **kwargs}.items()
             if v is not None and v != ""}
    if "interface" in given and given["interface"] not in can.VALID_INTERFACES:  # a typo, not a link that failed
        raise UsageError(f"unknown CAN interface {given['interface']!r}; python-can knows: "
                         f"{', '.join(sorted(can.VALID_INTERFACES))}")
    try:
        if "interface" not in given and not _configured_interface():
            given["interface"] = FALLBACK_INTERFACE
        config = can.util.load_config(config=given)
    except can.exceptions.CanInterfaceNotImplementedError as e:
        known = ", ".join(sorted(can.VALID_INTERFACES))
        where = repr(given["interface"]) if "interface" in given else "named by CAN_INTERFACE or ~/.canrc"
        raise LinkError(f"unknown or unavailable CAN interface {where} ({_first_line(e)}); "
                        f"python-can knows: {known}") from None
    except (ValueError, TypeError, KeyError) as e:  # a malformed ~/.canrc or CAN_* value
        raise LinkError(f"python-can configuration (CAN_* environment or ~/.canrc): {_first_line(e)}") from None
    if config.get("channel") in (None, ""):
        raise LinkError("no CAN channel: give one (--can can0) or set CAN_CHANNEL / channel in ~/.canrc")
    return config


def _configured_interface() -> bool:
    """Whether python-can's configuration (environment, config files) names an interface."""
    sources = (can.rc, can.util.load_environment_config(), can.util.load_file_config())
    return any(src.get("interface") or src.get("bustype") for src in sources)


def open_bus(channel: str | None = None, interface: str | None = None, bitrate: int | None = None,
             **kwargs: Any) -> can.BusABC:
    """``can.Bus`` on ``bus_config(...)``, python-can's failures turned into one ``LinkError`` line."""
    config = bus_config(channel, interface, bitrate, **kwargs)
    interface, channel = config["interface"], config["channel"]
    try:
        return can.Bus(**config)
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
    return [{"can_id": ids.id(slot), "can_mask": 0x7FF, "extended": False} for slot in range(N_SLOTS)]


class CanLink(Link):
    """Host side of one robot (``node``) on a CAN bus."""

    def __init__(self, channel: str | None = None, interface: str | None = None, *, node: int = 0,
                 base: int = DEFAULT_BASE, bitrate: int | None = None, bus: can.BusABC | None = None,
                 **bus_kwargs: Any):
        """``channel``/``interface``/``bitrate`` None: from python-can's configuration."""
        self._clock_zero = time.monotonic()  # clock() counts from the opening (t_host_s ≈ 0)
        self.ids = CanIds(node=node, base=base)
        if bus is None:
            self.config = bus_config(channel, interface, bitrate, **bus_kwargs)
            bus = open_bus(**self.config)
        else:
            self.config = {"channel": channel, "interface": interface, "bitrate": bitrate}
        rate = self.config.get("bitrate")
        self.description = (f"CAN {self.config['channel']} ({self.config['interface']}"
                            f"{f', {int(rate)} bit/s' if rate else ''}) node {node}")
        self.bus = bus
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
