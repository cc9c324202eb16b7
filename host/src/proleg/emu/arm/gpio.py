"""GPIO ports A and B (RM0008 §9.2): CRL/CRH, IDR, ODR, BSRR, BRR.

What the emulator needs from the pins: whether a PWM pin is in alternate-function
mode (else the MOSFET gate is low: the board's gate pull-down), and the I2C lines PB6
(SCL) and PB7 (SDA) when firmware bit-bangs them as open-drain outputs for a bus
recovery. Input levels: a pin reads its output latch when driven, the bus level for
PB6/PB7, and high (pull-up) otherwise.
"""

from __future__ import annotations

from collections.abc import Callable


class Gpio:
    def __init__(self, base: int, on_change: Callable[[], None] | None = None) -> None:
        self.BASE = base
        self.on_change = on_change
        self.external: Callable[[int], int | None] = lambda pin: None
        self.reset()

    def reset(self) -> None:
        self.crl = 0x44444444
        self.crh = 0x44444444
        self.odr = 0

    def mode(self, pin: int) -> int:
        """The 4-bit CNF:MODE nibble of a pin."""
        return ((self.crh if pin >= 8 else self.crl) >> (4 * (pin & 7))) & 0xF

    def is_af_output(self, pin: int) -> bool:
        m = self.mode(pin)
        return m & 3 != 0 and m & 8 != 0

    def is_gp_output(self, pin: int) -> bool:
        m = self.mode(pin)
        return m & 3 != 0 and m & 8 == 0

    def idr(self) -> int:
        v = 0
        for pin in range(16):
            ext = self.external(pin)
            if ext is not None:
                level = ext
            elif self.is_gp_output(pin):
                level = (self.odr >> pin) & 1
            else:
                level = 1
            v |= level << pin
        return v

    def read(self, off: int, now: int) -> int:
        return {0x00: self.crl, 0x04: self.crh, 0x08: self.idr(), 0x0C: self.odr}.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            self.crl = value
        elif off == 0x04:
            self.crh = value
        elif off == 0x0C:
            self.odr = value & 0xFFFF
        elif off == 0x10:
            self.odr = (self.odr | (value & 0xFFFF)) & ~(value >> 16) & 0xFFFF
            self.odr |= value & 0xFFFF
        elif off == 0x14:
            self.odr &= ~value & 0xFFFF
        else:
            return
        if self.on_change:
            self.on_change()
