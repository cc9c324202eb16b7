"""What the avr-emu board needs to know about a firmware ELF: its symbols and where
its control tick waits.

The tick-budget markers are program addresses (see harness.c): ``start`` is where the
firmware leaves its tick wait (its work begins), ``end`` where it enters the wait again.
They are found without changing the firmware:

- ``hal_wait_tick`` is a function: ``end`` is its entry, ``start`` the instruction after
  its (only) call site;
- it was inlined (``-flto``, today's arduino-nano build): the wait is the loop that
  polls ``hal_micros`` until the next tick boundary, recognised as a call of
  ``hal_micros`` that a backward branch a few instructions later jumps back to exactly
  (the loop head is the call itself; the bounded waits of the TWI driver start their
  loops at a register read instead). ``end`` is that call, ``start`` the instruction
  after the branch (the loop's exit).

Firmware that writes GPIOR0 (1 = work begins, 0 = work done) is measured from those
writes instead (the harness switches on the first write), so the markers may be absent.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from ...errors import SimError

NM = "avr-nm"
OBJDUMP = "avr-objdump"
DATA_BASE = 0x800000  # avr-gcc's data-space offset in ELF addresses
LOOP_SPAN = 64  # bytes: how far after the call the loop's backward branch may be

_LINE = re.compile(r"^\s*([0-9a-f]+):\s+((?:[0-9a-f]{2} )+)\s*(\S+)\s*([^;]*)(?:;\s*(0x[0-9a-f]+)\s*<([^>]+)>)?")


@dataclass(frozen=True)
class Symbol:
    name: str
    address: int  # flash byte address, or data-space address (without the 0x800000 offset)
    size: int
    kind: str  # nm type letter


@dataclass(frozen=True)
class Instruction:
    address: int
    size: int
    mnemonic: str
    target: int | None  # branch/call destination, as avr-objdump resolved it
    target_name: str


@dataclass(frozen=True)
class TickMarkers:
    start: int  # byte address: the tick's work begins here
    end: int  # byte address: the tick wait begins here
    how: str


def _tool(name: str) -> str:
    path = shutil.which(name)
    if path is None:
        raise SimError(f"{name} not found: install the Debian package binutils-avr (`make toolchains` does it)")
    return path


@lru_cache(maxsize=32)
def _symbols(elf: Path, mtime_ns: int) -> dict[str, Symbol]:
    proc = subprocess.run([_tool(NM), "-S", str(elf)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SimError(f"{elf}: {NM} cannot read it: {proc.stderr.strip()}")
    out: dict[str, Symbol] = {}
    for line in proc.stdout.splitlines():
        parts = line.split()
        if len(parts) == 4:
            addr, size, kind, name = parts
        elif len(parts) == 3:
            addr, kind, name = parts
            size = "0"
        else:
            continue
        a = int(addr, 16)
        if a >= DATA_BASE and kind.lower() in "bdv":
            a -= DATA_BASE
        out.setdefault(name, Symbol(name, a, int(size, 16), kind))
    return out


def symbols(elf: str | Path) -> dict[str, Symbol]:
    """Every symbol by name (LTO's ``.lto_priv.N`` suffixes kept)."""
    elf = Path(elf)
    return _symbols(elf, elf.stat().st_mtime_ns)


def find_symbol(elf: str | Path, name: str) -> Symbol | None:
    """A symbol by its source name, with or without an LTO/const-prop suffix."""
    syms = symbols(elf)
    if name in syms:
        return syms[name]
    for full, sym in syms.items():
        if full.split(".")[0] == name:
            return sym
    return None


@lru_cache(maxsize=32)
def _disassembly(elf: Path, mtime_ns: int) -> tuple[Instruction, ...]:
    proc = subprocess.run([_tool(OBJDUMP), "-d", "-j", ".text", str(elf)], capture_output=True, text=True)
    if proc.returncode != 0:
        raise SimError(f"{elf}: {OBJDUMP} cannot read it: {proc.stderr.strip()}")
    out = []
    for line in proc.stdout.splitlines():
        m = _LINE.match(line)
        if m:
            addr, raw, mnem, _ops, target, tname = m.groups()
            out.append(
                Instruction(
                    int(addr, 16),
                    len(raw.split()),
                    mnem,
                    int(target, 16) if target else None,
                    tname or "",
                )
            )
    return tuple(out)


def disassembly(elf: str | Path) -> tuple[Instruction, ...]:
    elf = Path(elf)
    return _disassembly(elf, elf.stat().st_mtime_ns)


def _is_call(ins: Instruction) -> bool:
    return ins.mnemonic in ("call", "rcall")


def _is_branch(ins: Instruction) -> bool:
    return ins.mnemonic in ("rjmp", "jmp") or ins.mnemonic.startswith("br")


def tick_markers(elf: str | Path) -> TickMarkers | None:
    """Where the firmware's tick work starts and ends (None when no wait was recognised)."""
    code = disassembly(elf)
    wait = find_symbol(elf, "wait_tick")
    if wait is not None and wait.kind in "tT":
        sites = [i for i in code if _is_call(i) and i.target == wait.address]
        if len(sites) == 1:
            return TickMarkers(sites[0].address + sites[0].size, wait.address, "wait_tick call")
    micros = find_symbol(elf, "hal_micros")
    if micros is None or micros.kind not in "tT":
        return None
    found = []
    for k, ins in enumerate(code):
        if not (_is_call(ins) and ins.target == micros.address):
            continue
        for later in code[k + 1 :]:
            if later.address > ins.address + LOOP_SPAN:
                break
            if _is_branch(later) and later.target == ins.address:
                found.append(TickMarkers(later.address + later.size, ins.address, "hal_micros wait loop"))
                break
    if len(found) == 1:
        return found[0]
    main = find_symbol(elf, "main")
    if main is not None:
        in_main = [f for f in found if main.address <= f.end < main.address + main.size]
        if len(in_main) == 1:
            return in_main[0]
    return None
