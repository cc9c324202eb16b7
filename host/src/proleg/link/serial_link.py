"""Serial links through pyserial's ``serial_for_url``: ``/dev/ttyUSB0``, ``COM3``, a pty path,
``socket://host:port``, ``rfc2217://host:port``, ``loop://``.

A USB serial adapter that disappears raises ``LinkDisconnected`` from ``read``/``write``;
``reopen`` opens the same URL again (the client retries it until the device is back).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import serial

from ..errors import LinkError
from .base import Link, LinkDisconnected
from ..ports import PortLock

DEFAULT_BAUDRATE = 115200
#: The fastest serial link the host takes (an FT232H's 12 Mbaud); a bigger number overflows
#: the termios call (OverflowError), and no adapter runs faster.
MAX_BAUDRATE = 12_000_000

Opener = Callable[..., Any]


#: Opening a port: its old input is read away until the line is quiet this long (a frame of 50 Hz
#: telemetry comes every 20 ms), for at most DRAIN_S.
QUIET_S = 0.03
DRAIN_S = 0.3


class SerialLink(Link):
    """One serial port. ``opener`` is ``serial.serial_for_url`` unless a test injects another."""

    def __init__(self, url: str, baudrate: int = DEFAULT_BAUDRATE, *, opener: Opener | None = None):
        self.url = url
        self.baudrate = baudrate
        self.description = url
        self._opener: Opener = opener or serial.serial_for_url
        self._port: Any = None
        self._lock: PortLock | None = None
        self._timeout: float | None = None
        self._clock_zero = time.monotonic()  # clock() counts from the opening (t_host_s ≈ 0)
        self._open()

    def _open(self) -> None:
        # A device is ours alone (proleg.ports' flock, taken before the port is touched): a second
        # console or run on the same port opened it too, and the two split the board's bytes
        # between them, each seeing gaps and CRC errors, each able to START the gait the other
        # stops; a flash under a console broke both.
        lock = PortLock(self.url)
        try:
            self._port = self._opener(self.url, baudrate=self.baudrate, timeout=0.0, write_timeout=2.0)
        except (serial.SerialException, OSError, ValueError, OverflowError) as e:
            lock.release()
            self._port = None
            raise LinkError(f"cannot open serial port {self.url}: {_reason(e)}") from None
        self._lock = lock
        self._timeout = 0.0
        self._discard_backlog()

    def _discard_backlog(self) -> None:
        """What the port held before we opened it is no part of this session: a board idle behind
        a pty (or a USB adapter's buffer) left seconds of old frames there, which ``proleg run
        --port`` counted and recorded as its own. Flushed, then read away until the line is quiet
        for ``QUIET_S`` (a pty still hands over what was in flight), for at most ``DRAIN_S``: a
        Nano that resets as its port opens says nothing for a while, so its BOOT is not lost."""
        port = self._port
        try:
            port.reset_input_buffer()
            end = time.monotonic() + DRAIN_S
            port.timeout = self._timeout = QUIET_S
            while time.monotonic() < end and port.read(max(1, port.in_waiting)):
                pass
        except (serial.SerialException, OSError, AttributeError, ValueError):
            pass  # a port (or URL handler) without an input buffer to discard

    def write(self, data: bytes) -> None:
        port = self._require()
        try:
            port.write(data)
        except serial.SerialTimeoutException:
            raise LinkError(f"{self.url}: write timed out (is the device reading?)") from None
        except (serial.SerialException, OSError) as e:
            self._drop()
            raise LinkDisconnected(f"{self.url}: device disconnected ({_reason(e)})") from None

    def read(self, timeout: float) -> bytes:
        port = self._require()
        try:
            if self._timeout != timeout:  # pyserial reconfigures the port on every change
                port.timeout = timeout
                self._timeout = timeout
            data = port.read(max(1, port.in_waiting))
            if data:
                waiting = port.in_waiting
                if waiting:
                    data += port.read(waiting)
            return bytes(data)
        except (serial.SerialException, OSError) as e:
            self._drop()
            raise LinkDisconnected(f"{self.url}: device disconnected ({_reason(e)})") from None

    def reopen(self) -> None:
        self._drop()
        self._open()

    def close(self) -> None:
        self._drop()

    def _require(self) -> Any:
        if self._port is None:
            raise LinkDisconnected(f"{self.url}: port is not open")
        return self._port

    def _drop(self) -> None:
        port, self._port = self._port, None
        lock, self._lock = self._lock, None
        if port is not None:
            try:
                port.close()
            except Exception:  # a vanished device may fail to close; it is gone either way
                pass
        if lock is not None:
            lock.release()  # after the port: nobody else opens it while ours is still open


def _reason(e: BaseException) -> str:
    text = str(e).strip()
    return text.splitlines()[0] if text else type(e).__name__
