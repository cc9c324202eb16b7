"""USART1 (RM0008 §27) in asynchronous 8N1 mode at the rate BRR sets.

A byte takes 10 bit times (start, 8 data, stop) each way; one bit is BRR cycles of
PCLK2 (72 MHz). Transmit: a data register and a shift register (TXE, TC). Receive: the
host's bytes arrive back to back at the baud rate; a byte that completes while RXNE is
still set is lost and sets ORE, as on the chip. The interrupt line is
(TXE·TXEIE) | (TC·TCIE) | ((RXNE|ORE)·RXNEIE).
"""

from __future__ import annotations

from collections import deque

from .clocks import NEVER

SR_ORE, SR_RXNE, SR_TC, SR_TXE = 1 << 3, 1 << 5, 1 << 6, 1 << 7
CR1_RXNEIE, CR1_TCIE, CR1_TXEIE, CR1_UE = 1 << 5, 1 << 6, 1 << 7, 1 << 13


class Usart:
    BASE = 0x40013800

    def __init__(self) -> None:
        self.host_rx: deque[int] = deque()  # host -> board, not yet on the wire
        self.host_tx = bytearray()  # board -> host, completed bytes
        self.reset()

    def reset(self) -> None:
        self.sr = SR_TXE | SR_TC
        self.cr1 = 0
        self.brr = 0
        self.dr_rx = 0
        self.tdr: int | None = None
        self.shift: int | None = None
        self.tx_done = NEVER
        self.rx_done = NEVER
        self.rx_byte = 0
        self.rx_lost = 0

    def byte_cycles(self) -> int:
        return 10 * max(16, self.brr)

    def irq(self) -> bool:
        c, s = self.cr1, self.sr
        return bool(
            (s & SR_TXE and c & CR1_TXEIE) or (s & SR_TC and c & CR1_TCIE) or (s & (SR_RXNE | SR_ORE) and c & CR1_RXNEIE)
        )

    def next_event(self) -> int:
        return min(self.tx_done, self.rx_done)

    def kick(self, now: int) -> None:
        """Start receiving the host's next byte if the line is idle."""
        if self.rx_done == NEVER and self.host_rx and self.cr1 & CR1_UE:
            self.rx_done = now + self.byte_cycles()
            self.rx_byte = self.host_rx.popleft()

    def advance(self, now: int) -> None:
        self.kick(now)
        while self.tx_done <= now or self.rx_done <= now:
            if self.tx_done <= self.rx_done:
                t = self.tx_done
                self.host_tx.append(self.shift or 0)
                self.shift, self.tdr = self.tdr, None
                if self.shift is None:
                    self.tx_done = NEVER
                    self.sr |= SR_TC
                else:
                    self.tx_done = t + self.byte_cycles()
                self.sr |= SR_TXE
            else:
                t = self.rx_done
                if self.sr & SR_RXNE:
                    self.sr |= SR_ORE
                    self.rx_lost += 1
                else:
                    self.dr_rx = self.rx_byte
                    self.sr |= SR_RXNE
                if self.host_rx:
                    self.rx_byte = self.host_rx.popleft()
                    self.rx_done = t + self.byte_cycles()
                else:
                    self.rx_done = NEVER

    def read(self, off: int, now: int) -> int:
        if off == 0x00:
            return self.sr
        if off == 0x04:
            v = self.dr_rx
            self.sr &= ~(SR_RXNE | SR_ORE)
            return v
        return {0x08: self.brr, 0x0C: self.cr1}.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x04:
            b = value & 0xFF
            self.sr &= ~SR_TC
            if self.shift is None:
                self.shift = b
                self.tx_done = now + self.byte_cycles()
            else:
                self.tdr = b
                self.sr &= ~SR_TXE
        elif off == 0x00:
            self.sr &= value | ~(SR_TC | SR_RXNE)  # rc_w0 bits
        elif off == 0x08:
            self.brr = value & 0xFFFF
        elif off == 0x0C:
            self.cr1 = value
