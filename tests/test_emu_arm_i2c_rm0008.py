"""The arm-emu I2C master receiver against the sequences of RM0008 §26.3.3.

Each test drives the register model the way firmware would (SR1/SR2/DR/CR1 accesses with
time passing between them) and checks what the slave saw: which bytes it sent, which it
was ACKed for, and whether the bus is free afterwards. A slave that is ACKed for a byte
keeps sending; one whose next bit is 0 when the master tries its STOP holds SDA low.
"""

from __future__ import annotations

import pytest

pytest.importorskip("unicorn")

from arm_i2c_master import CR1_ACK, CR1_POS, CR1_START, CR1_STOP, RegisterMaster  # noqa: E402
from proleg.emu.arm.clocks import NEVER  # noqa: E402
from proleg.emu.arm.i2c import ADDR, AF, BTF, RXNE, SB, Bus, I2c  # noqa: E402

MPU = 0x68
BYTE_US = 9 * 2.5  # 400 kHz: one 9-bit byte


class Slave:
    """An MPU-6050-like slave: sends DATA[0], DATA[1], ... one byte per fetch."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.sent = 0

    def transfer(self, addr: int, tx: bytes, nrx: int, t_us: int) -> bytes | None:
        if addr != MPU:
            return None
        if nrx == 0:
            return b""
        b = self.data[self.sent % len(self.data)]
        self.sent += 1
        return bytes([b])


class Rig(RegisterMaster):
    def __init__(self, data: bytes = bytes([0x91, 0xA2, 0xB3, 0xC4, 0xD5, 0xE6, 0x17, 0x28])) -> None:
        self.bus = Bus()
        self.slave = Slave(data)
        super().__init__(I2c(0x40005400, lambda: 36_000_000, self.bus, self.slave))

    def sleep(self, us: float) -> None:
        self.now += int(us * 72)
        self.i2c.advance(self.now)

    def address_read(self) -> None:
        self.cr1(CR1_START)
        self.wait(SB)
        self.i2c.write(0x10, MPU << 1 | 1, self._at())
        self.wait(ADDR | AF)
        assert not self.i2c.sr1 & AF

    def clear_addr(self) -> None:
        self.sr1()
        self.sr2()

    def finish(self) -> None:
        """Let the STOP go out; then the bus must be idle and free."""
        self.sleep(20)
        assert self.i2c.phase == "idle"
        assert not self.bus.sda_low and not self.bus.hold_bits


def test_one_byte_ack_cleared_before_addr_then_stop():
    """RM0008: for a single byte, ACK = 0 during EV6 (before ADDR is cleared), STOP after."""
    r = Rig()
    r.address_read()
    r.cr1(clear=CR1_ACK)
    r.clear_addr()
    r.cr1(CR1_STOP)
    r.wait(RXNE)
    assert r.dr() == 0x91
    r.finish()
    assert r.slave.sent == 1


def test_two_bytes_with_pos_nack_the_second():
    """POS = 1, ACK = 1; ADDR cleared, then ACK = 0 at once: byte 1 is still ACKed (ACK
    applies to the next byte in the shift register), byte 2 NACKed; BTF, STOP, two reads."""
    r = Rig()
    r.cr1(CR1_POS | CR1_ACK)
    r.address_read()
    r.clear_addr()
    r.cr1(clear=CR1_ACK)
    r.wait(BTF)
    assert r.i2c.sr1 & RXNE and r.i2c.rx_ready_ack is False
    r.cr1(CR1_STOP)
    assert [r.dr(), r.dr()] == [0x91, 0xA2]
    r.cr1(clear=CR1_POS)
    r.finish()
    assert r.slave.sent == 2


def test_two_bytes_without_pos_the_cleared_ack_nacks_the_first_byte():
    """The same with POS = 0: ACK is sampled when byte 1 ends, so byte 1 is NACKed and the
    slave sends nothing more (the reason RM0008 uses POS for two bytes)."""
    r = Rig()
    r.cr1(CR1_ACK)
    r.address_read()
    r.clear_addr()
    r.cr1(clear=CR1_ACK)
    r.wait(RXNE)
    r.sleep(100)
    assert not r.i2c.sr1 & BTF and r.i2c.next_event() == NEVER and r.slave.sent == 1


@pytest.mark.parametrize("n", [3, 6, 8])
@pytest.mark.parametrize("slow_us", [0, 60])
def test_n_bytes_with_btf_nack_the_last_whatever_the_core_delays(n, slow_us):
    """N > 2: read until three remain; BTF (N-2 in DR, N-1 held, SCL stretched), ACK = 0,
    read N-2 (N comes in, NACKed), BTF, STOP, read N-1, RxNE, read N. A core that is late
    by several byte times anywhere gets the same bytes and a free bus."""
    data = bytes([0x91, 0xA2, 0xB3, 0xC4, 0xD5, 0xE6, 0x87, 0x98, 0x09])
    r = Rig(data)
    r.cr1(CR1_ACK)
    r.address_read()
    r.clear_addr()
    got = []
    for _ in range(n - 3):
        r.wait(RXNE)
        r.sleep(slow_us)
        got.append(r.dr())
    r.wait(BTF)
    r.sleep(slow_us)
    r.cr1(clear=CR1_ACK)
    got.append(r.dr())
    r.wait(BTF)
    r.sleep(slow_us)
    r.cr1(CR1_STOP)
    got.append(r.dr())
    r.wait(RXNE)
    got.append(r.dr())
    r.finish()
    assert bytes(got) == data[:n] and r.slave.sent == n


def test_ack_cleared_during_btf_applies_to_the_next_byte_not_the_held_one():
    """Byte 2 is held in the shift register (BTF) and was ACKed before the stretch:
    clearing ACK now cannot NACK it; the slave sends byte 3, which gets the NACK."""
    r = Rig()
    r.cr1(CR1_ACK)
    r.address_read()
    r.clear_addr()
    r.wait(BTF)  # byte 1 in DR, byte 2 held
    assert r.slave.sent == 2 and r.i2c.rx_ready_ack is True
    r.cr1(clear=CR1_ACK)
    assert r.dr() == 0x91
    assert r.slave.sent == 3  # byte 3 started: byte 2 had been ACKed
    r.wait(BTF)
    assert r.i2c.rx_acked is False  # byte 3 NACKed: the slave let go
    r.cr1(CR1_STOP)
    assert [r.dr(), r.dr()] == [0xA2, 0xB3]
    r.finish()


def test_a_late_simple_close_acks_the_last_byte_and_the_slave_holds_sda():
    """The short close (ACK = 0 and STOP after reading byte N-1) works only while byte N is
    still in flight. Done after byte N has completed (the core was late), byte N was ACKed:
    the slave drives its next byte, whose first bit is 0, and the STOP cannot happen."""
    r = Rig(bytes([0x91, 0xA2, 0x33]))  # the byte after the last one read starts with a 0
    r.cr1(CR1_ACK)
    r.address_read()
    r.clear_addr()
    r.wait(RXNE)
    r.sleep(3 * BYTE_US)  # late: byte 2 completed and was ACKed while byte 1 sat in DR
    assert r.i2c.sr1 & BTF
    r.cr1(CR1_STOP, clear=CR1_ACK)
    assert r.dr() == 0x91
    assert r.dr() == 0xA2
    r.sleep(20)
    assert r.bus.sda_low  # the stranded slave: only 9 SCL clocks (bus recovery) free it
    r.cr1(CR1_START)
    r.sleep(50)
    assert not r.i2c.sr1 & SB and r.sr2() & 2  # no START while SDA is low: BUSY


def test_the_simple_close_in_time_nacks_the_last_byte():
    """The same short close done while byte N is on the wire: NACKed, bus free."""
    r = Rig()
    r.cr1(CR1_ACK)
    r.address_read()
    r.clear_addr()
    r.wait(RXNE)
    assert r.dr() == 0x91
    r.cr1(CR1_STOP, clear=CR1_ACK)
    r.wait(RXNE)
    assert r.dr() == 0xA2
    r.finish()
    assert r.slave.sent == 2
