"""The STM32F103's ROM serial bootloader (ST AN3155, USART protocol) on a pseudo-terminal,
so ``stm32flash`` (and ``proleg flash --board bluepill-f103 --tool stm32flash``) writes
the emulated bluepill's flash; GO then boots arm-emu from that flash on the same port.

On the board: BOOT0 = 1 and a reset start the system-memory bootloader (AN2606 §4:
STM32F10xxx medium density, bootloader v2.2, USART1 on PA9/PA10, 8E1). It waits for
0x7F (autobaud), answers ACK (0x79), then serves commands, each sent as the command byte
and its complement; a bad complement, checksum or address gets NACK (0x1F).

Emulated here (AN3155 §3):
- GET (0x00): version 2.2 and the commands of the F103's bootloader; GET VERSION (0x01);
  GET ID (0x02): PID 0x410 (medium density);
- READ MEMORY (0x11): flash, RAM, system memory (blank) and the option bytes
  (factory values: RDP = 0xA5, no write protection);
- WRITE MEMORY (0x31): flash (1 KB pages as on the chip: a half-word can only be
  programmed when erased, else NACK: a PGERR on the chip, RM0008 §3.3.3) and RAM;
- ERASE (0x43): global (0xFF 0x00) or a list of 1 KB pages; EXTENDED ERASE (0x44): the
  two-byte variant (mass erase 0xFFFF), offered instead of 0x43 with ``extended_erase``
  (the later STM32 bootloaders), so both stm32flash paths can be tried;
- GO (0x21): to the flash base, the vector table's stack pointer and reset handler (what
  the chip's bootloader does); arm-emu then runs the flash on the same port;
- WRITE UNPROTECT (0x73) and READOUT UNPROTECT (0x92, which mass-erases): ACK, ACK and a
  system reset back into the bootloader (BOOT0 is still 1), as on the chip. WRITE PROTECT
  (0x63) and READOUT PROTECT (0x82) are answered NACK: protection is not emulated.

Not emulated: the UART's byte timing (replies come at once), the flash's programming
and erase times, GO to RAM or to an address other than the flash base (NACK).

``python -m proleg.emu.arm.rom_bootloader [--image firmware.bin] [--link PATH]`` prints
``pty: /dev/pts/N`` and serves until SIGINT/SIGTERM. See docs/flashing.md.
"""

from __future__ import annotations

import argparse
import os
import struct
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Generator
from pathlib import Path

from ...errors import SimError
from ...names import counted
from ..pty import PtyPort, serve_board, stop_on_signals

ACK, NACK = 0x79, 0x1F
INIT = 0x7F
VERSION = 0x22  # bootloader v2.2 (AN2606, STM32F10xxx medium density)
PID = 0x410  # STM32F10xxx medium density (RM0008 DBGMCU_IDCODE DEV_ID)
FLASH_BASE, FLASH_SIZE, PAGE = 0x08000000, 0x10000, 1024  # STM32F103C8: 64 KB, 1 KB pages
RAM_BASE, RAM_SIZE = 0x20000000, 0x5000
RAM_BOOTLOADER = 0x200  # the bootloader's own RAM (AN2606): not writable by the host
SYSMEM_BASE, SYSMEM_SIZE = 0x1FFFF000, 0x800
OPTION_BASE = 0x1FFFF800
#: factory option bytes (RM0008 §4.7.1): RDP 0xA5 (unprotected), USER 0xFF, data 0xFF, WRP 0xFF, each with its complement
OPTION_BYTES = bytes([0xA5, 0x5A, 0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00, 0xFF, 0x00])

CMD_GET, CMD_GVR, CMD_GID, CMD_READ, CMD_GO, CMD_WRITE = 0x00, 0x01, 0x02, 0x11, 0x21, 0x31
CMD_ERASE, CMD_EXT_ERASE, CMD_WP, CMD_WUNP, CMD_RP, CMD_RUNP = 0x43, 0x44, 0x63, 0x73, 0x82, 0x92


def _xor(data: bytes) -> int:
    x = 0
    for b in data:
        x ^= b
    return x


class RomBootloader:
    """The AN3155 protocol as a byte stream: ``feed(host bytes)`` → bytes to answer.

    ``flash`` is the chip's 64 KB of flash (erased = 0xFF); ``go_address`` is set when the
    host sent GO (the caller then boots the flash); ``resets`` counts the system resets the
    unprotect commands make."""

    def __init__(self, flash: bytes | None = None, *, extended_erase: bool = False):
        self.flash = bytearray(b"\xff" * FLASH_SIZE)
        if flash:
            if len(flash) > FLASH_SIZE:
                raise SimError(f"flash image of {len(flash)} bytes is larger than the {FLASH_SIZE}-byte flash")
            self.flash[: len(flash)] = flash
        self.ram = bytearray(RAM_SIZE)
        self.extended_erase = extended_erase
        self.go_address: int | None = None
        self.resets = 0
        self.log: list[str] = []  # one line per command served, for tests and -v
        self._in = bytearray()
        self._out = bytearray()
        self._proto = self._protocol()
        self._need = next(self._proto)

    def summary(self) -> str:
        """The commands served, by kind: "GET: 1, WRITE: 54, ..." (addresses left out)."""
        kinds = Counter(line.split(" 0x")[0] for line in self.log)
        return ", ".join(f"{k}: {n}" for k, n in kinds.items()) or "no commands"

    @property
    def commands(self) -> tuple[int, ...]:
        erase = CMD_EXT_ERASE if self.extended_erase else CMD_ERASE
        return (CMD_GET, CMD_GVR, CMD_GID, CMD_READ, CMD_GO, CMD_WRITE, erase, CMD_WP, CMD_WUNP, CMD_RP, CMD_RUNP)

    def feed(self, data: bytes) -> bytes:
        """Bytes from the host; returns what the bootloader answers."""
        self._in += data
        while self.go_address is None and len(self._in) >= self._need:
            chunk = bytes(self._in[: self._need])
            del self._in[: self._need]
            self._need = self._proto.send(chunk)
        out = bytes(self._out)
        self._out.clear()
        return out

    def reset(self) -> None:
        """System reset with BOOT0 = 1: back to waiting for 0x7F."""
        self.resets += 1
        self._in.clear()
        self._proto = self._protocol()
        self._need = next(self._proto)

    # -- memory -------------------------------------------------------------------------
    def _region(self, addr: int, n: int, *, write: bool) -> tuple[bytearray | bytes, int] | None:
        """(memory, offset) holding [addr, addr + n), or None when out of bounds."""
        if FLASH_BASE <= addr and addr + n <= FLASH_BASE + FLASH_SIZE:
            return self.flash, addr - FLASH_BASE
        lo = RAM_BASE + (RAM_BOOTLOADER if write else 0)
        if lo <= addr and addr + n <= RAM_BASE + RAM_SIZE:
            return self.ram, addr - RAM_BASE
        if not write and SYSMEM_BASE <= addr and addr + n <= SYSMEM_BASE + SYSMEM_SIZE:
            return bytes(SYSMEM_SIZE), addr - SYSMEM_BASE  # the ROM's code is not ours to show
        if not write and OPTION_BASE <= addr and addr + n <= OPTION_BASE + len(OPTION_BYTES):
            return OPTION_BYTES, addr - OPTION_BASE
        return None

    def _program(self, mem: bytearray, off: int, data: bytes) -> bool:
        if mem is not self.flash:
            mem[off : off + len(data)] = data
            return True
        if off % 2 or len(data) % 2:
            return False  # the flash is programmed by half-words (RM0008 §3.3.3)
        for i in range(0, len(data), 2):
            old = mem[off + i : off + i + 2]
            new = data[i : i + 2]
            if old != b"\xff\xff" and new != b"\x00\x00" and old != new:
                return False  # PGERR: programming a half-word that is not erased
        mem[off : off + len(data)] = data
        return True

    def _erase_pages(self, pages: list[int]) -> bool:
        if any(p >= FLASH_SIZE // PAGE for p in pages):
            return False
        for p in pages:
            self.flash[p * PAGE : (p + 1) * PAGE] = b"\xff" * PAGE
        return True

    # -- the protocol -------------------------------------------------------------------
    def _send(self, *data: int | bytes) -> None:
        for d in data:
            if isinstance(d, int):
                self._out.append(d)
            else:
                self._out += d

    def _address(self) -> Generator[int, bytes, int | None]:
        """Receive a 4-byte address and its XOR checksum; ACK/NACK; the address or None."""
        raw = yield 5
        if _xor(raw[:4]) != raw[4]:
            self._send(NACK)
            return None
        return struct.unpack(">I", raw[:4])[0]

    def _protocol(self) -> Generator[int, bytes, None]:
        while (yield 1)[0] != INIT:
            pass  # before autobaud the USART does not even know the baud rate
        self._send(ACK)
        while True:
            cmd, comp = yield 2
            if cmd ^ comp != 0xFF or cmd not in self.commands:
                self._send(NACK)
                continue
            if cmd == CMD_GET:
                self._send(ACK, len(self.commands), VERSION, bytes(self.commands), ACK)
                self.log.append("GET")
            elif cmd == CMD_GVR:
                self._send(ACK, VERSION, 0x00, 0x00, ACK)
                self.log.append("GET VERSION")
            elif cmd == CMD_GID:
                self._send(ACK, 1, PID >> 8, PID & 0xFF, ACK)
                self.log.append("GET ID")
            elif cmd == CMD_READ:
                self._send(ACK)
                addr = yield from self._address()
                if addr is None:
                    continue
                region = self._region(addr, 1, write=False)
                if region is None:
                    self._send(NACK)
                    continue
                self._send(ACK)
                n_raw = yield 2
                n = n_raw[0] + 1
                region = self._region(addr, n, write=False)
                if n_raw[0] ^ n_raw[1] != 0xFF or region is None:
                    self._send(NACK)
                    continue
                mem, off = region
                self._send(ACK, bytes(mem[off : off + n]))
                self.log.append(f"READ 0x{addr:08x} {n}")
            elif cmd == CMD_WRITE:
                self._send(ACK)
                addr = yield from self._address()
                if addr is None:
                    continue
                if self._region(addr, 1, write=True) is None:
                    self._send(NACK)
                    continue
                self._send(ACK)
                n = (yield 1)[0] + 1
                payload = yield n + 1
                data, cs = payload[:n], payload[n]
                region = self._region(addr, n, write=True)
                if (n - 1) ^ _xor(data) != cs or region is None or not self._program(region[0], region[1], data):  # type: ignore[arg-type]
                    self._send(NACK)
                    continue
                self._send(ACK)
                self.log.append(f"WRITE 0x{addr:08x} {n}")
            elif cmd == CMD_ERASE:
                self._send(ACK)
                n = (yield 1)[0]
                if n == 0xFF:
                    ok = (yield 1)[0] == 0x00
                    if ok:
                        self._erase_pages(list(range(FLASH_SIZE // PAGE)))
                    self._send(ACK if ok else NACK)
                    self.log.append("ERASE all" if ok else "ERASE refused")
                    continue
                payload = yield n + 2
                pages, cs = list(payload[: n + 1]), payload[n + 1]
                ok = _xor(bytes([n, *pages])) == cs and self._erase_pages(pages)
                self._send(ACK if ok else NACK)
                self.log.append(f"ERASE {counted(len(pages), 'page')}" if ok else "ERASE refused")
            elif cmd == CMD_EXT_ERASE:
                self._send(ACK)
                head = yield 2
                n = (head[0] << 8) | head[1]
                if n >= 0xFFFD:  # mass erase (0xFFFF), bank 1 (0xFFFE), bank 2 (0xFFFD)
                    ok = (yield 1)[0] == head[0] ^ head[1]
                    if ok:
                        self._erase_pages(list(range(FLASH_SIZE // PAGE)))
                    self._send(ACK if ok else NACK)
                    self.log.append("EXTENDED ERASE all" if ok else "EXTENDED ERASE refused")
                    continue
                payload = yield 2 * (n + 1) + 1
                pages = [(payload[i] << 8) | payload[i + 1] for i in range(0, 2 * (n + 1), 2)]
                ok = _xor(head + payload[:-1]) == payload[-1] and self._erase_pages(pages)
                self._send(ACK if ok else NACK)
                self.log.append(f"EXTENDED ERASE {counted(len(pages), 'page')}" if ok else "EXTENDED ERASE refused")
            elif cmd == CMD_GO:
                self._send(ACK)
                addr = yield from self._address()
                if addr is None:
                    continue
                if addr != FLASH_BASE:
                    self._send(NACK)  # only the flash's vector table is emulated
                    continue
                self._send(ACK)
                self.log.append(f"GO 0x{addr:08x}")
                self.go_address = addr
                yield 1 << 30  # the application owns the port from now on
            elif cmd in (CMD_WUNP, CMD_RUNP):
                self._send(ACK)
                if cmd == CMD_RUNP:
                    self._erase_pages(list(range(FLASH_SIZE // PAGE)))
                self._send(ACK)
                self.log.append("WRITE UNPROTECT" if cmd == CMD_WUNP else "READOUT UNPROTECT")
                self.resets += 1
                while (yield 1)[0] != INIT:  # the chip resets into the bootloader (BOOT0 = 1)
                    pass
                self._send(ACK)
            else:  # CMD_WP, CMD_RP: protection is not emulated
                self._send(NACK)


def flash_elf(image: bytes, path: Path) -> Path:
    """A minimal ARM ELF whose one load segment is ``image`` at the flash base (what
    arm-emu boots; a chip's flash has no symbols, so arm-emu's symbol shortcuts are off)."""
    ehdr = struct.pack(
        "<4sBBBBB7xHHIIIIIHHHHHH",
        b"\x7fELF", 1, 1, 1, 0, 0,  # ELF32, little-endian, version 1, SYSV ABI
        2, 40, 1,  # ET_EXEC, EM_ARM, EV_CURRENT
        FLASH_BASE + 4, 52, 0,  # entry (informative), phoff, shoff
        0x05000200, 52, 32, 1, 40, 0, 0,  # EABI5 soft-float, ehsize, phentsize, phnum, shentsize, shnum, shstrndx
    )
    phdr = struct.pack("<8I", 1, 52 + 32, FLASH_BASE, FLASH_BASE, len(image), len(image), 5, 4)
    path.write_bytes(ehdr + phdr + image)
    return path


def boot_board(flash: bytes, *, seed: int = 1, tick_us: int = 1000):
    """arm-emu running ``flash`` from its reset vector (imported here: unicorn is heavy)."""
    from .board import ArmEmuBoard

    fd, tmp = tempfile.mkstemp(prefix="proleg-rom-flash-", suffix=".elf")
    os.close(fd)
    try:
        return ArmEmuBoard(flash_elf(bytes(flash), Path(tmp)), seed, tick_us=tick_us)
    finally:
        os.unlink(tmp)


def serve_rom(rom: RomBootloader, port: PtyPort, *, stop=lambda: False, poll_s: float = 0.002) -> bool:
    """Serve the bootloader until GO (True) or ``stop()`` (False)."""
    while not stop():
        port.poll_open()
        data = port.read() if port.is_open else b""
        if data:
            port.write(rom.feed(data))
            if rom.go_address is not None:
                return True
        else:
            port.wait(poll_s)
    return False


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m proleg.emu.arm.rom_bootloader",
        description="An emulated bluepill in its ROM serial bootloader (BOOT0 = 1) on a pseudo-terminal; "
        "GO boots arm-emu from the flash written.",
    )
    p.add_argument("--image", type=Path, help="raw flash image already on the chip (default: erased)")
    p.add_argument("--link", help="also make this path a symlink to the pty")
    p.add_argument("--extended-erase", action="store_true", help="offer EXTENDED ERASE (0x44) instead of ERASE (0x43)")
    p.add_argument("--speed", type=float, default=1.0, help="arm-emu after GO: × real time (default 1)")
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args(argv)
    try:
        rom = RomBootloader(args.image.read_bytes() if args.image else None, extended_erase=args.extended_erase)
        port = PtyPort(args.link)
    except (SimError, OSError) as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    stop = stop_on_signals()
    print(f"pty: {port.path}", flush=True)
    try:
        if serve_rom(rom, port, stop=stop):
            t0 = time.perf_counter()
            board = boot_board(rom.flash, seed=args.seed)
            print(f"GO 0x{rom.go_address:08x}: arm-emu booted the flash in {time.perf_counter() - t0:.1f} s",
                  file=sys.stderr, flush=True)
            serve_board(board, port, speed=args.speed, stop=stop)
    except SimError as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    finally:
        port.close()
    print(f"{port.stats.line()}; bootloader: {rom.summary()}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
