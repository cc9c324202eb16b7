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
  signal (``proleg.emu.pty.PtyPort``): the emulated chip gets an external reset.
- **Real time.** ``proleg.emu.pty.serve_board`` throttles the core to the wall clock
  (``speed`` × real time, default 1): unthrottled, optiboot's 1 s window closes before
  avrdude, which waits 300 ms after its DTR toggle, syncs (measured: ``--speed 10`` fails
  with "not in sync", 1 and 3 flash).

``python -m proleg.emu.avr.pty_nano [--elf APP.elf] [--link PATH]`` prints the pty's path
(``pty: /dev/pts/N``) and serves until SIGINT/SIGTERM. See docs/flashing.md.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ...errors import SimError
from ..pty import PtyPort, PtyStats, serve_board, stop_on_signals
from .board import AvrEmuBoard, _config_value
from .optiboot import BOOT_START, build_optiboot, check_boot_image, read_ihex


class PtyNano:
    """``board`` (an ``AvrEmuBoard`` with a bootloader installed) served on a new pty."""

    def __init__(self, board: AvrEmuBoard, *, speed: float = 1.0, link: str | Path | None = None):
        self.board = board
        self.speed = speed
        self.port = PtyPort(link)
        self.path = self.port.path

    def serve(self, until: float | None = None, stop=lambda: False) -> PtyStats:
        """Serve until ``stop()`` is true or ``until`` wall-clock seconds have passed."""
        return serve_board(self.board, self.port, speed=self.speed, on_open=self.board.external_reset,
                           until=until, stop=stop)

    def close(self) -> None:
        self.port.close()


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
    # The tick rate only paces run_ticks (the pty server runs by time): any for a foreign ELF.
    tick_hz = None if not blank and _config_value(elf, "CFG_TICK_HZ") else 1000.0
    board = AvrEmuBoard(elf, seed, tick_hz=tick_hz)
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
    p.add_argument("--speed", type=float, default=1.0, help="× real time (default 1; much faster and optiboot's window closes before avrdude syncs)")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    try:
        board = nano_with_bootloader(args.elf, args.bootloader, args.seed)
        nano = PtyNano(board, speed=args.speed, link=args.link)
    except (SimError, OSError) as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    stop = stop_on_signals()
    print(f"pty: {nano.path}", flush=True)
    try:
        st = nano.serve(stop=stop)
    except SimError as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    finally:
        nano.close()
    print(f"{st.line()}, {board.mcu_resets} MCU resets", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
