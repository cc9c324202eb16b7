"""I2C1 in master mode (RM0008 §26) on a bus with the shared MPU-6050 models, and I2C2.

Timing: a bit is CCR·3 (fast mode, DUTY = 0), CCR·25 (DUTY = 1) or CCR·2 (standard
mode) periods of PCLK1; START, each 9-bit byte and STOP take that many bits. Status
bits follow the reference manual's master sequences (RM0008 §26.3.3): SB (cleared by
reading SR1 then writing DR), ADDR (SR1 then SR2), TXE/BTF, AF on a NACKed address, BUSY
while the master owns the bus or a line is held low.

Master receiver (RM0008 §26.3.3, "Master receiver" and "Closing the communication"):
- After each received byte the interface gives the ACK pulse, then sets RxNE. The (N)ACK
  is decided when the byte's reception ends: with POS = 0 it is CR1.ACK at that moment;
  with POS = 1 ("the ACK bit controls the (N)ACK of the next byte received in the shift
  register") it is CR1.ACK as it was when that byte's reception began.
- A byte that completes while DR still holds an unread byte stays in the shift register:
  BTF is set and SCL is stretched (after that byte's ACK pulse) until DR is read; the
  read moves it to DR and, if it was ACKed, the slave's next byte starts. Clearing ACK
  while BTF is set therefore NACKs the byte after the held one, not the held one (the
  N > 2 sequence: BTF, ACK = 0, read N-2, BTF, STOP, read N-1, RxNE, read N).
- STOP is generated after the byte in flight, or at once when none is (BTF stretch, or
  the clock halted after a NACK). A slave whose last byte was ACKed is already driving
  the next byte's first bit when the master tries its STOP: if that bit is 0 the STOP
  never happens and the slave holds SDA (``Bus.strand``), exactly as on a real bus.

The slaves are the MPU-6050 register models (``sim_mpu6050.c``) and TCA9548A
multiplexers (``sim_tca9548a.c``), routed by ``i2cbus.c`` (``BusDevices``): one
transaction per address phase: written bytes are committed on a repeated START or STOP;
read bytes are fetched one at a time at the time of the address phase. Every STOP on the
bus (the peripheral's, or one made with the pins as GPIO) is passed on: a multiplexer
connects the channels its control register names only then (TCA9548A §8.5.4).

Bus faults: a slave that is sending a byte when the master abandons the transfer
(SWRST or PE cleared mid-read) keeps driving SDA with that byte's bits, advancing one
bit per SCL clock; it lets go after the ninth clock (it sees the NACK). While SDA is
held low no START can be generated (SB never sets, BUSY stays 1), whatever the
peripheral does: only clocking SCL (the 9-clock recovery, PB6 as GPIO open-drain)
frees the bus. ``hold_sda`` injects that state directly.

Misuse that RM0008 §26.6.1 forbids is counted, not silently accepted: a write to CR1
while START or STOP is still pending (``violations``).
"""

from __future__ import annotations

from collections.abc import Callable

from .clocks import NEVER

CR1_PE, CR1_START, CR1_STOP, CR1_ACK, CR1_POS, CR1_SWRST = 1, 1 << 8, 1 << 9, 1 << 10, 1 << 11, 1 << 15
SB, ADDR, BTF, RXNE, TXE, BERR, ARLO, AF = 1, 2, 4, 1 << 6, 1 << 7, 1 << 8, 1 << 9, 1 << 10
MSL, BUSY, TRA = 1, 2, 4


class BusDevices:
    """What answers on one of the board's buses (0 = I2C1, 1 = I2C2): the MPU-6050 and
    TCA9548A models wired there (``i2cbus.c`` in the native library)."""

    def __init__(self, native, bus: int) -> None:
        self.native = native
        self.bus = bus

    def transfer(self, addr: int, tx: bytes, nrx: int, t_us: int) -> bytes | None:
        return self.native.bus_transfer(self.bus, addr, tx, nrx, t_us)

    def stop(self) -> None:
        """A STOP condition: a multiplexer connects the channels it was told to (TCA9548A §8.5.4)."""
        self.native.lib.emu_i2c_stop(self.bus)


class Bus:
    """The two wires and who holds SDA."""

    def __init__(self, on_stop: Callable[[], None] | None = None) -> None:
        self.hold_bits: list[int] = []  # bits a stranded slave still drives on SDA
        self.scl_gpio = 1
        self.sda_gpio = 1
        self.recoveries = 0
        self.on_stop = on_stop  # the slaves see a STOP condition made with the pins as GPIO

    @property
    def sda_low(self) -> bool:
        return bool(self.hold_bits) and self.hold_bits[0] == 0

    def strand(self, byte: int) -> None:
        """A slave was cut off while sending ``byte``: it keeps driving its bits."""
        self.hold_bits = [(byte >> (7 - i)) & 1 for i in range(8)] + [1]

    def sda_master(self, level: int) -> None:
        """SDA driven by GPIO: rising while SCL is high is a STOP, which resets every slave."""
        if level and not self.sda_gpio and self.scl_gpio and not self.sda_low:
            if self.hold_bits:
                self.hold_bits = []
                self.recoveries += 1
            if self.on_stop is not None:
                self.on_stop()
        self.sda_gpio = level

    def scl(self, level: int) -> None:
        """SCL driven by GPIO: each rising edge clocks a stranded slave one bit on."""
        if level and not self.scl_gpio and self.hold_bits:
            self.hold_bits.pop(0)
            if not self.hold_bits:
                self.recoveries += 1
        self.scl_gpio = level


class I2c:
    def __init__(self, base: int, pclk1: Callable[[], int], bus: Bus | None = None, slaves=None) -> None:
        self.BASE = base
        self.pclk1 = pclk1
        self.bus = bus or Bus()
        self.slaves = slaves  # BusDevices (transfer, stop) or None: nobody on this bus
        self.violations = 0
        self.transfers = 0
        self.reset()

    def reset(self) -> None:
        self.cr1 = 0
        self.regs: dict[int, int] = {}
        self.sr1 = 0
        self.sr2 = 0
        self.sr1_read = False
        self.phase = "idle"  # idle, start, addr, tx, rx, stop
        self.done = NEVER  # cycle at which the bit/byte in flight completes
        self.addr = 0
        self.reading = False
        self.tx_buf = bytearray()
        self.tx_pending: int | None = None
        self.rx_shift: int | None = None  # byte being received (or, writing, sent)
        self.rx_start_ack = False  # CR1.ACK when the byte in flight began (for POS = 1)
        self.rx_ready: int | None = None  # a received byte held in the shift register (BTF)
        self.rx_ready_ack = False  # the (N)ACK that byte was given
        self.dr_rx = 0
        self.t_addr_us = 0
        self.rx_acked = False  # last received byte was ACKed: the slave is sending the next one

    # -- timing ---------------------------------------------------------------------
    def bit_cycles(self) -> int:
        ccr = self.regs.get(0x1C, 0)
        n = ccr & 0xFFF or 1
        per = (25 if ccr & (1 << 14) else 3) if ccr & (1 << 15) else 2
        return max(1, per * n * 72_000_000 // max(1, self.pclk1()))

    def next_event(self) -> int:
        return self.done

    def core_has_work(self) -> bool:
        """A flag is up that a polling master acts on, with no bus event of its own coming
        (SB, ADDR, BTF, RxNE, AF/BERR/ARLO, or TXE with no byte in flight while writing)."""
        if self.sr1 & (SB | ADDR | BTF | RXNE | AF | BERR | ARLO):
            return True
        return bool(self.sr1 & TXE) and self.phase == "tx" and self.done == NEVER

    # -- the slave side -------------------------------------------------------------
    def _ack_address(self, now: int) -> bool:
        if self.slaves is None:
            return False
        return self.slaves.transfer(self.addr, b"", 0, now // 72) is not None

    def _commit(self, now: int) -> None:
        if self.tx_buf and self.slaves is not None and not self.reading:
            self.slaves.transfer(self.addr, bytes(self.tx_buf), 0, now // 72)
            self.transfers += 1
        self.tx_buf = bytearray()

    def _fetch(self) -> int:
        rx = self.slaves.transfer(self.addr, b"", 1, self.t_addr_us) if self.slaves else None
        return rx[0] if rx else 0xFF

    # -- events ---------------------------------------------------------------------
    def advance(self, now: int) -> None:
        while self.done <= now:
            t, self.done = self.done, NEVER
            self._complete(t)

    def _complete(self, t: int) -> None:
        bit = self.bit_cycles()
        if self.phase == "start":
            self.sr1 |= SB
            self.sr2 |= MSL | BUSY
            self.cr1 &= ~CR1_START
            self.phase = "addr"
        elif self.phase == "addr":
            if self._ack_address(t):
                self.sr1 |= ADDR
                self.rx_acked = self.reading  # a read: the slave drives its first byte next
                if self.reading:
                    self.t_addr_us = t // 72
                    self.sr2 &= ~TRA
                else:
                    self.sr2 |= TRA
                self.phase = "rx" if self.reading else "tx"
            else:
                self.sr1 |= AF
                self.phase = "tx"
        elif self.phase == "tx":
            self.tx_buf.append(self.rx_shift if self.rx_shift is not None else 0)
            self.rx_shift = None
            if self.tx_pending is not None:
                self.rx_shift, self.tx_pending = self.tx_pending, None
                self.sr1 |= TXE
                self.done = t + 9 * bit
            else:
                self.sr1 |= BTF | TXE
                if self.cr1 & CR1_STOP:
                    self._begin_stop(t)
        elif self.phase == "rx":
            byte, self.rx_shift = self.rx_shift, None
            byte = 0xFF if byte is None else byte
            ack = self.rx_start_ack if self.cr1 & CR1_POS else bool(self.cr1 & CR1_ACK)
            self.rx_acked = ack  # the ACK pulse goes out now, before any stretch
            if self.sr1 & RXNE:  # DR still full: hold the byte, stretch SCL
                self.rx_ready, self.rx_ready_ack = byte, ack
                self.sr1 |= BTF
            else:
                self.dr_rx = byte
                self.sr1 |= RXNE
            if self.cr1 & CR1_STOP:
                self._begin_stop(t)
            elif self.rx_ready is None and ack:
                self._rx_next(t)
        elif self.phase == "stop":
            if self.slaves is not None and hasattr(self.slaves, "stop"):
                self.slaves.stop()
            self.cr1 &= ~CR1_STOP
            self.sr2 &= ~(MSL | BUSY | TRA)
            self.sr1 &= ~(TXE | (0 if self.rx_ready is not None else BTF))
            self.phase = "idle"
            if self.cr1 & CR1_START:
                self._begin_start(t)

    def _rx_next(self, t: int) -> None:
        """The slave sends its next byte (the last one was ACKed and SCL is free)."""
        self.rx_shift = self._fetch()
        self.rx_start_ack = bool(self.cr1 & CR1_ACK)
        self.done = t + 9 * self.bit_cycles()

    def _begin_start(self, now: int) -> None:
        if self.bus.sda_low:
            self.phase = "start-blocked"
            self.sr2 |= BUSY
            return
        self._commit(now)
        self.phase = "start"
        self.sr1 &= ~(BTF | TXE)
        self.done = max(now, self.done if self.done != NEVER else now) + self.bit_cycles()

    def _begin_stop(self, now: int) -> None:
        if self.phase == "rx" and self.rx_acked and self.rx_shift is None:
            nxt = self._fetch()  # the slave already drives the next byte's first bit
            if not nxt & 0x80:
                self.bus.strand(nxt)  # SDA low: the STOP cannot happen
        self._commit(now)
        self.phase = "stop"
        self.done = now + self.bit_cycles()

    def _abandon(self) -> None:
        """The peripheral is reset or disabled: a slave mid-byte is stranded."""
        if self.phase == "rx" and self.rx_shift is not None:
            self.bus.strand(self.rx_shift)
        elif self.phase == "rx" and self.rx_acked:
            self.bus.strand(self._fetch())

    # -- registers ------------------------------------------------------------------
    def read(self, off: int, now: int) -> int:
        if off == 0x00:
            return self.cr1
        if off == 0x14:
            self.sr1_read = True
            return self.sr1
        if off == 0x18:
            v = self.sr2 | (BUSY if self.bus.sda_low else 0)
            if self.sr1_read and self.sr1 & ADDR:
                self.sr1 &= ~ADDR
                if self.phase == "tx":
                    self.sr1 |= TXE
                elif self.phase == "rx":
                    self._rx_next(now)
            self.sr1_read = False
            return v
        if off == 0x10:
            v = self.dr_rx
            self.sr1 &= ~RXNE
            if self.rx_ready is not None:  # the held byte moves to DR, SCL is released
                self.sr1 &= ~BTF
                self.dr_rx, self.rx_ready = self.rx_ready, None
                self.sr1 |= RXNE
                if self.phase == "rx" and self.rx_ready_ack and self.done == NEVER:
                    self._rx_next(now)
            return v
        return self.regs.get(off, 0)

    def write(self, off: int, value: int, now: int) -> None:
        if off == 0x00:
            self._write_cr1(value, now)
        elif off == 0x10:
            self._write_dr(value & 0xFF, now)
        elif off == 0x14:
            self.sr1 &= value | ~(BERR | ARLO | AF | (1 << 11) | (1 << 12) | (1 << 14) | (1 << 15))
        else:
            self.regs[off] = value

    def _write_cr1(self, value: int, now: int) -> None:
        old = self.cr1
        if value & CR1_SWRST:
            self._abandon()
            self.reset()
            self.cr1 = CR1_SWRST
            return
        if old & (CR1_START | CR1_STOP):
            self.violations += 1  # RM0008 §26.6.1: CR1 written while START/STOP pending
        if old & CR1_PE and not value & CR1_PE:
            self._abandon()
            keep = dict(self.regs)
            self.reset()
            self.regs = keep
            self.cr1 = value
            return
        self.cr1 = value
        if not value & CR1_PE:
            return
        if value & CR1_START and not old & CR1_START:
            if self.phase == "idle" or (self.phase in ("tx", "rx", "addr") and self.done == NEVER):
                self._begin_start(now)
            # phase "stop": the START follows the STOP (see _complete)
        if value & CR1_STOP and not old & CR1_STOP:
            if self.phase == "tx" and self.done == NEVER:
                self._begin_stop(now)
            elif self.phase in ("addr",) and self.done == NEVER:
                self._begin_stop(now)
            elif self.phase == "rx" and self.done == NEVER:  # no byte in flight: BTF or NACKed
                self._begin_stop(now)

    def _write_dr(self, b: int, now: int) -> None:
        bit = self.bit_cycles()
        if self.phase == "addr" and self.sr1 & SB:
            self.sr1 &= ~SB
            self.addr = b >> 1
            self.reading = bool(b & 1)
            self.done = now + 9 * bit
            return
        if self.phase == "tx" and not self.sr1 & (ADDR | AF):
            self.sr1 &= ~BTF
            if self.done == NEVER:
                self.rx_shift = b
                self.done = now + 9 * bit
            else:
                self.tx_pending = b
                self.sr1 &= ~TXE

    def poll_blocked(self, now: int) -> None:
        """A START waiting for the bus goes out once SDA is free."""
        if self.phase == "start-blocked" and not self.bus.sda_low:
            self.phase = "idle"
            self._begin_start(now)
