"""An emulated board's serial port as a pseudo-terminal, so that real host tools (avrdude,
stm32flash, pyserial) open it as they would /dev/ttyUSB0.

``PtyPort`` is the master side of a new pty:
- **Who has it open.** The master reports POLLHUP while nobody holds the slave open
  (Linux); ``poll_open`` turns the end of that into "just opened", which the Nano uses
  as its DTR auto-reset.
- **Closed port.** What the board sends while nobody has the port open is dropped, as a
  USB-serial adapter does; it is not queued for the next opener.
- **Raw.** The slave starts raw (no echo, no CR/LF mapping); the opener sets its own
  termios (baud rate and parity mean nothing on a pty).

``serve_board`` runs a board (``run_us``, ``write``, ``read``, ``time_s``: AvrEmuBoard,
ArmEmuBoard) behind a ``PtyPort`` in slices of emulated time throttled to the wall clock
(``speed`` × real time): protocols with timeouts (a bootloader's window) then see the
host's timing as on the bench. A host that falls behind (a loaded machine) drops the lag
instead of catching up in a burst.
"""

from __future__ import annotations

import errno
import os
import select
import signal
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from ..errors import SimError
from ..names import counted

#: emulated time per slice: the pty is served (read, written, open checked) between slices
SLICE_US = 500
#: a host this far behind real time drops the lag instead of running faster to catch up
MAX_LAG_S = 0.02


class SerialBoard(Protocol):
    def run_us(self, us: int) -> None: ...
    def write(self, data: bytes) -> None: ...
    def read(self) -> bytes: ...
    @property
    def time_s(self) -> float: ...


@dataclass
class PtyStats:
    opens: int = 0
    bytes_in: int = 0
    bytes_out: int = 0
    dropped_out: int = 0
    emulated_s: float = 0.0
    wall_s: float = 0.0

    def line(self) -> str:
        return (
            f"served {self.wall_s:.1f} s ({self.emulated_s:.1f} s emulated): {counted(self.opens, 'open')}, "
            f"{self.bytes_in} bytes in, {self.bytes_out} out, {self.dropped_out} dropped while closed"
        )


class PtyPort:
    """The master side of a new pseudo-terminal (``path`` is the slave to open)."""

    def __init__(self, link: str | Path | None = None):
        self.master, slave = os.openpty()
        self.path = os.ttyname(slave)
        tty.setraw(slave)
        os.close(slave)  # from now on POLLHUP on the master says "nobody has it open"
        os.set_blocking(self.master, False)
        self._poll = select.poll()
        self._poll.register(self.master, select.POLLIN | select.POLLHUP)
        self.is_open = False
        self.just_opened = False
        self._pending = bytearray()
        self.stats = PtyStats()
        self.link = Path(link) if link else None
        if self.link is not None:
            if self.link.is_symlink() or self.link.exists():
                self.link.unlink()
            self.link.symlink_to(self.path)

    def poll_open(self) -> bool:
        """Whether someone has the port open now; True once per opening in ``just_opened``."""
        events = dict(self._poll.poll(0)).get(self.master, 0)
        now_open = not events & select.POLLHUP
        self.just_opened = now_open and not self.is_open
        if self.just_opened:
            self.stats.opens += 1
            self._pending.clear()
        self.is_open = now_open
        return now_open

    def read(self) -> bytes:
        """What the host wrote since the last call (nothing while closed)."""
        chunks = []
        while True:
            try:
                data = os.read(self.master, 4096)
            except BlockingIOError:
                break
            except OSError as e:
                if e.errno == errno.EIO:  # nobody has the slave open
                    break
                raise
            if not data:
                break
            chunks.append(data)
        out = b"".join(chunks)
        self.stats.bytes_in += len(out)
        return out

    def write(self, data: bytes) -> None:
        """Send to the host; dropped while nobody has the port open."""
        if not self.is_open:
            self.stats.dropped_out += len(data)
            return
        self._pending += data
        while self._pending:
            try:
                n = os.write(self.master, self._pending)
            except BlockingIOError:
                return  # the reader is slow: the rest goes out on the next call
            except OSError as e:
                if e.errno == errno.EIO:
                    return
                raise
            self.stats.bytes_out += n
            del self._pending[:n]

    def wait(self, seconds: float) -> None:
        """Sleep up to ``seconds``; wakes early when the host writes (while open)."""
        if seconds <= 0:
            return
        if self.is_open:
            self._poll.poll(seconds * 1000.0)
        else:
            time.sleep(seconds)  # POLLHUP would wake poll at once

    def close(self) -> None:
        if self.link is not None and self.link.is_symlink():
            self.link.unlink()
        os.close(self.master)


def serve_board(
    board: SerialBoard,
    port: PtyPort,
    *,
    speed: float = 1.0,
    on_open: Callable[[], None] | None = None,
    until: float | None = None,
    stop: Callable[[], bool] = lambda: False,
) -> PtyStats:
    """Run ``board`` behind ``port`` at ``speed`` × real time until ``stop()`` or ``until``
    wall-clock seconds; ``on_open`` runs each time a host opens the port."""
    if not speed > 0:
        raise SimError(f"speed must be > 0 (× real time), got {speed}")
    t0 = time.perf_counter()
    emu0 = board.time_s
    base_wall, base_emu = t0, emu0
    while not stop():
        if until is not None and time.perf_counter() - t0 >= until:
            break
        if port.poll_open():
            if port.just_opened:
                board.read()  # what the chip sent while the port was closed is gone
                if on_open is not None:
                    on_open()
            data = port.read()
            if data:
                board.write(data)
        board.run_us(SLICE_US)
        port.write(board.read())
        ahead = (board.time_s - base_emu) / speed - (time.perf_counter() - base_wall)
        if ahead > 0:
            port.wait(ahead)
        elif ahead < -MAX_LAG_S:
            base_wall, base_emu = time.perf_counter(), board.time_s  # drop the lag
    port.stats.emulated_s += board.time_s - emu0
    port.stats.wall_s += time.perf_counter() - t0
    return port.stats


def stop_on_signals() -> Callable[[], bool]:
    """A ``stop`` for the serving loops that turns true on SIGINT or SIGTERM (the command-line
    servers end cleanly and print their counts instead of dying mid-frame)."""
    stopping: list[bool] = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopping.append(True))
    return lambda: bool(stopping)
