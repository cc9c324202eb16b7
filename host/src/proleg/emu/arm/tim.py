"""General-purpose timers TIM2-TIM4 as PWM generators (RM0008 §15).

Modelled: PSC, ARR, CCR1-4 with their preload (CCMRx.OCxPE: a new CCR takes effect at
the next update event, i.e. at the end of the running PWM period), CCER.CCxE, CR1.CEN,
EGR.UG (immediate update). The duty of a channel is CCR/(ARR+1), clamped to 1, in
PWM mode 1 (OCxM = 110) with the output enabled; 0 otherwise. The counter is not
stepped: its phase is computed from the time CEN was set.
"""

from __future__ import annotations


class Timer:
    def __init__(self, base: int, clock_hz) -> None:
        self.BASE = base
        self.clock_hz = clock_hz  # callable: the timer kernel clock now
        self.reset()

    def reset(self) -> None:
        self.regs: dict[int, int] = {0x2C: 0xFFFF}
        self.active = [0, 0, 0, 0]  # CCR values in effect
        self.pending: list[tuple[int, int] | None] = [None] * 4  # (value, write cycle)
        self.start = 0

    def _period_cycles(self) -> int:
        counts = (self.regs.get(0x28, 0) + 1) * (self.regs.get(0x2C, 0) + 1)
        return max(1, counts * 72_000_000 // max(1, self.clock_hz()))

    def _settle(self, ch: int, now: int) -> None:
        p = self.pending[ch]
        if p is None:
            return
        period = self._period_cycles()
        if not self.regs.get(0x00, 0) & 1:
            return
        if (now - self.start) // period > (p[1] - self.start) // period:
            self.active[ch] = p[0]
            self.pending[ch] = None

    def read(self, off: int, now: int) -> int:
        if 0x34 <= off <= 0x40:
            ch = (off - 0x34) // 4
            p = self.pending[ch]
            return p[0] if p else self.active[ch]
        return self.regs.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if 0x34 <= off <= 0x40:
            ch = (off - 0x34) // 4
            self._settle(ch, now)
            if self._preload(ch) and self.regs.get(0x00, 0) & 1:
                self.pending[ch] = (value & 0xFFFF, now)
            else:
                self.active[ch] = value & 0xFFFF
                self.pending[ch] = None
            return
        if off == 0x14 and value & 1:  # EGR.UG
            for ch in range(4):
                if self.pending[ch] is not None:
                    self.active[ch] = self.pending[ch][0]
                    self.pending[ch] = None
            self.start = now
            return
        if off == 0x00 and value & 1 and not self.regs.get(0x00, 0) & 1:
            self.start = now
        self.regs[off] = value

    def _preload(self, ch: int) -> bool:
        ccmr = self.regs.get(0x18 if ch < 2 else 0x1C, 0)
        return bool((ccmr >> (8 * (ch & 1))) & 0x08)

    def duty_permyriad(self, ch: int, now: int) -> int:
        """Channel ch (0-based) duty in 1/10000, as the pin drives it now."""
        self._settle(ch, now)
        ccmr = self.regs.get(0x18 if ch < 2 else 0x1C, 0)
        ocm = (ccmr >> (8 * (ch & 1) + 4)) & 7
        if not self.regs.get(0x00, 0) & 1 or not (self.regs.get(0x20, 0) >> (4 * ch)) & 1 or ocm != 6:
            return 0
        arr = self.regs.get(0x2C, 0) + 1
        return min(10000, self.active[ch] * 10000 // arr)
