"""The arm-emu board's peripheral models and cycle estimate, each against the manual."""

from __future__ import annotations

import pytest

pytest.importorskip("unicorn")

from proleg.emu.arm.clocks import Iwdg, Rcc  # noqa: E402
from proleg.emu.arm.i2c import Bus, I2c  # noqa: E402
from proleg.emu.arm.scs import Scs  # noqa: E402
from proleg.emu.arm.timing import cycle_table, instruction_cost  # noqa: E402
from proleg.emu.arm.usart import Usart  # noqa: E402


@pytest.mark.parametrize(
    ("hw1", "hw2", "cost"),
    [
        (0x2005, 0, (1, 1)),  # movs r0, #5
        (0x6953, 0, (2, 1)),  # ldr r3, [r2, #20]
        (0xB570, 0, (5, 1)),  # push {r4, r5, r6, lr}
        (0xBD70, 0, (5, 1)),  # pop {r4, r5, r6, pc}
        (0xE8BD, 0x87F0, (9, 2)),  # ldmia.w sp!, {r4-r10, pc}
        (0xF8D2, 0x0D04, (2, 2)),  # ldr.w r0, [r2, #3332]
        (0xFBB2, 0xF2F1, (7, 2)),  # udiv r2, r2, r1
        (0xFB02, 0x3000, (2, 2)),  # mla r0, r2, r0, r3
        (0xF7FF, 0xFF9A, (1, 2)),  # bl (the branch refill is counted per block)
    ],
)
def test_instruction_costs_follow_the_cortex_m3_trm(hw1, hw2, cost):
    assert instruction_cost(hw1, hw2) == cost


def test_the_cycle_table_steps_over_32_bit_instructions():
    image = bytes.fromhex("0520" "b2fbf1f2" "7047")  # movs; udiv; bx lr
    assert cycle_table(image) == [0, 1, 8, 8, 9]  # halfword 2 is inside the udiv: no cost of its own


def test_systick_countflag_is_clear_on_read_and_survives_the_interrupt():
    s = Scs()
    s.write(0x14, 71999, 0)  # 1 ms at 72 MHz
    s.write(0x18, 0, 0)
    s.write(0x10, 7, 0)
    assert s.cvr(1) == 71999 and s.cvr(72000) == 0 and s.cvr(72001) == 71999
    s.advance(72000)
    assert s.systick_pending
    s.systick_pending = False  # the handler was taken: COUNTFLAG is still set
    assert s.read(0x10, 72010) & (1 << 16)
    assert not s.read(0x10, 72011) & (1 << 16)


def test_usart_bytes_take_ten_bit_times_and_an_unread_byte_is_overrun():
    u = Usart()
    u.write(0x08, 625, 0)  # 115200 Bd at 72 MHz
    u.write(0x0C, 1 << 13 | 1 << 2 | 1 << 3, 0)
    u.host_rx.extend(b"ab")
    u.kick(0)
    u.advance(6249)
    assert not u.sr & (1 << 5)
    u.advance(6250)
    assert u.sr & (1 << 5) and u.dr_rx == ord("a")
    u.advance(12500)  # "b" completes while "a" is unread
    assert u.sr & (1 << 3) and u.rx_lost == 1
    u.write(0x04, 0x55, 20000)
    u.advance(26249)
    assert u.host_tx == b""
    u.advance(26250)
    assert u.host_tx == b"\x55"


def test_i2c_fast_mode_bit_is_three_ccr_periods_of_pclk1():
    rcc = Rcc()
    rcc.write(0x04, (4 << 8) | 2, 0)  # PLL, APB1 /2
    i2c = I2c(0x40005400, lambda: rcc.pclk1)
    i2c.write(0x1C, (1 << 15) | 30, 0)  # the HAL's CCR at 400 kHz
    assert i2c.bit_cycles() * 400_000 == 72_000_000 // 1  # 2.5 µs = 180 cycles


def test_a_stranded_slave_lets_go_after_at_most_nine_clocks_or_a_stop():
    bus = Bus()
    bus.strand(0x00)
    for _ in range(8):
        assert bus.sda_low
        bus.scl(0)
        bus.scl(1)
    assert not bus.hold_bits or not bus.sda_low
    bus.scl(0)
    bus.scl(1)
    assert bus.hold_bits == [] and bus.recoveries == 1


def test_iwdg_period_is_reload_times_prescaler_over_lsi():
    w = Iwdg()
    w.write(0x00, 0x5555, 0)
    w.write(0x04, 1, 0)  # /8
    w.write(0x08, 249, 0)
    w.write(0x00, 0xCCCC, 100)
    assert w.next_event() == 100 + 250 * 8 * 72_000_000 // 40_000  # 50 ms
    w.write(0x04, 6, 200)  # locked again after the start: ignored
    assert w.pr == 1


def test_rcc_csr_flags_survive_a_reset_until_rmvf():
    rcc = Rcc()
    assert rcc.read(0x24, 0) == (1 << 27) | (1 << 26)  # power-on
    rcc.write(0x24, 1 << 24, 0)
    rcc.system_reset("watchdog")
    assert rcc.read(0x24, 0) == (1 << 29) | (1 << 26)
