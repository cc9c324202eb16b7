"""The one link interface every transport implements (like python-can's ``BusABC``).

A link moves the protocol's wire bytes (COBS frames, see ``proleg.protocol``) between the
host and one robot. It knows nothing about messages' meaning: ``RobotClient`` decodes, the
console/recorder/tests subscribe to the client. Three implementations:

- ``SerialLink``  — pyserial's ``serial_for_url`` (a device, COM port, ``socket://``,
  ``rfc2217://``, ``loop://``, a pty path);
- ``CanLink``     — python-can (any interface), frames mapped as in ``proleg.protocol.can``;
- ``SimLink``     — an in-process simulated board, advanced in virtual time.

``proleg.link.factory.open_link(url)`` picks one from a URL (``serial://…``, ``can://…``, ``sim://ROBOT``).
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from types import TracebackType

from ..errors import LinkError


class LinkDisconnected(LinkError):
    """The device went away (USB serial unplugged...); ``Link.reopen`` may bring it back."""


class Link(ABC):
    """A byte pipe to one robot.

    ``read`` returns whatever bytes arrived (possibly several or partial frames), or ``b""``
    when ``timeout`` seconds passed without any. ``clock`` is the link's time base in seconds:
    wall time since the link opened for real links, virtual time for the simulated board;
    timeouts are measured on it.
    """

    #: Human-readable endpoint for messages ("/dev/ttyUSB0", "can0 (socketcan) node 1", "sim paper-r1").
    description: str = "link"

    @abstractmethod
    def write(self, data: bytes) -> None:
        """Send wire bytes (whole frames). Raises ``LinkError``/``LinkDisconnected``."""

    @abstractmethod
    def read(self, timeout: float) -> bytes:
        """Bytes received within ``timeout`` seconds of ``clock``; ``b""`` when none."""

    @abstractmethod
    def close(self) -> None:
        """Release the transport; idempotent."""

    #: ``clock``'s zero on the monotonic clock: when the link opened (real links set it when
    #: they open; a link that does not gets it at its first ``clock`` call)
    _clock_zero: float | None = None

    def clock(self) -> float:
        """Seconds on the link's time base (monotonic), 0 ≈ when the link opened: what
        recordings' ``t_host_s`` counts (docs/data.md)."""
        now = time.monotonic()
        if self._clock_zero is None:
            self._clock_zero = now
        return now - self._clock_zero

    def reopen(self) -> None:
        """Try to open the transport again after ``LinkDisconnected``; raises ``LinkError`` if
        it is still gone. Links that cannot disappear do not support it."""
        raise LinkError(f"{self.description}: link cannot be reopened")

    def truth(self) -> dict[str, float]:
        """Ground truth the link can tell beyond the protocol (the simulated robot's
        ``displacement_mm``...); empty for real hardware."""
        return {}

    def __enter__(self) -> Link:
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.description}>"
