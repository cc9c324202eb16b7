"""The Cortex-M3 System Control Space: SysTick, NVIC and the SCB registers the HAL uses.

ARMv7-M ARM (DDI 0403E) B3.3 SysTick: the counter counts down from RVR at the core
clock (CLKSOURCE = 1) or core/8; reaching 0 sets COUNTFLAG (cleared by reading CSR or
writing CVR) and pends the SysTick exception when TICKINT = 1; writing CVR clears it
to 0. The counter is not stepped: its value is computed from the cycle it last wrapped.
NVIC: ISER/ICER, ISPR/ICPR, IPR (4 priority bits on the STM32F1). SCB: VTOR, AIRCR
(SYSRESETREQ), SHPR2/3, CCR; other words read back what was written.
"""

from __future__ import annotations

from .clocks import NEVER


class Scs:
    BASE = 0xE000E000

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.csr = 0
        self.rvr = 0
        self.base = 0  # cycle at which the counter last was 0
        self.next_wrap = NEVER
        self.systick_pending = False
        self.iser = [0] * 8
        self.ispr = [0] * 8
        self.ipr = bytearray(240)
        self.regs: dict[int, int] = {0xD08: 0, 0xD14: 0x200}  # VTOR, CCR.STKALIGN
        self.reset_request = False
        self.countflag_reads = 0

    # -- SysTick --------------------------------------------------------------------
    def _div(self) -> int:
        return 1 if self.csr & 4 else 8

    def _period(self) -> int:
        return (self.rvr + 1) * self._div()

    def cvr(self, now: int) -> int:
        if not self.csr & 1:
            return 0
        k = ((now - self.base) // self._div()) % (self.rvr + 1)
        return 0 if k == 0 else self.rvr + 1 - k

    def next_event(self) -> int:
        return self.next_wrap

    def advance(self, now: int) -> None:
        if self.next_wrap <= now:
            period = self._period()
            n = (now - self.next_wrap) // period + 1
            self.next_wrap += n * period
            self.csr |= 1 << 16
            if self.csr & 2:
                self.systick_pending = True

    def systick_priority(self) -> int:
        return self.regs.get(0xD20, 0) >> 24 & 0xF0

    def irq_priority(self, irq: int) -> int:
        return self.ipr[irq] & 0xF0

    def irq_enabled(self, irq: int) -> bool:
        return bool(self.iser[irq >> 5] >> (irq & 31) & 1)

    # -- registers ------------------------------------------------------------------
    def read(self, off: int, now: int) -> int:
        if off == 0x10:
            v = self.csr
            self.csr &= ~(1 << 16)
            return v
        if off == 0x14:
            return self.rvr
        if off == 0x18:
            return self.cvr(now)
        if off == 0x1C:
            return 0x40000000 | 9000  # CALIB: no reference clock, TENMS at 9 MHz
        if 0x100 <= off < 0x120:
            return self.iser[(off - 0x100) // 4]
        if 0x180 <= off < 0x1A0:
            return self.iser[(off - 0x180) // 4]
        if 0x200 <= off < 0x220:
            return self.ispr[(off - 0x200) // 4]
        if 0x280 <= off < 0x2A0:
            return self.ispr[(off - 0x280) // 4]
        if 0x400 <= off < 0x4F0:
            return int.from_bytes(self.ipr[off - 0x400 : off - 0x400 + 4], "little")
        if off == 0xD00:
            return 0x412FC231  # Cortex-M3 r2p1
        if off == 0xD04:
            return (1 << 26) if self.systick_pending else 0
        return self.regs.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x10:
            was = self.csr & 1
            self.csr = (self.csr & (1 << 16)) | (value & 7)
            if value & 1 and not was:
                self.base = now
                self.next_wrap = now + self._period()
            elif not value & 1:
                self.next_wrap = NEVER
        elif off == 0x14:
            self.rvr = value & 0xFFFFFF
        elif off == 0x18:
            self.csr &= ~(1 << 16)
            self.base = now
            if self.csr & 1:
                self.next_wrap = now + self._period()
        elif 0x100 <= off < 0x120:
            self.iser[(off - 0x100) // 4] |= value
        elif 0x180 <= off < 0x1A0:
            self.iser[(off - 0x180) // 4] &= ~value
        elif 0x200 <= off < 0x220:
            self.ispr[(off - 0x200) // 4] |= value
        elif 0x280 <= off < 0x2A0:
            self.ispr[(off - 0x280) // 4] &= ~value
        elif 0x400 <= off < 0x4F0:
            self.ipr[off - 0x400 : off - 0x400 + 4] = (value & 0xFFFFFFFF).to_bytes(4, "little")
        elif off == 0xD04:
            if value & (1 << 26):
                self.systick_pending = True
            if value & (1 << 25):
                self.systick_pending = False
        elif off == 0xD0C:
            if value >> 16 == 0x05FA and value & 4:
                self.reset_request = True
        else:
            self.regs[off] = value
