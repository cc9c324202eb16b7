"""Optiboot, the Arduino Nano's bootloader, built from Debian's sources for avr-emu.

Debian's ``arduino-core-avr`` ships optiboot 4.4 (``optiboot.c`` and its Makefile under
``/usr/share/arduino/hardware/arduino/avr/bootloaders/optiboot/``) and a prebuilt
``optiboot_atmega328.hex`` that is a 532-byte rebuild: it does not fit the Nano's 512-byte
boot section (BOOTSZ = 256 words at 0x7E00, ATmega328P datasheet Table 27-7), its last
20 bytes would land past the end of flash. ``build_optiboot`` compiles the same source
with the flags of optiboot's own Makefile (target ``atmega328``: 16 MHz, 115200 Bd,
``-Os -fno-inline-small-functions -fno-split-wide-types``, ``.text`` at 0x7E00 and the
version word at 0x7FFE; ``-mrelax`` in place of ``-mshort-calls``, which gcc ≥ 4.7 no
longer has) and the start-up LED flashes off (``LED_START_FLASHES=0``: the avr-emu board
has no LED; the flashes are what pushes the image past 512 bytes). The result is 496 bytes
of code plus the version word, cached under ``$PROLEG_CACHE/avr-emu/`` keyed by the
sources, the flags and the compiler version.

``python -m proleg.emu.avr.optiboot`` (or ``scripts/build-optiboot.sh``) builds it and
prints the path of the .hex and its size.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from ...errors import SimError
from .library import cache_root

#: where Debian's arduino-core-avr puts optiboot's sources
SOURCE_DIR = Path("/usr/share/arduino/hardware/arduino/avr/bootloaders/optiboot")
PACKAGE = "arduino-core-avr"
SOURCES = ("optiboot.c", "boot.h", "pin_defs.h", "stk500.h")

#: the ATmega328P boot section a Nano's fuses select (BOOTSZ1:0 = 11: 256 words)
BOOT_START = 0x7E00
FLASH_END = 0x8000
BOOT_BYTES = FLASH_END - BOOT_START

#: optiboot's Makefile, target atmega328 (CFLAGS, LDSECTIONS, LDFLAGS), LED flashes off
CFLAGS = (
    "-g", "-Wall", "-Os", "-fno-inline-small-functions", "-fno-split-wide-types", "-mrelax",
    "-mmcu=atmega328p", "-DF_CPU=16000000L", "-DBAUD_RATE=115200", "-DLED_START_FLASHES=0",
)
LDFLAGS = (
    f"-Wl,--section-start=.text=0x{BOOT_START:x}", f"-Wl,--section-start=.version=0x{FLASH_END - 2:x}",
    "-Wl,--relax", "-Wl,--gc-sections", "-nostartfiles", "-nostdlib",
)
OBJCOPY = ("-j", ".text", "-j", ".data", "-j", ".version", "--set-section-flags", ".version=alloc,load", "-O", "ihex")


def read_ihex(path: str | Path) -> dict[int, bytes]:
    """An Intel HEX file as {start address: bytes} of contiguous runs (record types 00,
    01, 02 and 04; checksums checked)."""
    path = Path(path)
    memory: dict[int, int] = {}
    base = 0
    for lineno, raw in enumerate(path.read_text(encoding="ascii", errors="replace").splitlines(), 1):
        line = raw.strip()
        if not line:
            continue
        try:
            if not line.startswith(":"):
                raise ValueError("no ':'")
            rec = bytes.fromhex(line[1:])
            if len(rec) < 5 or len(rec) != rec[0] + 5:
                raise ValueError("wrong length")
            if sum(rec) & 0xFF:
                raise ValueError("bad checksum")
        except ValueError as e:
            raise SimError(f"{path}:{lineno}: not an Intel HEX record ({e})") from None
        n, addr, kind, data = rec[0], (rec[1] << 8) | rec[2], rec[3], rec[4 : 4 + rec[0]]
        if kind == 0x00:
            for i in range(n):
                memory[base + addr + i] = data[i]
        elif kind == 0x01:
            break
        elif kind == 0x02:
            base = int.from_bytes(data, "big") << 4
        elif kind == 0x04:
            base = int.from_bytes(data, "big") << 16
    runs: dict[int, bytes] = {}
    start = prev = None
    chunk = bytearray()
    for a in sorted(memory):
        if prev is not None and a != prev + 1:
            runs[start] = bytes(chunk)  # type: ignore[index]
            chunk = bytearray()
            start = None
        if start is None:
            start = a
        chunk.append(memory[a])
        prev = a
    if start is not None:
        runs[start] = bytes(chunk)
    return runs


def check_boot_image(image: dict[int, bytes], where: str) -> int:
    """Bytes used; SimError unless every byte lies in the boot section."""
    if not image:
        raise SimError(f"{where}: empty bootloader image")
    lo = min(image)
    hi = max(a + len(d) for a, d in image.items())
    if lo < BOOT_START or hi > FLASH_END:
        raise SimError(
            f"{where}: bootloader spans 0x{lo:04x}..0x{hi - 1:04x}, outside the {BOOT_BYTES}-byte boot "
            f"section 0x{BOOT_START:04x}..0x{FLASH_END - 1:04x}"
        )
    return sum(len(d) for d in image.values())


def _tool_version(cc: str) -> str:
    try:
        return subprocess.run([cc, "--version"], capture_output=True, text=True, check=False).stdout.splitlines()[0]
    except (OSError, IndexError):
        return "unknown"


def build_optiboot(source_dir: Path = SOURCE_DIR) -> Path:
    """Path of optiboot_atmega328.hex built from ``source_dir`` (built now unless cached)."""
    missing = [s for s in SOURCES if not (source_dir / s).exists()]
    if missing:
        raise SimError(
            f"{source_dir}: no optiboot sources ({', '.join(missing)} missing): install the Debian package "
            f"{PACKAGE} (`make toolchains` does it)"
        )
    for tool in ("avr-gcc", "avr-objcopy"):
        if shutil.which(tool) is None:
            raise SimError(f"{tool} not found: install the Debian packages gcc-avr binutils-avr (`make toolchains`)")
    digest = hashlib.sha256()
    for s in SOURCES:
        digest.update(s.encode() + b"\0" + (source_dir / s).read_bytes() + b"\0")
    digest.update(" ".join((*CFLAGS, *LDFLAGS, *OBJCOPY, _tool_version("avr-gcc"))).encode())
    out = cache_root() / f"optiboot-{digest.hexdigest()[:16]}" / "optiboot_atmega328.hex"
    if out.exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=".optiboot-", dir=out.parent) as tmp:
        elf = Path(tmp) / "optiboot_atmega328.elf"
        hexfile = Path(tmp) / "optiboot_atmega328.hex"
        steps = (
            ["avr-gcc", *CFLAGS, *LDFLAGS, "-o", str(elf), str(source_dir / "optiboot.c")],
            ["avr-objcopy", *OBJCOPY, str(elf), str(hexfile)],
        )
        for cmd in steps:
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                lines = (proc.stdout + proc.stderr).strip().splitlines()
                raise SimError(f"building optiboot failed ({cmd[0]}):\n  " + "\n  ".join(lines[-12:]))
        check_boot_image(read_ihex(hexfile), str(hexfile))
        shutil.copyfile(elf, out.with_suffix(".elf"))
        os.replace(hexfile, out)  # atomic: concurrent builders all end with a complete file
    return out


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m proleg.emu.avr.optiboot",
                                description="Build optiboot for the ATmega328P (Nano) from Debian's sources.")
    p.add_argument("--source-dir", type=Path, default=SOURCE_DIR, help=f"optiboot sources (default {SOURCE_DIR})")
    p.add_argument("--copy-to", type=Path, metavar="FILE", help="also copy the .hex here")
    args = p.parse_args(argv)
    try:
        out = build_optiboot(args.source_dir)
        used = check_boot_image(read_ihex(out), str(out))
        if args.copy_to:
            shutil.copyfile(out, args.copy_to)
    except (SimError, OSError) as e:
        print(f"proleg: {e}", file=sys.stderr)
        return 1
    print(f"{out}: {used} bytes in the {BOOT_BYTES}-byte boot section at 0x{BOOT_START:04X}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
