"""The arm-emu bxCAN model against RM0008 (rev 21) chapter 24: modes, bit timing, transmit
mailboxes and their priority, FIFO 0, the filter banks and the interrupt lines."""

from __future__ import annotations

import pytest

from proleg.emu.arm.bxcan import FRAME_BITS, JOIN_BITS, RX0_IRQ, TX_IRQ, BxCan
from proleg.emu.arm.clocks import CPU_HZ

MCR, MSR, TSR, RF0R, IER, BTR = 0x00, 0x04, 0x08, 0x0C, 0x14, 0x1C
FMR, FM1R, FS1R, FFA1R, FA1R = 0x200, 0x204, 0x20C, 0x214, 0x21C
BTR_500K = 0x011E0003  # 36 MHz PCLK1: BRP 4, TS1 15, TS2 2, SJW 2 -> 500 kbit/s
PCLK1 = 36_000_000
BIT = CPU_HZ * 72 // PCLK1  # cycles per bit at 500 kbit/s
FRAME = FRAME_BITS * BIT


def _tir(mb: int) -> int:
    return 0x180 + 0x10 * mb


def _on_bus(txfp: bool = False, mask_id: int | None = None) -> tuple[BxCan, int]:
    """A controller initialised at 500 kbit/s (filter bank 0: 32-bit mask passing ``mask_id``,
    or everything), out of initialisation and synchronised; returns it and the time."""
    c = BxCan(lambda: PCLK1)
    c.write(MCR, 0x1, 0)
    c.write(BTR, BTR_500K, 0)
    c.write(FMR, 1, 0)
    c.write(FS1R, 1, 0)
    c.write(0x240, (mask_id or 0) << 21, 0)
    c.write(0x244, (0x7FF << 21 | 6) if mask_id is not None else 0, 0)
    c.write(FA1R, 1, 0)
    c.write(FMR, 0, 0)
    c.write(MCR, 0x4 if txfp else 0, 0)
    now = JOIN_BITS * BIT
    c.advance(now)
    assert not c.read(MSR, now) & 1
    return c, now


def _queue(c: BxCan, mb: int, ident: int, data: bytes, now: int) -> None:
    c.write(_tir(mb) + 4, len(data), now)
    c.write(_tir(mb) + 8, int.from_bytes(data[:4].ljust(4, b"\0"), "little"), now)
    c.write(_tir(mb) + 12, int.from_bytes(data[4:8].ljust(4, b"\0"), "little"), now)
    c.write(_tir(mb), ident << 21 | 1, now)


def test_reset_state_is_asleep_with_three_empty_mailboxes():
    c = BxCan(lambda: PCLK1)
    assert c.read(MCR, 0) == 0x00010002  # SLEEP, DBF (§24.9.2 reset value)
    assert c.read(MSR, 0) & 0x3 == 0x2  # SLAK
    tsr = c.read(TSR, 0)
    assert tsr >> 26 & 7 == 7 and tsr >> 24 & 3 == 0  # TME0..2, CODE = mailbox 0
    assert c.read(RF0R, 0) == 0 and c.irqs() == []


def test_initialisation_request_is_acknowledged_and_only_then_is_btr_writable():
    c = BxCan(lambda: PCLK1)
    c.write(BTR, BTR_500K, 0)
    assert c.read(BTR, 0) == 0x01230000  # ignored outside initialisation
    c.write(MCR, 0x1, 0)
    assert c.read(MSR, 0) & 0x3 == 0x1  # INAK, out of sleep
    c.write(BTR, BTR_500K, 0)
    assert c.read(BTR, 0) == BTR_500K and c.bitrate == pytest.approx(500_000)


def test_leaving_initialisation_takes_eleven_recessive_bits():
    c = BxCan(lambda: PCLK1)
    c.write(MCR, 0x1, 0)
    c.write(BTR, BTR_500K, 0)
    c.write(MCR, 0x0, 100)
    assert c.read(MSR, 100) & 1  # still INAK: synchronising
    c.advance(100 + JOIN_BITS * BIT - 1)
    assert c.read(MSR, 0) & 1
    c.advance(100 + JOIN_BITS * BIT)
    assert not c.read(MSR, 0) & 1 and c.on_bus


def test_a_frame_takes_its_bit_times_then_sets_rqcp_txok_and_frees_the_mailbox():
    c, now = _on_bus()
    _queue(c, 0, 0x123, b"\x01\x02\x03", now)
    tsr = c.read(TSR, now)
    assert not tsr & (1 << 26) and tsr >> 24 & 3 == 1  # mailbox 0 busy, CODE names mailbox 1
    c.advance(now + FRAME - 1)
    assert c.host_tx == []
    c.advance(now + FRAME)
    assert c.host_tx == [(0x123, b"\x01\x02\x03")]
    tsr = c.read(TSR, now + FRAME)
    assert tsr & 0x3 == 0x3 and tsr & (1 << 26)  # RQCP0, TXOK0, TME0
    c.write(TSR, 1, now + FRAME)  # RQCP0 is write-1-to-clear and takes TXOK0 with it
    assert c.read(TSR, now + FRAME) & 0xFF == 0


def test_without_txfp_the_lowest_identifier_goes_first_with_it_in_request_order():
    for txfp, expected in ((False, [0x100, 0x200, 0x300]), (True, [0x300, 0x100, 0x200])):
        c, now = _on_bus(txfp)
        c.host_rx.append((0x001, b"busy"))  # the host holds the bus while all three are queued
        c.kick(now)
        for mb, ident in enumerate((0x300, 0x100, 0x200)):
            _queue(c, mb, ident, b"x", now)
        c.advance(now + 4 * FRAME)
        assert [i for i, _ in c.host_tx] == expected, f"TXFP={txfp}"


def test_transmit_interrupt_follows_rqcp_when_tmeie_is_set():
    c, now = _on_bus()
    c.write(IER, 1, now)
    _queue(c, 0, 0x10, b"", now)
    assert TX_IRQ not in c.irqs()
    c.advance(now + FRAME)
    assert TX_IRQ in c.irqs()
    c.write(TSR, 1, now + FRAME)
    assert TX_IRQ not in c.irqs()


def test_abort_request_empties_a_mailbox_that_has_not_reached_the_bus():
    c, now = _on_bus()
    _queue(c, 0, 0x10, b"a", now)  # goes on the bus at once
    _queue(c, 1, 0x20, b"b", now)  # waits
    c.write(TSR, 1 << 15, now)  # ABRQ1
    tsr = c.read(TSR, now)
    assert tsr & (1 << 27) and tsr & (1 << 8) and not tsr & (1 << 9)  # TME1, RQCP1, not TXOK1
    c.advance(now + 3 * FRAME)
    assert [i for i, _ in c.host_tx] == [0x10]


def test_a_queued_mailbox_is_write_protected():
    c, now = _on_bus()
    _queue(c, 0, 0x10, b"a", now)
    c.write(_tir(0) + 8, 0xFFFFFFFF, now)
    c.advance(now + FRAME)
    assert c.host_tx == [(0x10, b"a")]


def test_fifo0_holds_three_messages_then_overruns_and_rfom0_releases_the_oldest():
    c, now = _on_bus()
    c.write(IER, 2, now)  # FMPIE0
    for k in range(4):
        c.host_rx.append((0x100 + k, bytes([k] * 8)))
    c.kick(now)
    c.advance(now + 4 * FRAME)
    rf = c.read(RF0R, 0)
    assert rf & 3 == 3 and rf & (1 << 3) and rf & (1 << 4)  # FMP0 = 3, FULL0, FOVR0
    assert RX0_IRQ in c.irqs()
    assert c.read(0x1B0, 0) >> 21 == 0x100 and c.read(0x1B4, 0) & 0xF == 8
    assert c.read(0x1B8, 0) == 0  # data bytes 0..3 of message 0
    ids = []
    for _ in range(3):
        ids.append(c.read(0x1B0, 0) >> 21)
        c.write(RF0R, 1 << 5, 0)
    assert ids == [0x100, 0x101, 0x103]  # RFLM = 0: the fourth overwrote the last
    assert c.read(RF0R, 0) & 3 == 0 and RX0_IRQ not in c.irqs()


def test_a_32_bit_mask_filter_passes_its_identifier_only():
    c, now = _on_bus(mask_id=0x100)
    c.host_rx.extend([(0x101, b"no"), (0x100, b"yes"), (0x110, b"no")])
    c.kick(now)
    c.advance(now + 3 * FRAME)
    assert c.read(RF0R, 0) & 3 == 1 and c.dropped_by_filter == 2


def test_list_and_16_bit_filters_and_fifo_assignment():
    c = BxCan(lambda: PCLK1)
    c.write(MCR, 0x1, 0)
    c.write(BTR, BTR_500K, 0)
    c.write(FMR, 1, 0)
    c.write(FM1R, 0b011, 0)  # banks 0, 1 list mode; bank 2 mask
    c.write(FS1R, 0b001, 0)  # bank 0 32-bit, banks 1, 2 16-bit
    c.write(FFA1R, 0b010, 0)  # bank 1 -> FIFO 1
    c.write(0x240, 0x201 << 21, 0)
    c.write(0x244, 0x202 << 21, 0)
    c.write(0x248, (0x301 << 5) | (0x302 << 5) << 16, 0)
    c.write(0x24C, 0, 0)
    c.write(0x250, (0x400 << 5) | (0x7F0 << 5) << 16, 0)  # 0x400..0x40F
    c.write(0x254, 0xFFFF << 16 | 0xFFFF, 0)  # id 0x7FF with RTR+IDE+EXID all 1: matches nothing standard
    c.write(FA1R, 0b111, 0)
    c.write(FMR, 0, 0)
    c.write(MCR, 0, 0)
    c.advance(JOIN_BITS * BIT)
    frames = [0x201, 0x202, 0x203, 0x301, 0x302, 0x40A, 0x41A]
    c.host_rx.extend((i, b"") for i in frames)
    now = JOIN_BITS * BIT
    c.kick(now)
    for k in range(len(frames)):
        c.advance(now + (k + 1) * FRAME)
        while c.read(RF0R, 0) & 3:  # keep FIFO 0 from overrunning
            c.write(RF0R, 1 << 5, 0)
    assert c.fifo1_taken == 2 and c.dropped_by_filter == 2  # 0x301, 0x302 to FIFO 1; 0x203, 0x41A nowhere


def test_no_reception_while_the_filters_are_in_initialisation():
    c, now = _on_bus()
    c.write(FMR, 1, now)
    c.host_rx.append((0x100, b"x"))
    c.kick(now)
    c.advance(now + FRAME)
    assert c.read(RF0R, 0) & 3 == 0


def test_the_lower_identifier_wins_arbitration_on_the_shared_bus():
    c, now = _on_bus()
    c.write(MCR, 0x1, now)  # hold both frames until the bus is joined again
    c.host_rx.append((0x080, b"host"))
    c.write(MCR, 0, now)
    _queue(c, 0, 0x100, b"mine", now)
    c.advance(now + JOIN_BITS * BIT + FRAME)
    assert c.read(RF0R, 0) & 3 == 1 and c.host_tx == []  # the host's 0x080 went first
    c.advance(now + JOIN_BITS * BIT + 2 * FRAME)
    assert c.host_tx == [(0x100, b"mine")]
