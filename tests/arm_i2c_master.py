"""Firmware-like register access to one arm-emu STM32 I2C peripheral model, in manual time:
the part the RM0008 sequence tests (test_emu_arm_i2c_rm0008.py) and the multiplexer tests
(test_emu_arm_mux.py) share. Time is in core cycles at 72 MHz; every access first lets the
model catch up to ``now``."""

from __future__ import annotations

from proleg.emu.arm.clocks import NEVER
from proleg.emu.arm.i2c import I2c

CR1_PE, CR1_START, CR1_STOP, CR1_ACK, CR1_POS = 1, 1 << 8, 1 << 9, 1 << 10, 1 << 11


class RegisterMaster:
    def __init__(self, i2c: I2c) -> None:
        self.i2c = i2c
        self.now = 0
        self.i2c.write(0x1C, (1 << 15) | 30, 0)  # fast mode, the HAL's CCR at 400 kHz
        self.i2c.write(0x00, CR1_PE, 0)

    def _at(self) -> int:
        self.i2c.advance(self.now)
        return self.now

    def cr1(self, set_: int = 0, clear: int = 0) -> None:
        v = self.i2c.read(0x00, self._at())
        self.i2c.write(0x00, (v & ~clear) | set_, self.now)

    def sr1(self) -> int:
        return self.i2c.read(0x14, self._at())

    def sr2(self) -> int:
        return self.i2c.read(0x18, self._at())

    def dr(self) -> int:
        return self.i2c.read(0x10, self._at())

    def wait(self, mask: int) -> int:
        """Poll SR1 until a bit of mask is set (its value); fail if nothing on the bus could set it."""
        while not (v := self.sr1()) & mask:
            nxt = self.i2c.next_event()
            assert nxt != NEVER, f"SR1 {v:#x}: the bus stopped, {mask:#x} never sets"
            self.now = max(self.now + 1, nxt)
        return v
