"""The flash program/erase controller (FPEC) and the flash page the firmware keeps its
non-volatile block in (hal_nv_*: the last 1 KiB page, 0x0800FC00).

Registers at 0x40022000 (RM0008 §3.3.3 "Embedded Flash memory"; PM0075 "STM32F10xxx Flash
memory microcontrollers programming manual" §2.3-2.4, §3): ACR (latency, prefetch: kept for
the clock set-up), KEYR, SR, CR, AR. Behaviour modelled:

- CR.LOCK is set at reset; KEY1 = 0x45670123 then KEY2 = 0xCDEF89AB unlocks it; any other
  sequence keeps the FPEC locked until the next reset (the chip also raises a bus error;
  here it is counted in ``errors``). CR writes while locked are ignored.
- Page erase: CR.PER, AR = an address in the page, CR.STRT → the page reads 0xFF; the CPU
  stalls (its flash fetches wait) for t_ERASE, 20 ms typical (DS5319 table 28).
- Programming: CR.PG, then one half-word store into the page → written if the half-word
  was erased (0xFFFF) or the value is 0; otherwise SR.PGERR and nothing written. The CPU
  stalls t_PROG, 52.5 µs typical. A byte or word store is a bus error on the chip: counted
  in ``errors``, nothing written. A store without PG writes nothing (counted).
- SR: BSY always reads 0 (the stall already waited), EOP set at the end of each operation,
  PGERR/WRPRTERR/EOP cleared by writing 1.
- The page's bytes survive ``reset()`` (a reset of any kind); they start erased (0xFF).

Only the last page is modelled: an erase elsewhere would wipe the firmware itself and is
refused with ``SimError`` (a firmware bug, not a state to emulate).
"""

from __future__ import annotations

from collections.abc import Callable

from ...errors import SimError
from .clocks import CPU_HZ

PAGE_BASE = 0x0800FC00
PAGE_SIZE = 0x400
KEY1, KEY2 = 0x45670123, 0xCDEF89AB
T_ERASE_S = 20e-3      # DS5319 table 28: t_ERASE 20 ms typ (40 ms max)
T_PROG_S = 52.5e-6     # DS5319 table 28: t_PROG 52.5 µs typ per half-word

SR_BSY, SR_PGERR, SR_WRPRTERR, SR_EOP = 1 << 0, 1 << 2, 1 << 4, 1 << 5
CR_PG, CR_PER, CR_MER, CR_STRT, CR_LOCK = 1 << 0, 1 << 1, 1 << 2, 1 << 6, 1 << 7


class Fpec:
    BASE = 0x40022000

    def __init__(self, stall: Callable[[int], None]) -> None:
        """``stall(cycles)``: the CPU waits this long (the board moves its clock on)."""
        self.stall = stall
        self.acr = 0x30
        self.page = bytearray(b"\xff" * PAGE_SIZE)
        self.page_erases = 0
        self.programs = 0
        self.errors = 0
        self.reset()

    def reset(self) -> None:
        self.cr = CR_LOCK
        self.sr = 0
        self.ar = 0
        self._key = 0  # KEY1 seen
        self._locked_out = False

    # -- registers ------------------------------------------------------------------
    def read(self, off: int, now: int) -> int:
        return {0x00: self.acr, 0x0C: self.sr, 0x10: self.cr, 0x14: self.ar, 0x1C: 0x03FFFFFC,
                0x20: 0xFFFFFFFF}.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            self.acr = value & 0x3F
        elif off == 0x04:
            self._keyr(value)
        elif off == 0x0C:
            self.sr &= ~(value & (SR_PGERR | SR_WRPRTERR | SR_EOP))
        elif off == 0x10:
            self._cr(value)
        elif off == 0x14:
            self.ar = value

    def _keyr(self, value: int) -> None:
        if self._locked_out or not self.cr & CR_LOCK:
            return
        if not self._key and value == KEY1:
            self._key = 1
        elif self._key and value == KEY2:
            self.cr &= ~CR_LOCK
            self._key = 0
        else:
            self._locked_out = True  # a wrong key: locked until reset (a bus error on the chip)
            self.errors += 1

    def _cr(self, value: int) -> None:
        if self.cr & CR_LOCK:
            return  # ignored while locked
        self.cr = value & 0x1677 | (value & CR_LOCK)
        if value & CR_STRT:
            self.cr &= ~CR_STRT
            if value & CR_MER:
                raise SimError("FPEC: mass erase would wipe the firmware (not modelled)")
            if value & CR_PER:
                page = self.ar & ~(PAGE_SIZE - 1)
                if page != PAGE_BASE:
                    raise SimError(f"FPEC: erase of page {page:#010x} would wipe the firmware "
                                   f"(only the non-volatile page {PAGE_BASE:#010x} is modelled)")
                self.page[:] = b"\xff" * PAGE_SIZE
                self.page_erases += 1
                self.sr |= SR_EOP
                self.stall(int(T_ERASE_S * CPU_HZ))

    # -- the page, mapped as MMIO ----------------------------------------------------
    def map(self, uc) -> None:
        uc.mmio_map(PAGE_BASE, PAGE_SIZE, self._page_read, None, self._page_write, None)

    def _page_read(self, uc, offset: int, size: int, _user) -> int:
        return int.from_bytes(self.page[offset:offset + size], "little")

    def _page_write(self, uc, offset: int, size: int, value: int, _user) -> None:
        if not self.cr & CR_PG or size != 2 or offset & 1:
            self.errors += 1  # no PG, or not a half-word: nothing is written
            return
        old = int.from_bytes(self.page[offset:offset + 2], "little")
        value &= 0xFFFF
        if old != 0xFFFF and value != 0:
            self.sr |= SR_PGERR
        else:
            self.page[offset:offset + 2] = value.to_bytes(2, "little")
            self.programs += 1
            self.sr |= SR_EOP
        self.stall(int(T_PROG_S * CPU_HZ))
