"""The emulated Nano with its bootloader: optiboot built from Debian's sources fits the
boot section, sits behind BOOTRST, stays only after an external reset, programs flash
through SPM, and hands over to the application by its watchdog — all in emulated time,
speaking STK500 from Python (the real avrdude over a pty is tests/test_flash_e2e.py).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from proleg.errors import SimError

OPTIBOOT_DIR = Path("/usr/share/arduino/hardware/arduino/avr/bootloaders/optiboot")

pytestmark = pytest.mark.skipif(
    not Path("/usr/include/simavr/sim_avr.h").exists()
    or shutil.which("avr-gcc") is None
    or not (OPTIBOOT_DIR / "optiboot.c").exists(),
    reason="needs simavr/libsimavr-dev, avr-gcc and arduino-core-avr (make toolchains installs them)",
)

F_CPU = 16_000_000
STK_OK, STK_INSYNC, CRC_EOP = 0x10, 0x14, 0x20

APP = r"""
#include <avr/io.h>
/* A tiny application: says MSG once on the UART (115200 Bd, U2X), then idles. */
int main(void)
{
    const char *s = MSG;
    UBRR0 = 16;
    UCSR0A = _BV(U2X0);
    UCSR0B = _BV(TXEN0);
    while (*s) {
        while (!(UCSR0A & _BV(UDRE0))) {
        }
        UDR0 = *s++;
    }
    for (;;) {
    }
}
"""


def compile_app(tmp_path: Path, msg: str) -> tuple[Path, bytes]:
    src = tmp_path / f"app-{msg}.c"
    src.write_text(APP)
    elf = tmp_path / f"app-{msg}.elf"
    subprocess.run(["avr-gcc", "-mmcu=atmega328p", "-Os", f'-DMSG="{msg}"', str(src), "-o", str(elf)],
                   check=True, capture_output=True)
    binfile = elf.with_suffix(".bin")
    subprocess.run(["avr-objcopy", "-O", "binary", "-j", ".text", "-j", ".data", str(elf), str(binfile)], check=True)
    return elf, binfile.read_bytes()


@pytest.fixture(scope="module")
def optiboot_hex():
    from proleg.emu.avr.optiboot import build_optiboot

    return build_optiboot()


def nano(elf: Path | None, optiboot_hex: Path):
    from proleg.emu.avr.pty_nano import nano_with_bootloader

    return nano_with_bootloader(elf, optiboot_hex)


def run_until_output(board, n: int, limit_us: int = 200_000, step_us: int = 200) -> bytes:
    out = b""
    waited = 0
    while len(out) < n and waited < limit_us:
        board.run_us(step_us)
        waited += step_us
        out += board.read()
    return out


def stk(board, cmd: bytes, reply_len: int) -> bytes:
    """One STK500v1 command; the reply (INSYNC .. OK) checked and its payload returned."""
    board.write(cmd)
    out = run_until_output(board, reply_len + 2)
    assert out[:1] == bytes([STK_INSYNC]) and out[-1:] == bytes([STK_OK]), f"{cmd[:1].hex()}: {out.hex()}"
    return out[1:-1]


# ------------------------------------------------------------------ the image


def test_optiboot_from_debian_sources_fits_the_boot_section(optiboot_hex):
    from proleg.emu.avr.optiboot import BOOT_BYTES, BOOT_START, check_boot_image, read_ihex

    image = read_ihex(optiboot_hex)
    used = check_boot_image(image, str(optiboot_hex))
    assert used <= BOOT_BYTES == 512
    assert min(image) == BOOT_START == 0x7E00
    assert max(a + len(d) for a, d in image.items()) <= 0x8000
    # the version word optiboot keeps in the last two bytes: 4.4
    assert image[max(image)][-2:] == bytes([4, 4])


def test_debian_prebuilt_optiboot_overflows_the_boot_section():
    """Why the bootloader is built here: the shipped hex runs past the end of flash."""
    from proleg.emu.avr.optiboot import check_boot_image, read_ihex

    shipped = OPTIBOOT_DIR / "optiboot_atmega328.hex"
    if not shipped.exists():
        pytest.skip("no prebuilt optiboot_atmega328.hex")
    image = read_ihex(shipped)
    if sum(len(d) for d in image.values()) <= 512:
        pytest.skip("this arduino-core-avr ships a hex that fits")
    with pytest.raises(SimError, match="outside the 512-byte boot section"):
        check_boot_image(image, str(shipped))


def test_read_ihex_matches_objcopy_binary(tmp_path, optiboot_hex):
    from proleg.emu.avr.optiboot import read_ihex

    binfile = tmp_path / "o.bin"
    subprocess.run(["avr-objcopy", "-I", "ihex", "-O", "binary", "--gap-fill", "0xff", str(optiboot_hex), str(binfile)], check=True)
    image = read_ihex(optiboot_hex)
    lo, hi = min(image), max(a + len(d) for a, d in image.items())
    flat = bytearray(b"\xff" * (hi - lo))
    for a, d in image.items():
        flat[a - lo : a - lo + len(d)] = d
    assert bytes(flat) == binfile.read_bytes()


def test_read_ihex_names_the_bad_line(tmp_path):
    from proleg.emu.avr.optiboot import read_ihex

    bad = tmp_path / "bad.hex"
    bad.write_text(":0400000001020304F3\n:00000001FF\n")  # the checksum is 0xF2
    with pytest.raises(SimError, match=r"bad\.hex:1: not an Intel HEX record \(bad checksum\)"):
        read_ihex(bad)


# ------------------------------------------------------------------ the bootloader running


def test_power_on_runs_the_application_at_once(tmp_path, optiboot_hex):
    elf, _ = compile_app(tmp_path, "APP1")
    board = nano(elf, optiboot_hex)
    assert board.flash_read(0x7E00, 2) != b"\xff\xff"
    out = run_until_output(board, 4, limit_us=20_000)
    assert out == b"APP1"  # optiboot saw no EXTRF: straight to the application
    assert board.mcu_resets == 0


def test_external_reset_stays_in_optiboot_then_the_watchdog_starts_the_application(tmp_path, optiboot_hex):
    elf, _ = compile_app(tmp_path, "APP1")
    board = nano(elf, optiboot_hex)
    run_until_output(board, 4)
    board.external_reset()
    assert stk(board, b"\x30\x20", 0) == b""  # STK_GET_SYNC
    assert stk(board, b"\x75\x20", 3) == bytes([0x1E, 0x95, 0x0F])  # READ_SIGN: ATmega328P
    # no more commands: optiboot's 1 s watchdog (WDTO_1S, ~1.0 s) resets into the application
    assert run_until_output(board, 1, limit_us=900_000) == b""
    assert run_until_output(board, 4, limit_us=300_000) == b"APP1"
    assert board.mcu_resets == 2  # the external reset and the watchdog's


def test_a_byte_optiboot_does_not_expect_leaves_within_the_16ms_watchdog(tmp_path, optiboot_hex):
    """Optiboot shortens its running watchdog to 16 ms; plain simavr 1.6 kept the 1 s one."""
    elf, _ = compile_app(tmp_path, "APP1")
    board = nano(elf, optiboot_hex)
    run_until_output(board, 4)
    board.external_reset()
    board.run_us(1000)
    board.write(b"\x00\x05")  # a proleg frame's first bytes: not STK500
    out = run_until_output(board, 4, limit_us=40_000)
    assert out == b"APP1"
    assert board.time_s < 0.1


def test_stk500_programs_flash_through_spm_and_the_new_application_runs(tmp_path, optiboot_hex):
    _, new = compile_app(tmp_path, "NEW2")
    board = nano(None, optiboot_hex)  # a blank application section
    assert board.flash_read(0, 256) == b"\xff" * 256
    board.external_reset()
    stk(board, b"\x30\x20", 0)
    page = 128  # ATmega328P SPM page: 64 words
    padded = new + b"\xff" * (-len(new) % page)
    for off in range(0, len(padded), page):
        word = off // 2
        stk(board, bytes([0x55, word & 0xFF, word >> 8, CRC_EOP]), 0)  # LOAD_ADDRESS (words)
        stk(board, bytes([0x64, 0, page]) + b"F" + padded[off : off + page] + bytes([CRC_EOP]), 0)  # PROG_PAGE
    assert board.flash_read(0, len(new)) == new
    stk(board, bytes([0x55, 0, 0, CRC_EOP]), 0)
    assert stk(board, bytes([0x74, 0, page]) + b"F" + bytes([CRC_EOP]), page) == padded[:page]  # READ_PAGE
    stk(board, b"\x51\x20", 0)  # LEAVE_PROGMODE: watchdog 16 ms, then the application
    t0 = board.time_s
    assert run_until_output(board, 4, limit_us=40_000) == b"NEW2"
    assert board.time_s - t0 < 0.03
    # flash is non-volatile: a power-on keeps what the bootloader wrote
    board.reset(2)
    assert board.flash_read(0, len(new)) == new
    assert run_until_output(board, 4, limit_us=20_000) == b"NEW2"


def test_without_a_bootloader_the_board_starts_at_zero_as_before(tmp_path):
    """The existing avr-emu path: the ELF at 0, no boot section, a power-on reloads it."""
    from proleg.emu.avr import AvrEmuBoard

    elf, app = compile_app(tmp_path, "APP1")
    board = AvrEmuBoard(elf, tick_hz=1000, imu_addresses=())
    assert run_until_output(board, 4, limit_us=20_000) == b"APP1"
    board.flash_write(0, b"\xff" * len(app))
    board.reset(1)
    assert board.flash_read(0, len(app)) == app
    assert run_until_output(board, 4, limit_us=20_000) == b"APP1"


def test_install_bootloader_refuses_bytes_below_the_boot_section(tmp_path, optiboot_hex):
    from proleg.emu.avr import AvrEmuBoard

    elf, _ = compile_app(tmp_path, "APP1")
    board = AvrEmuBoard(elf, tick_hz=1000, imu_addresses=())
    with pytest.raises(SimError, match="below the boot section"):
        board.install_bootloader({0x7000: b"\x00\x00"}, 0x7E00)
    with pytest.raises(SimError, match="past the end of flash"):
        board.flash_write(0x7FFF, b"\x00\x00")


def test_a_dtr_reset_through_optiboot_keeps_the_envelope_and_a_power_on_does_not(optiboot_hex):
    """A real Nano's reset cause is always UNKNOWN behind optiboot, which clears MCUSR on every
    start: a power-on too. The DTR auto-reset (optiboot's 1 s wait, then its watchdog) must
    keep what the coils spent (docs/safety.md, "A reset"): the firmware treats UNKNOWN as not a
    power-on and the mark decides; optiboot leaves .noinit alone (its buffer is at RAMSTART)."""
    from proleg.emu.avr import nano_elf
    from proleg.paths import robots_dir
    from proleg.protocol.codec import FrameDecoder
    from proleg.protocol.definition import EventKind, ResetCause
    from proleg.robot import load_robot

    board = nano(nano_elf(load_robot(robots_dir() / "paper-r1.toml")), optiboot_hex)
    decoder = FrameDecoder()

    def boots():
        msgs = decoder.feed(board.read())
        return [(m.code, m.detail) for m in msgs if m.name == "EVENT" and m.kind == EventKind.BOOT]

    board.advance(0.05)
    assert boots() == [(ResetCause.UNKNOWN, 0)]  # a power-on: RAM without the mark, a cold budget
    kept = board.read_symbol("kept")
    board.external_reset()
    board.advance(1.5)
    assert board.mcu_resets == 2  # the DTR reset and optiboot's watchdog
    assert boots() == [(ResetCause.UNKNOWN, 1)]  # the budget kept
    assert board.read_symbol("kept")[-2:] == kept[-2:]  # the same mark
