"""The in-process simulated board as a link.

The board object (``proleg.sim``, or any object with the same three methods) is duck-typed::

    write(data: bytes) -> None      # host → board UART
    read() -> bytes                 # board → host bytes produced so far
    advance(seconds: float) -> None # run firmware + plant in virtual time

``SimLink.read(timeout)`` advances virtual time in ``step_s`` steps until bytes arrive or
``timeout`` virtual seconds pass, so a test runs as fast as the CPU allows; ``clock()`` is the
virtual time, so the client's timeouts are virtual too. ``speed`` paces virtual time to wall
time (1.0 = real time, for the console); ``None`` runs flat out.
"""

from __future__ import annotations

import math
import threading
import time
from typing import Any, Protocol

from ..errors import LinkError
from .base import Link


class BoardLike(Protocol):
    def write(self, data: bytes) -> None: ...
    def read(self) -> bytes: ...
    def advance(self, seconds: float) -> None: ...


TRUTH_ATTRIBUTES = ("displacement_mm",)


def temperature_key(actuator: str) -> str:
    """The truth (and recording column) of a simulated coil's temperature, °C: ``temp_<name>_c``."""
    from ..names import identifier

    return f"temp_{identifier(actuator)}_c"


#: The slowest pace (``speed``) the CLI takes for a simulated board (``run --sim --speed``, ``sim
#: --pty --speed``, a ``sim://`` URL's ``speed``): a thousandth of real time, a simulated second
#: in about 17 minutes. 1e-9 was taken, and ``run --sim --duration 1`` then lasted 32 years.
MIN_SPEED = 0.001


class SimLink(Link):
    def __init__(self, board: BoardLike, *, step_s: float = 0.002, speed: float | None = None,
                 description: str = "simulated board"):
        if step_s <= 0:
            raise LinkError(f"simulated link step must be > 0 s, got {step_s}")
        if speed is not None and speed <= 0:
            raise LinkError(f"simulated link speed must be > 0, got {speed}")
        self.board = board
        self.step_s = step_s
        self.speed = speed
        self.description = description
        self._t_ns = 0
        self._step_ns = max(1, round(step_s * 1e9))
        self._lock = threading.Lock()
        self._wall0 = time.monotonic()
        self._closed = False

    def write(self, data: bytes) -> None:
        self._check_open()
        with self._lock:
            self.board.write(bytes(data))

    def read(self, timeout: float) -> bytes:
        self._check_open()
        with self._lock:
            data = self.board.read()
            if data:
                return bytes(data)
            # Rounded up: a positive timeout below 0.5 ns must still advance the clock, or a
            # caller waiting "until clock() >= end" (end = clock() + s, in float seconds) reads
            # a remaining sub-nanosecond forever without time moving (proleg learn hung so).
            deadline = self._t_ns + math.ceil(max(0.0, timeout) * 1e9)
            while True:
                step = min(self._step_ns, deadline - self._t_ns)
                if step <= 0:
                    return b""
                self.board.advance(step / 1e9)
                self._t_ns += step
                if self.speed is not None:
                    self._pace()
                data = self.board.read()
                if data:
                    return bytes(data)

    def _pace(self) -> None:
        ahead = self._t_ns / 1e9 / self.speed - (time.monotonic() - self._wall0)  # type: ignore[operator]
        if ahead > 0.001:
            time.sleep(ahead)

    def clock(self) -> float:
        return self._t_ns / 1e9

    def truth(self) -> dict[str, float]:
        out: dict[str, float] = {}
        source: Any = getattr(self.board, "plant", None) or self.board
        for name in TRUTH_ATTRIBUTES:
            v = getattr(source, name, None)
            if v is None and source is not self.board:
                v = getattr(self.board, name, None)
            if isinstance(v, (int, float)):
                out[name] = float(v)
        robot = getattr(self.board, "robot", None)
        temps = getattr(source, "temperature_c", None) if source is not self.board else None
        if robot is not None and temps is not None:  # each coil's temperature: no board can tell it
            for actuator, t in zip(robot.actuators, temps):
                out[temperature_key(actuator.name)] = float(t)
        return out

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            close = getattr(self.board, "close", None)
            if callable(close):
                close()

    def _check_open(self) -> None:
        if self._closed:
            raise LinkError(f"{self.description}: link is closed")
