"""The emulated STM32F103 ROM serial bootloader byte for byte against ST AN3155, and the
flash tool command on a pseudo-terminal (stm32flash itself: tests/test_flash_e2e.py)."""

from __future__ import annotations

import os
import struct

import pytest

from proleg.emu.arm.elf import read_elf
from proleg.emu.arm.rom_bootloader import (
    ACK,
    FLASH_BASE,
    FLASH_SIZE,
    NACK,
    OPTION_BASE,
    RomBootloader,
    flash_elf,
)
from proleg.firmware.boards import load_board
from proleg.firmware.flash import choose_method, flash_command, is_pseudo_terminal


def cmd(c: int) -> bytes:
    return bytes([c, c ^ 0xFF])


def addr(a: int) -> bytes:
    raw = struct.pack(">I", a)
    return raw + bytes([raw[0] ^ raw[1] ^ raw[2] ^ raw[3]])


def xor(data: bytes) -> int:
    x = 0
    for b in data:
        x ^= b
    return x


def synced(**kw) -> RomBootloader:
    rom = RomBootloader(**kw)
    assert rom.feed(b"\x7f") == bytes([ACK])
    return rom


def write(rom: RomBootloader, a: int, data: bytes) -> bytes:
    out = rom.feed(cmd(0x31)) + rom.feed(addr(a))
    return out + rom.feed(bytes([len(data) - 1]) + data + bytes([xor(bytes([len(data) - 1]) + data)]))


def read(rom: RomBootloader, a: int, n: int) -> bytes:
    out = rom.feed(cmd(0x11)) + rom.feed(addr(a)) + rom.feed(bytes([n - 1, (n - 1) ^ 0xFF]))
    assert out[:3] == bytes([ACK, ACK, ACK]), out.hex()
    return out[3:]


def test_nothing_is_answered_before_the_autobaud_byte():
    rom = RomBootloader()
    assert rom.feed(cmd(0x00)) == b""  # the USART has no baud rate yet
    assert rom.feed(b"\x7f") == bytes([ACK])
    assert rom.feed(b"\x7f\x7f") == bytes([NACK])  # a second 0x7F is a command byte: bad complement


def test_get_version_and_id_are_those_of_a_medium_density_f103():
    rom = synced()
    assert rom.feed(cmd(0x00)) == bytes([ACK, 11, 0x22, 0x00, 0x01, 0x02, 0x11, 0x21, 0x31, 0x43, 0x63, 0x73, 0x82, 0x92, ACK])
    assert rom.feed(cmd(0x01)) == bytes([ACK, 0x22, 0x00, 0x00, ACK])
    assert rom.feed(cmd(0x02)) == bytes([ACK, 0x01, 0x04, 0x10, ACK])
    assert rom.feed(cmd(0x44)) == bytes([NACK])  # not offered: this bootloader has ERASE (0x43)
    ext = synced(extended_erase=True)
    assert 0x44 in ext.feed(cmd(0x00)) and 0x43 not in ext.commands


def test_a_byte_at_a_time_is_the_same_conversation():
    whole, bytewise = synced(), synced()
    msg = cmd(0x31) + addr(FLASH_BASE) + bytes([3, 1, 2, 3, 4, 3 ^ 1 ^ 2 ^ 3 ^ 4]) + cmd(0x11) + addr(FLASH_BASE) + bytes([3, 0xFC])
    assert b"".join(bytewise.feed(bytes([b])) for b in msg) == whole.feed(msg)
    assert whole.flash[:4] == bytes([1, 2, 3, 4])


def test_write_needs_erased_flash_as_the_chip_does():
    rom = synced()
    assert write(rom, FLASH_BASE + 0x100, b"\x12\x34\x56\x78") == bytes([ACK, ACK, ACK])
    assert read(rom, FLASH_BASE + 0x100, 4) == b"\x12\x34\x56\x78"
    # programming a half-word that is not erased: PGERR on the chip, NACK here, flash unchanged
    assert write(rom, FLASH_BASE + 0x100, b"\x00\x00\x00\x01")[-1] == NACK
    assert rom.flash[0x100:0x104] == b"\x12\x34\x56\x78"
    # page erase (one page: N = 0, page 0, checksum)
    assert rom.feed(cmd(0x43)) + rom.feed(bytes([0, 0, 0])) == bytes([ACK, ACK])
    assert rom.flash[:1024] == b"\xff" * 1024
    assert write(rom, FLASH_BASE + 0x100, b"\x00\x00\x00\x01")[-1] == ACK


def test_bad_checksums_complements_and_addresses_are_refused():
    rom = synced()
    assert rom.feed(bytes([0x11, 0x11])) == bytes([NACK])  # complement wrong
    bad = bytearray(addr(FLASH_BASE))
    bad[4] ^= 1
    assert rom.feed(cmd(0x11) + bytes(bad)) == bytes([ACK, NACK])
    assert rom.feed(cmd(0x11) + addr(0x30000000)) == bytes([ACK, NACK])  # nothing there
    assert rom.feed(cmd(0x31) + addr(0x20000000)) == bytes([ACK, NACK])  # the bootloader's own RAM
    out = rom.feed(cmd(0x31) + addr(FLASH_BASE) + bytes([3, 1, 2, 3, 4, 0]))  # data checksum wrong
    assert out == bytes([ACK, ACK, NACK]) and rom.flash[:4] == b"\xff" * 4
    assert rom.feed(cmd(0x31) + addr(FLASH_BASE + FLASH_SIZE - 2)) == bytes([ACK, ACK])
    assert rom.feed(bytes([3, 1, 2, 3, 4, 3 ^ 1 ^ 2 ^ 3 ^ 4])) == bytes([NACK])  # runs past the end of flash
    assert rom.feed(cmd(0x43) + bytes([0, 64, 64])) == bytes([ACK, NACK])  # page 64 of a 64-page flash
    assert rom.feed(cmd(0x21) + addr(0x20000200)) == bytes([ACK, NACK])  # GO elsewhere: not emulated
    assert rom.feed(cmd(0x63)) == bytes([NACK]) and rom.feed(cmd(0x82)) == bytes([NACK])  # protection: not emulated
    assert rom.feed(cmd(0x02)) == bytes([ACK, 0x01, 0x04, 0x10, ACK])  # still in step


def test_global_and_extended_erase():
    rom = synced(flash=b"\x00" * 4096)
    assert rom.feed(cmd(0x43) + bytes([0xFF, 0x01])) == bytes([ACK, NACK])  # global erase needs 0x00
    assert rom.flash[:4096] == b"\x00" * 4096
    assert rom.feed(cmd(0x43) + bytes([0xFF, 0x00])) == bytes([ACK, ACK])
    assert rom.flash == b"\xff" * FLASH_SIZE
    ext = synced(extended_erase=True, flash=b"\x00" * 4096)
    pages = bytes([0, 1, 0, 1, 0, 3])  # N = 1: pages 1 and 3
    assert ext.feed(cmd(0x44) + pages + bytes([xor(pages)])) == bytes([ACK, ACK])
    assert ext.flash[:1024] == b"\x00" * 1024 and ext.flash[1024:2048] == b"\xff" * 1024
    assert ext.flash[2048:3072] == b"\x00" * 1024 and ext.flash[3072:4096] == b"\xff" * 1024
    assert ext.feed(cmd(0x44) + bytes([0xFF, 0xFF, 0x00])) == bytes([ACK, ACK])  # mass erase
    assert ext.flash == b"\xff" * FLASH_SIZE


def test_reads_reach_ram_and_the_factory_option_bytes():
    rom = synced()
    assert write(rom, 0x20000200, b"\xaa\xbb\xcc\xdd") == bytes([ACK, ACK, ACK])
    assert read(rom, 0x20000200, 4) == b"\xaa\xbb\xcc\xdd"
    assert read(rom, OPTION_BASE, 2) == b"\xa5\x5a"  # RDP level 0: not read-protected


def test_readout_unprotect_erases_and_resets_into_the_bootloader():
    rom = synced(flash=b"\x00" * 64)
    assert rom.feed(cmd(0x92)) == bytes([ACK, ACK])
    assert rom.flash[:64] == b"\xff" * 64 and rom.resets == 1
    assert rom.feed(cmd(0x02)) == b""  # after the reset: waiting for 0x7F again
    assert rom.feed(b"\x7f") == bytes([ACK])


def test_go_hands_the_port_to_the_application():
    rom = synced()
    assert rom.feed(cmd(0x21) + addr(FLASH_BASE)) == bytes([ACK, ACK])
    assert rom.go_address == FLASH_BASE
    assert rom.feed(b"\x7f" + cmd(0x00)) == b""  # the bootloader is gone


def test_flash_elf_is_what_arm_emu_reads(tmp_path):
    image = os.urandom(3000)
    elf = read_elf(flash_elf(image, tmp_path / "f.elf"))
    assert [(s.paddr, s.data) for s in elf.segments] == [(FLASH_BASE, image)]
    assert elf.symbols == {}


# ------------------------------------------------------------------ the command line


def test_stm32flash_command_and_its_pty_adjustment(tmp_path):
    method = choose_method(load_board("bluepill-f103"), "stm32flash")
    art = tmp_path / "firmware.bin"
    assert flash_command(method, art, "/dev/ttyUSB0") == [
        "stm32flash", "-b", "115200", "-w", str(art), "-v", "-g", "0x0", "/dev/ttyUSB0"]
    master, slave = os.openpty()
    try:
        pty = os.ttyname(slave)
        link = tmp_path / "ttyBLUEPILL"
        link.symlink_to(pty)
        assert is_pseudo_terminal(pty) and is_pseudo_terminal(str(link))
        assert not is_pseudo_terminal("/dev/null") and not is_pseudo_terminal(str(art)) and not is_pseudo_terminal(None)
        # Linux ptys drop PARENB: stm32flash's default 8E1 would fail its termios read-back
        assert flash_command(method, art, str(link))[:3] == ["stm32flash", "-m", "8n1"]
        avrdude = choose_method(load_board("arduino-nano"))
        assert "8n1" not in flash_command(avrdude, art, pty)
    finally:
        os.close(master)
        os.close(slave)


@pytest.mark.parametrize("tool", ["openocd", "pyocd", "stm32flash"])
def test_bluepill_offers_every_flash_tool(tool):
    assert choose_method(load_board("bluepill-f103"), tool).tool == tool

