"""arm-emu's TCA9548A multiplexer against the datasheet (TI SCPS207F, §8.5), driven through
the STM32 I2C1/I2C2 register models the way firmware drives them.

The model is the one host-sim and avr-emu use (``firmware_templates/hal/sim/sim_tca9548a.c``),
wired to the buses by ``emu/arm/i2cbus.c``. What the datasheet says, and each test checks:
- §8.5.2 / Table 1: the device answers at 0x70 + A2..A0, nowhere else;
- §8.5.4: one control register, written and read over I2C; bit n selects channel n,
  several at once; a read returns it; of several bytes written the last is kept;
- §8.5.4: a selected channel "becomes active after a stop condition" (not before);
- Table 2: power-up/reset default 0x00, no channel selected;
- downstream devices are on the bus exactly while their channel is connected; two
  devices answering at once drive the open-drain bus together (wired AND).
"""

from __future__ import annotations

import pytest

pytest.importorskip("unicorn")

from arm_i2c_master import CR1_ACK, CR1_PE, CR1_START, CR1_STOP, RegisterMaster  # noqa: E402
from proleg.emu.arm.i2c import ADDR, AF, BTF, RXNE, SB, TXE, Bus, BusDevices, I2c  # noqa: E402
from proleg.emu.arm.native import Native  # noqa: E402
MUX, IMU = 0x70, 0x68
WHO_AM_I, PWR_MGMT_1 = 0x75, 0x6B


class Master(RegisterMaster):
    """Firmware-like polled transfers on one I2C peripheral model, in manual time."""

    def __init__(self, native: Native, bus: int) -> None:
        devices = BusDevices(native, bus)
        self.bus = Bus(devices.stop)
        super().__init__(I2c(0x40005400 + 0x400 * bus, lambda: 36_000_000, self.bus, devices))

    def idle(self) -> None:
        self.now += 50 * 72
        self.i2c.advance(self.now)
        assert self.i2c.phase == "idle"

    def address(self, addr: int, read: bool) -> bool:
        """START (or repeated START) and the address byte: True when it was ACKed."""
        self.cr1(CR1_START)
        self.wait(SB)
        self.i2c.write(0x10, addr << 1 | int(read), self._at())
        if self.wait(ADDR | AF) & AF:
            self.i2c.write(0x14, ~AF & 0xFFFF, self.now)
            self.cr1(CR1_STOP)
            self.idle()
            return False
        return True

    def clear_addr(self) -> None:
        self.sr1()
        self.i2c.read(0x18, self._at())

    def write(self, addr: int, data: bytes, *, stop: bool = True) -> bool:
        if not self.address(addr, False):
            return False
        self.clear_addr()
        for b in data:
            self.wait(TXE)
            self.i2c.write(0x10, b, self._at())
        self.wait(BTF)
        if stop:
            self.cr1(CR1_STOP)
            self.idle()
        return True

    def read(self, addr: int, n: int) -> bytes | None:
        """n bytes, the last NACKed, then STOP (ACK cleared and STOP set while it is on the wire)."""
        if not self.address(addr, True):
            return None
        out = bytearray()
        if n == 1:
            self.cr1(clear=CR1_ACK)
            self.clear_addr()
            self.cr1(CR1_STOP)
        else:
            self.cr1(CR1_ACK)
            self.clear_addr()
        while len(out) < n:
            self.wait(RXNE)
            out.append(self.i2c.read(0x10, self._at()))
            if len(out) == n - 1:
                self.cr1(CR1_STOP, clear=CR1_ACK)
        self.idle()
        return bytes(out)

    def read_reg(self, addr: int, reg: int) -> int | None:
        if not self.write(addr, bytes([reg]), stop=False):
            return None
        r = self.read(addr, 1)
        return None if r is None else r[0]


@pytest.fixture
def native():
    n = Native()
    n.lib.sim_mpu_power_on(1)
    n.lib.emu_i2c_unwire()
    return n


def test_the_multiplexer_answers_at_its_strapped_address_only(native):
    """Table 1: 0x70 + A2..A0; here A2..A0 = 101 (0x75)."""
    native.lib.emu_i2c_add_mux(0, 0x75)
    m = Master(native, 0)
    assert m.read(0x75, 1) == b"\x00"  # Table 2: power-up default, no channel
    for other in (0x70, 0x74, 0x76, 0x77):
        assert m.read(other, 1) is None


def test_a_channel_connects_its_devices_and_only_while_its_bit_is_set(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 3)
    m = Master(native, 0)
    assert m.read_reg(IMU, WHO_AM_I) is None  # power-up: channel 3 not connected, nobody ACKs 0x68
    assert m.write(MUX, bytes([1 << 3]))
    assert m.read(MUX, 1) == bytes([1 << 3])  # the control register reads back
    assert m.read_reg(IMU, WHO_AM_I) == 0x68
    assert m.write(MUX, bytes([1 << 2]))  # another channel: the IMU on 3 is cut off
    assert m.read_reg(IMU, WHO_AM_I) is None
    assert m.write(MUX, b"\x00")
    assert m.read_reg(IMU, WHO_AM_I) is None


def test_every_byte_read_returns_the_control_register(native):
    native.lib.emu_i2c_add_mux(0, MUX)
    m = Master(native, 0)
    m.write(MUX, bytes([0xA5]))
    assert m.read(MUX, 3) == bytes([0xA5] * 3)


def test_of_several_bytes_written_the_last_is_kept(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 6)
    m = Master(native, 0)
    assert m.write(MUX, bytes([1 << 6, 1 << 1, 1 << 6 | 1 << 0]))
    assert native.lib.sim_tca_control(0, MUX) == 0x41
    assert m.read_reg(IMU, WHO_AM_I) == 0x68


def test_a_selected_channel_becomes_active_only_after_a_stop(native):
    """§8.5.4: the control register is written at once, the channel is connected at STOP:
    a repeated START to the IMU right after the select finds nobody."""
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 1)
    m = Master(native, 0)
    assert m.write(MUX, bytes([1 << 1]), stop=False)
    assert not m.address(IMU, False)  # repeated START: the channel is not active yet (that NACK ends with a STOP)
    assert native.lib.sim_tca_control(0, MUX) == 0x02
    assert m.read_reg(IMU, WHO_AM_I) == 0x68  # after the STOP it is


def test_a_stop_made_with_the_pins_as_gpio_also_connects_the_channel(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 4)
    m = Master(native, 0)
    m.write(MUX, bytes([1 << 4]), stop=False)
    m.cr1(CR1_START)  # a repeated START delivers the byte, but is no STOP
    m.wait(SB)
    assert native.lib.sim_tca_control(0, MUX) == 1 << 4 and native.lib.emu_i2c_mux_active(0, MUX) == 0
    m.cr1(clear=CR1_PE)  # the firmware gives up and frees the bus by hand
    m.bus.sda_master(0)  # SDA low while SCL is high, then released: a STOP condition
    m.bus.sda_master(1)
    assert native.lib.emu_i2c_mux_active(0, MUX) == 1 << 4


def test_several_channels_at_once_and_two_devices_at_one_address_drive_the_bus_together(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 2)
    native.lib.emu_i2c_wire(1, 0, IMU, MUX, 5)
    m = Master(native, 0)
    m.write(MUX, bytes([1 << 2]))
    assert m.write(IMU, bytes([PWR_MGMT_1, 0x01]))  # wake only the IMU on channel 2 (PLL clock)
    assert native.lib.sim_mpu_peek_slot(0, PWR_MGMT_1) == 0x01
    assert native.lib.sim_mpu_peek_slot(1, PWR_MGMT_1) == 0x40  # the one on 5 still asleep
    m.write(MUX, bytes([1 << 2 | 1 << 5]))
    assert m.read_reg(IMU, PWR_MGMT_1) == 0x01 & 0x40  # both answer: the AND of their bytes
    m.write(MUX, bytes([1 << 5]))
    assert m.read_reg(IMU, PWR_MGMT_1) == 0x40


def test_the_multiplexer_of_one_bus_does_not_switch_the_other(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 0)
    native.lib.emu_i2c_wire(1, 1, IMU, MUX, 0)
    i2c1, i2c2 = Master(native, 0), Master(native, 1)
    assert i2c1.write(MUX, b"\x01")
    assert i2c1.read_reg(IMU, WHO_AM_I) == 0x68
    assert i2c2.read_reg(IMU, WHO_AM_I) is None  # I2C2's multiplexer still at 0x00
    assert native.lib.sim_tca_control(1, MUX) == 0
    assert i2c2.write(MUX, b"\x01") and i2c2.read_reg(IMU, WHO_AM_I) == 0x68


def test_power_on_returns_every_multiplexer_to_no_channel(native):
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 7)
    m = Master(native, 0)
    m.write(MUX, bytes([0x80]))
    assert native.lib.emu_i2c_mux_active(0, MUX) == 0x80
    native.lib.emu_i2c_unwire()
    native.lib.emu_i2c_wire(0, 0, IMU, MUX, 7)
    assert native.lib.sim_tca_control(0, MUX) == 0 and native.lib.emu_i2c_mux_active(0, MUX) == 0
    assert Master(native, 0).read_reg(IMU, WHO_AM_I) is None
