"""Just enough ELF32 (little-endian ARM) reading for the emulator: load segments, symbols."""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

from ...errors import SimError


@dataclass(frozen=True)
class Segment:
    paddr: int  # load address (flash for .data's initial values)
    data: bytes  # file bytes (memsz beyond them is zero and not loaded)


@dataclass(frozen=True)
class Symbol:
    name: str
    value: int
    size: int
    is_func: bool


@dataclass(frozen=True)
class Elf:
    path: Path
    segments: tuple[Segment, ...]
    symbols: dict[str, Symbol]

    def symbol(self, name: str) -> Symbol | None:
        return self.symbols.get(name)


def read_elf(path: str | Path) -> Elf:
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as e:
        raise SimError(f"{path}: cannot read the firmware image: {e.strerror}") from None
    if raw[:4] != b"\x7fELF" or raw[4] != 1 or raw[5] != 1:
        raise SimError(f"{path}: not a 32-bit little-endian ELF file (expected the bluepill firmware.elf)")
    e_machine = struct.unpack_from("<H", raw, 18)[0]
    if e_machine != 40:
        raise SimError(f"{path}: ELF machine {e_machine}, expected 40 (ARM)")
    (e_phoff, e_shoff) = struct.unpack_from("<II", raw, 28)
    e_phentsize, e_phnum, e_shentsize, e_shnum = struct.unpack_from("<HHHH", raw, 42)
    segments = []
    for i in range(e_phnum):
        p_type, p_offset, _vaddr, p_paddr, p_filesz, _memsz, _flags, _align = struct.unpack_from(
            "<8I", raw, e_phoff + i * e_phentsize
        )
        if p_type == 1 and p_filesz:
            segments.append(Segment(p_paddr, raw[p_offset : p_offset + p_filesz]))
    symbols: dict[str, Symbol] = {}
    sections = [struct.unpack_from("<10I", raw, e_shoff + i * e_shentsize) for i in range(e_shnum)]
    for sh in sections:
        if sh[1] != 2:  # SHT_SYMTAB
            continue
        strtab = sections[sh[6]]
        for off in range(sh[4], sh[4] + sh[5], 16):
            st_name, st_value, st_size, st_info = struct.unpack_from("<IIIB", raw, off)
            if not st_name or (st_info & 0xF) not in (1, 2):  # OBJECT, FUNC
                continue
            start = strtab[4] + st_name
            name = raw[start : raw.index(b"\0", start)].decode()
            is_func = (st_info & 0xF) == 2
            symbols.setdefault(name, Symbol(name, st_value & ~1 if is_func else st_value, st_size, is_func))
    return Elf(path, tuple(segments), symbols)
