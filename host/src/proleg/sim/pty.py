"""Serve a simulated robot on a pseudo-terminal, in real time.

Any serial tool, or ``proleg console --port /dev/pts/N``, then talks to the simulated
board as to a real one on a USB serial port. The simulation is paced to the wall
clock (``speed`` times real time, or as fast as it can go); bytes the host does not read are
dropped once the pty's buffer is full, like a UART whose cable nobody listens to, and counted.
"""

from __future__ import annotations

import errno
import os
import select
import time
import tty
from collections.abc import Callable, Sequence
from pathlib import Path

from .closed_loop import SimulatedRobot


#: Output the server holds while the pty's own buffer is full (nobody reading): a UART sends
#: into the void, a USB adapter buffers a little. It held 64 KiB, half a minute of frames at
#: 50 Hz, which a client that connected later took for its own session (proleg run --port
#: counted 624 frames for a 1 s run, the first ones 11 s before its START).
BACKLOG_BYTES = 1024
#: Wall time the server steps the simulation before it serves the pty again. Catching up on
#: all of ``speed`` × the wall time at once never ended at a speed faster than the machine can
#: simulate: at ``--speed 1e9`` not one byte was served (and 0.0 s simulated), at 10000 fewer
#: seconds than at 100. Past what it can do, the simulation runs late instead.
CATCH_UP_SLICE_S = 0.02


class PtyServer:
    """``faults``: ``(at_s, FAULT)`` pairs injected once ``at_s`` of simulated time has passed
    since ``serve`` was first called (``proleg sim --pty --inject FAULT+T``, as without --pty and in
    ``proleg console --sim``); ``say`` tells each injection."""

    def __init__(self, sim: SimulatedRobot, speed: float = 1.0, link: str | Path | None = None,
                 faults: Sequence[tuple[float, str]] = (), say: Callable[[str], None] = print):
        self.sim = sim
        self.due = sorted((float(at), str(f)) for at, f in faults)
        self.elapsed_s = 0.0  # simulated seconds served by the last serve()
        self._t0: float | None = None  # simulated time at the first serve(): timed faults count from it
        self.say = say
        self.speed = speed
        self.master, self._slave = os.openpty()  # the slave stays open: clients may come and go
        tty.setraw(self._slave)
        os.set_blocking(self.master, False)
        self.path = os.ttyname(self._slave)
        self.link = Path(link) if link else None
        if self.link is not None:
            if self.link.is_symlink():
                self.link.unlink()
            self.link.symlink_to(self.path)
        self.bytes_in = self.bytes_out = self.bytes_dropped = 0

    def close(self) -> None:
        if self.link is not None and self.link.is_symlink():
            self.link.unlink()
        for fd in (self.master, self._slave):
            try:
                os.close(fd)
            except OSError:
                pass

    def __enter__(self) -> "PtyServer":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def serve(self, duration_s: float | None = None, should_stop: Callable[[], bool] = lambda: False) -> None:
        """Run until ``duration_s`` of virtual time has passed (forever if None) or stopped."""
        sim = self.sim
        wall0, sim0 = time.monotonic(), sim.time_s
        pending = b""
        t0 = self._t0 = sim0 if self._t0 is None else self._t0
        while not should_stop():
            elapsed = self.elapsed_s = sim.time_s - sim0
            if duration_s is not None and elapsed >= duration_s:
                return
            ready, _, _ = select.select([self.master], [], [], sim.plant_dt_s / self.speed)
            if ready:
                try:
                    data = os.read(self.master, 4096)
                except OSError as e:  # EIO: no client has the slave open right now
                    if e.errno != errno.EIO:
                        raise
                    data = b""
                if data:
                    self.bytes_in += len(data)
                    sim.write(data)
            now = time.monotonic()
            target, slice_end = (now - wall0) * self.speed, now + CATCH_UP_SLICE_S
            while sim.time_s - sim0 < target and time.monotonic() < slice_end:
                sim.step()
                while self.due and sim.time_s - t0 >= self.due[0][0]:
                    at, fault = self.due.pop(0)
                    sim.inject(fault)
                    self.say(f"injected {fault} at {sim.time_s - t0:.1f} s (simulated)")
            pending += sim.read()
            if pending:
                pending = self._write(pending)

    def _write(self, data: bytes) -> bytes:
        try:
            n = os.write(self.master, data)
        except BlockingIOError:
            n = 0
        self.bytes_out += n
        rest = data[n:]
        if len(rest) > BACKLOG_BYTES:  # nobody is reading: drop the oldest, as a UART would
            self.bytes_dropped += len(rest) - BACKLOG_BYTES
            rest = rest[-BACKLOG_BYTES:]
        return rest
