"""RCC (with the RCC_CSR reset flags), FLASH_ACR and the independent watchdog (IWDG).

RM0008 rev 21: RCC §7.3 (CR, CFGR, APBxENR, CSR), IWDG §19. The HSE crystal and the
PLL report ready as soon as they are switched on (the real ones take ~1 ms and ~200 µs;
the HAL only polls the ready bits). The LSI clocking the IWDG is taken at its typical
40 kHz (datasheet DS5319 table 24: 30-60 kHz): the watchdog period is
(RLR+1)·4·2^PR / 40 kHz. IWDG_SR's update bits read 0 (the real PVU/RVU clear within
a few LSI periods).
"""

from __future__ import annotations

CPU_HZ = 72_000_000
LSI_HZ = 40_000
NEVER = 1 << 62

# RCC_CSR reset flags (RM0008 §7.3.10)
CSR_LPWRRSTF = 1 << 31
CSR_WWDGRSTF = 1 << 30
CSR_IWDGRSTF = 1 << 29
CSR_SFTRSTF = 1 << 28
CSR_PORRSTF = 1 << 27
CSR_PINRSTF = 1 << 26
CSR_RMVF = 1 << 24

RESET_FLAGS = {
    "power-on": CSR_PORRSTF | CSR_PINRSTF,
    "external": CSR_PINRSTF,
    "watchdog": CSR_IWDGRSTF | CSR_PINRSTF,
    "software": CSR_SFTRSTF | CSR_PINRSTF,
}


class Rcc:
    BASE = 0x40021000

    def __init__(self) -> None:
        self.csr_flags = RESET_FLAGS["power-on"]
        self.csr_reads = 0
        self.csr_last_read = 0  # what the firmware last saw in RCC_CSR
        self.reset()

    def reset(self) -> None:
        self.cr = 0x83  # HSION, HSIRDY, HSITRIM = 16
        self.cfgr = 0
        self.regs: dict[int, int] = {}
        self.csr_low = 0  # LSION, LSIRDY

    def system_reset(self, cause: str) -> None:
        self.csr_flags |= RESET_FLAGS[cause]
        self.reset()

    @property
    def sysclk(self) -> int:
        return CPU_HZ if (self.cfgr >> 2) & 3 == 2 else 8_000_000

    @property
    def pclk1(self) -> int:
        ppre1 = (self.cfgr >> 8) & 7
        return self.sysclk >> (ppre1 - 3) if ppre1 >= 4 else self.sysclk

    def read(self, off: int, now: int) -> int:
        if off == 0x00:
            return self.cr
        if off == 0x04:
            return self.cfgr
        if off == 0x24:
            self.csr_reads += 1
            self.csr_last_read = self.csr_flags | self.csr_low
            return self.csr_last_read
        return self.regs.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            v = (value & 0x010D0001) | 0x80  # HSEON, CSSON, HSEBYP, PLLON, HSION; trim
            v |= (v & (1 << 16)) << 1 | (v & (1 << 24)) << 1 | (v & 1) << 1  # ready flags
            self.cr = v
        elif off == 0x04:
            self.cfgr = (value & ~0xC) | ((value & 3) << 2)  # SWS follows SW
        elif off == 0x24:
            if value & CSR_RMVF:
                self.csr_flags = 0
            self.csr_low = (value & 1) | ((value & 1) << 1)
        else:
            self.regs[off] = value


class Flash:
    BASE = 0x40022000

    def __init__(self) -> None:
        self.acr = 0x30

    def read(self, off: int, now: int) -> int:
        return self.acr if off == 0 else 0

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0:
            self.acr = value & 0x3F


class Iwdg:
    """Independent watchdog: once started (KR = 0xCCCC) only a reset stops it."""

    BASE = 0x40003000

    def __init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        self.running = False
        self.unlocked = False
        self.pr = 0
        self.rlr = 0xFFF
        self.expiry = NEVER
        self.reloads = 0

    def period_cycles(self) -> int:
        return (self.rlr + 1) * (4 << self.pr) * (CPU_HZ // LSI_HZ)

    def read(self, off: int, now: int) -> int:
        return {0x04: self.pr, 0x08: self.rlr}.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            key = value & 0xFFFF
            if key == 0x5555:
                self.unlocked = True
            elif key == 0xCCCC:
                self.running = True
                self.unlocked = False
                self.expiry = now + self.period_cycles()
            elif key == 0xAAAA:
                self.unlocked = False
                self.reloads += 1
                if self.running:
                    self.expiry = now + self.period_cycles()
        elif off == 0x04 and self.unlocked:
            self.pr = value & 7
        elif off == 0x08 and self.unlocked:
            self.rlr = value & 0xFFF

    def next_event(self) -> int:
        return self.expiry if self.running else NEVER
