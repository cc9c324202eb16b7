"""Board files (``boards/*.toml``): one file per board.

A board file names the MCU and clock, the toolchain and its flags, flash and RAM size,
the IMU bus, the PWM pin of each actuator channel, the host UART, and how to flash.
``load_board`` takes a board name (``arduino-nano``) or a path to a board file.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BoardError
from ..paths import boards_dir

FAMILIES = ("sim", "avr", "stm32f1")


@dataclass(frozen=True)
class FlashMethod:
    tool: str
    command: tuple[str, ...]  # {artifact} and {port} are filled in
    packages: tuple[str, ...]

    @property
    def needs_port(self) -> bool:
        return any("{port}" in part for part in self.command)


@dataclass(frozen=True)
class Board:
    name: str
    path: Path
    description: str
    family: str
    mcu: str
    clock_hz: int
    flash_bytes: int  # 0 = no limit (host-sim)
    ram_bytes: int
    cc: str
    cflags: tuple[str, ...]
    ldflags: tuple[str, ...]
    objcopy: str | None
    objcopy_flags: tuple[str, ...]
    size_tool: str
    artifact: str
    packages: tuple[str, ...]
    i2c: dict[str, Any]
    pwm_pins: tuple[str, ...]
    pwm_frequency_hz: int
    uart_port: str
    uart_baud: int
    flash_methods: tuple[FlashMethod, ...]

    @property
    def pwm_channels(self) -> tuple[str, ...]:
        return self.pwm_pins

    # Dict-style access keeps templates simple: board["name"], board["family"] ...
    def __getitem__(self, key: str) -> Any:
        return getattr(self, key)

    def get(self, key: str, default: Any = None) -> Any:
        return getattr(self, key, default)


def available_boards() -> list[str]:
    return sorted(p.stem for p in boards_dir().glob("*.toml"))


def load_board(name_or_path: str | Path) -> Board:
    text = str(name_or_path)
    if text.endswith(".toml") or "/" in text:
        path = Path(text)
    else:
        path = boards_dir() / f"{text}.toml"
        if not path.exists():
            raise BoardError(f"unknown board {text!r} (expected one of: {', '.join(available_boards())})")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BoardError(f"{path}: no such board file") from None
    except tomllib.TOMLDecodeError as e:
        raise BoardError(f"{path}: not valid TOML: {e}") from None
    return _board_from_dict(path, doc)


def _need(path: Path, doc: dict, table: str, key: str, kind: type | tuple[type, ...]) -> Any:
    t = doc.get(table)
    if not isinstance(t, dict) or key not in t:
        raise BoardError(f"{path}: {table}.{key}: missing")
    v = t[key]
    if not isinstance(v, kind) or isinstance(v, bool):
        raise BoardError(f"{path}: {table}.{key}: expected {getattr(kind, '__name__', kind)}, got {v!r}")
    return v


def _strings(path: Path, doc: dict, table: str, key: str, default: list | None = None) -> tuple[str, ...]:
    t = doc.get(table, {})
    v = t.get(key, default)
    if v is None or not isinstance(v, list) or not all(isinstance(s, str) for s in v):
        raise BoardError(f"{path}: {table}.{key}: expected a list of strings, got {v!r}")
    return tuple(v)


def _board_from_dict(path: Path, doc: dict) -> Board:
    known = {"board", "toolchain", "i2c", "pwm", "uart", "flash"}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise BoardError(f"{path}: unknown table {unknown[0]!r} (expected: {', '.join(sorted(known))})")
    family = _need(path, doc, "board", "family", str)
    if family not in FAMILIES:
        raise BoardError(f"{path}: board.family: expected one of {', '.join(FAMILIES)}, got {family!r}")
    flash = doc.get("flash", [])
    if not isinstance(flash, list):
        raise BoardError(f"{path}: flash: expected [[flash]] tables")
    methods = []
    for i, f in enumerate(flash):
        if not isinstance(f, dict) or not isinstance(f.get("tool"), str):
            raise BoardError(f"{path}: flash[{i}].tool: expected a string")
        cmd = f.get("command")
        if not isinstance(cmd, list) or not cmd or not all(isinstance(s, str) for s in cmd):
            raise BoardError(f"{path}: flash[{i}].command: expected a list of strings")
        methods.append(FlashMethod(f["tool"], tuple(cmd), tuple(f.get("packages", []))))
    tc = doc.get("toolchain", {})
    i2c = doc.get("i2c", {})
    if not isinstance(i2c, dict):
        raise BoardError(f"{path}: i2c: expected a table")
    return Board(
        name=_need(path, doc, "board", "name", str),
        path=path,
        description=doc["board"].get("description", ""),
        family=family,
        mcu=_need(path, doc, "board", "mcu", str),
        clock_hz=_need(path, doc, "board", "clock_hz", int),
        flash_bytes=_need(path, doc, "board", "flash_bytes", int),
        ram_bytes=_need(path, doc, "board", "ram_bytes", int),
        cc=_need(path, doc, "toolchain", "cc", str),
        cflags=_strings(path, doc, "toolchain", "cflags", []),
        ldflags=_strings(path, doc, "toolchain", "ldflags", []),
        objcopy=tc.get("objcopy"),
        objcopy_flags=_strings(path, doc, "toolchain", "objcopy_flags", []),
        size_tool=_need(path, doc, "toolchain", "size", str),
        artifact=_need(path, doc, "toolchain", "artifact", str),
        packages=_strings(path, doc, "toolchain", "packages", []),
        i2c=i2c,
        pwm_pins=_strings(path, doc, "pwm", "pins"),
        pwm_frequency_hz=_need(path, doc, "pwm", "frequency_hz", int),
        uart_port=_need(path, doc, "uart", "port", str),
        uart_baud=_need(path, doc, "uart", "baud", int),
        flash_methods=tuple(methods),
    )
