"""An emulated Arduino Nano on a pseudo-terminal, with its bootloader and its auto-reset,
so the real flash tool (avrdude) and the real host link (pyserial) talk to it as to a
Nano on /dev/ttyUSB0.

- **Bootloader.** Optiboot (``optiboot.build_optiboot``, or any Intel HEX that fits the
  boot section) sits at 0x7E00 with BOOTRST set: every reset starts it. Optiboot 4.4 stays
  only after an external reset (MCUSR = EXTRF), for about 1 s (its 1 s watchdog, restarted
  by every well-formed command); otherwise, or on a byte it does not expect, it lets the
  watchdog reset the chip into the application. simavr performs its SPM page erase/write.
- **Auto-reset.** On a Nano, opening the port raises DTR, whose edge pulls RESET low
  through a 100 nF capacitor. A pseudo-terminal has no DTR, so the opening itself is the
  signal: the master side reports POLLHUP while nobody holds the slave open; when that
  ends, the emulated chip gets an external reset.
- **Real time.** The core runs in slices of emulated time throttled to the wall clock
  (``speed`` × real time, default 1): faster than about 2× real time optiboot's window
  closes before avrdude, which waits 300 ms after its DTR toggle, syncs. A host that
  falls behind (a loaded machine) is not caught up in a burst: the lag is dropped.
- **Closed port.** What the chip sends while nobody has the port open is dropped, as a
  USB-serial adapter does; it is not queued for the next opener.

``python -m proleg.emu.avr.pty_nano [--elf APP.elf] [--link PATH]`` prints the pty's path
(``pty: /dev/pts/N``) and serves until SIGINT/SIGTERM. See docs/flashing.md.
"""

from __future__ import annotations

import argparse
import errno
import os
import select
import signal
import sys
import time
import tty
from dataclasses import dataclass
from pathlib import Path

from ...errors import SimError
from .board import AvrEmuBoard
from .optiboot import BOOT_START, build_optiboot, check_boot_image, read_ihex

#: emulated time per slice: the pty is served (read, written, open checked) between slices
SLICE_US = 500
#: a host this far behind real time drops the lag instead of running faster to catch up
MAX_LAG_S = 0.02


@dataclass
class PtyStats:
    opens: int = 0
    bytes_in: int = 0
    bytes_out: int = 0
    dropped_out: int = 0
    emulated_s: float = 0.0
    wall_s: float = 0.0


class PtyNano:
    """``board`` (an ``AvrEmuBoard`` with a bootloader installed) served on a new pty."""

    def __init__(self, board: AvrEmuBoard, *, speed: float = 1.0, link: str | Path | None = None):
        if not speed > 0:
            raise SimError(f"speed must be > 0 (× real time), got {speed}")
        self.board = board
        self.speed = speed
        self.stats = PtyStats()
        self.master, slave = os.openpty()
        self.path = os.ttyname(slave)
        tty.setraw(slave)  # the slave's line discipline: no echo, no CR/LF mapping
        os.close(slave)  # from now on POLLHUP on the master says "nobody has it open"
        os.set_blocking(self.master, False)
        self._poll = select.poll()
        self._poll.register(self.master, select.POLLIN | select.POLLHUP)
        self._open = False
        self._pending = bytearray()
        self.link = Path(link) if link else None
        if self.link is not None:
            if self.link.is_symlink() or self.link.exists():
                self.link.unlink()
            self.link.symlink_to(self.path)

    # -- one step ---------------------------------------------------------------------
    def _check_open(self) -> bool:
        events = dict(self._poll.poll(0)).get(self.master, 0)
        is_open = not events & select.POLLHUP
        if is_open and not self._open:
            self.stats.opens += 1
            self._pending.clear()
            self.board.read()  # what the chip sent while the port was closed is gone
            self.board.external_reset()  # DTR → 100 nF → RESET
        self._open = is_open
        return is_open

    def _host_to_chip(self) -> None:
        while True:
            try:
                data = os.read(self.master, 4096)
            except BlockingIOError:
                return
            except OSError as e:
                if e.errno == errno.EIO:  # the slave was just closed
                    return
                raise
            if not data:
                return
            self.stats.bytes_in += len(data)
            self.board.write(data)

    def _chip_to_host(self) -> None:
        out = self.board.read()
        if not self._open:
            self.stats.dropped_out += len(out)
            return
        self._pending += out
        while self._pending:
            try:
                n = os.write(self.master, self._pending)
            except BlockingIOError:
                return  # the reader is slow: keep it for the next slice
            except OSError as e:
                if e.errno == errno.EIO:
                    return
                raise
            self.stats.bytes_out += n
            del self._pending[:n]

    def step(self) -> None:
        """Serve the port, then run one slice of emulated time."""
        if self._check_open():
            self._host_to_chip()
        self.board.run_us(SLICE_US)
        self._chip_to_host()

    # -- the loop ---------------------------------------------------------------------
    def serve(self, until: float | None = None, stop=lambda: False) -> PtyStats:
        """Serve until ``stop()`` is true or ``until`` wall-clock seconds have passed."""
        t0 = time.perf_counter()
        emu0 = self.board.time_s
        base_wall, base_emu = t0, emu0
        while not stop():
            now = time.perf_counter()
            if until is not None and now - t0 >= until:
                break
            self.step()
            ahead = (self.board.time_s - base_emu) / self.speed - (time.perf_counter() - base_wall)
            if ahead > 0:
                if self._open:
                    self._poll.poll(ahead * 1000.0)  # wakes early when the host writes
                else:
                    time.sleep(ahead)
            elif ahead < -MAX_LAG_S:
                base_wall, base_emu = time.perf_counter(), self.board.time_s  # drop the lag
        self.stats.emulated_s += self.board.time_s - emu0
        self.stats.wall_s += time.perf_counter() - t0
        return self.stats

    def close(self) -> None:
        if self.link is not None and self.link.is_symlink():
            self.link.unlink()
        os.close(self.master)


def nano_with_bootloader(elf: Path | None = None, bootloader: Path | None = None, seed: int = 1) -> AvrEmuBoard:
    """An emulated Nano with optiboot (or ``bootloader``) in its boot section and ``elf``
    in its application section (a blank application section when None)."""
    hexfile = bootloader or build_optiboot()
    image = read_ihex(hexfile)
    check_boot_image(image, str(hexfile))
    blank = elf is None
    if blank:
        elf = hexfile.with_suffix(".elf")  # any ATmega328P ELF opens the core; the flash is erased below
        if not elf.exists():
            raise SimError(f"{elf}: no ELF next to {hexfile}: give the application (--elf)")
    board = AvrEmuBoard(elf, seed, tick_hz=1000 if blank else None)
    board.install_bootloader(image, BOOT_START, erase_application=blank)
    board.reset(seed)  # power-on: flash kept, the core starts in the boot section
    return board


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m proleg.emu.avr.pty_nano",
        description="An emulated Arduino Nano (optiboot, auto-reset on open) on a pseudo-terminal.",
    )
    p.add_argument("--elf", type=Path, help="application already in flash (default: blank, as a new chip)")
    p.add_argument("--bootloader", type=Path, help="Intel HEX of the bootloader (default: optiboot built from Debian's sources)")
    p.add_argument("--link", help="also make this path a symlink to the pty (e.g. /tmp/ttyNANO)")
    p.add_argument("--speed", type=float, default=1.0, help="× real time (default 1; above ~2 optiboot closes before avrdude syncs)")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    try:
        board = nano_with_bootloader(args.elf, args.bootloader, args.seed)
        nano = PtyNano(board, speed=args.speed, link=args.link)
    except (SimError, OSError) as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    stopping = []
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: stopping.append(True))
    print(f"pty: {nano.path}", flush=True)
    try:
        st = nano.serve(stop=lambda: bool(stopping))
    finally:
        nano.close()
    print(
        f"served {st.wall_s:.1f} s ({st.emulated_s:.1f} s emulated): {st.opens} opens, {st.bytes_in} bytes in, "
        f"{st.bytes_out} out, {st.dropped_out} dropped while closed, {board.mcu_resets} MCU resets",
        file=sys.stderr,
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
