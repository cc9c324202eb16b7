"""Board files (``boards/*.toml``): one file per board, the only board-specific data.

A board file names its HAL family (a folder ``firmware_templates/hal/<family>/``), the
MCU and clock, flash and RAM size, the compiler and its flags, the build steps after
compiling (``[build]``: link output, conversion to the flashed artifact, the size
command, whether the core's main loop is in the image), the IMU bus, the PWM pin of each
actuator channel, the host UART and its buffers, and how to flash. ``load_board`` takes
a board name (``arduino-nano``) or a path to a board file. See docs/adding-a-board.md.
"""

from __future__ import annotations

import difflib
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BoardError
from ..paths import boards_dir, not_a_regular_file
from ..robot_limbs import NAME_ALPHABET, name_re
from .can_config import CanConfig, can_config, link_transport
from .families import MAX_RING_BYTES, available_families, hal_root, is_ring_size, load_family

#: [uart] buffers when a board file does not give them (bytes, powers of two).
DEFAULT_UART_RX_BUFFER = 64
DEFAULT_UART_TX_BUFFER = 128
#: [i2c] hz when a board file does not give it (fast mode).
DEFAULT_I2C_HZ = 400_000
#: What a board name may be: it is `--board`'s argument, a C string in the firmware and INFO's
#: board_name (15 characters), so the robot names' alphabet (robot_limbs.name_re).
BOARD_NAME_RE = name_re(15)
#: The ranges of a board file's whole numbers, (lo, hi, what): clock_hz 0 is virtual time (host
#: builds); flash_bytes/ram_bytes 0 is no limit, base_*/stack_bytes 0 not measured. The C takes
#: them as unsigned long (32 bits on the MCUs); a HAL may need a narrower range of its own.
RANGES = {
    ("board", "clock_hz"): (0, 1_000_000_000, "a clock in Hz"),
    ("board", "flash_bytes"): (0, 0xFFFF_FFFF, "a size in bytes"),
    ("board", "ram_bytes"): (0, 0xFFFF_FFFF, "a size in bytes"),
    ("board", "base_flash_bytes"): (0, 0xFFFF_FFFF, "a size in bytes"),
    ("board", "base_ram_bytes"): (0, 0xFFFF_FFFF, "a size in bytes"),
    ("board", "stack_bytes"): (0, 0xFFFF_FFFF, "a size in bytes"),
    ("i2c", "hz"): (1_000, 3_400_000, "an I2C clock in Hz"),
    ("pwm", "frequency_hz"): (1, 1_000_000, "a PWM frequency in Hz"),
    ("uart", "baud"): (300, 12_000_000, "a baud rate"),
}
#: The keys of a [[flash]] table.
FLASH_KEYS = {"tool", "command", "packages"}


@dataclass(frozen=True)
class FlashMethod:
    tool: str
    command: tuple[str, ...]  # {artifact} and {port} are filled in
    packages: tuple[str, ...]

    @property
    def needs_port(self) -> bool:
        return any("{port}" in part for part in self.command)


@dataclass(frozen=True)
class I2cBus:
    """One I2C bus of the board: the HAL's bus index (0 = hal_i2c_write_read's bus),
    its name and pins, the IMU addresses a device on it may use, and the addresses at
    which a TCA9548A/PCA9548A multiplexer may sit on it (empty: no multiplexer)."""

    index: int
    name: str
    sda: str
    scl: str
    addresses: tuple[int, ...]
    mux_addresses: tuple[int, ...]


#: What a bus offers when the board file does not say (an MPU-6050's AD0 low/high).
DEFAULT_IMU_ADDRESSES = (0x68, 0x69)
MUX_RANGE = range(0x70, 0x78)
#: Buses a HAL may offer (hal_i2c_write_read_bus takes a uint8_t index; the core's tables hold up to 4).
MAX_I2C_BUSES = 4


@dataclass(frozen=True)
class TickBudget:
    """``[budget]``: the control tick's measured work on this board, busy p99 in µs of the
    MCU's clock = ``tick_us_base`` + ``tick_us_per_limb`` × limbs (bench/bench_mcu.py on the
    emulated MCU; ``measured`` says when and how). ``proleg build`` refuses a tick_hz whose
    period this cannot fit within ``BUSY_LIMIT`` of; with ``enforce = false`` it only warns
    (a board whose firmware is known not to meet its budget yet)."""

    tick_us_base: float
    tick_us_per_limb: float
    measured: str
    enforce: bool = True

    #: busy p99 at most this share of the tick period (issue 11, SPEC §3)
    BUSY_LIMIT = 0.70

    def busy_us(self, limbs: int) -> float:
        return self.tick_us_base + self.tick_us_per_limb * limbs

    def max_tick_hz(self, limbs: int) -> int:
        """The highest whole tick rate whose period the work of ``limbs`` limbs fits."""
        return int(self.BUSY_LIMIT * 1e6 // self.busy_us(limbs))


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
    packages: tuple[str, ...]
    main_loop: bool  # core/main.c (main, tick pacing) is in the image; False: a host drives the ticks
    link: str  # what `$(CC) <objects> <ldflags> -o` writes
    artifact: str  # what is flashed or loaded: the link output, or made from it by `objcopy`
    objcopy: tuple[str, ...]  # link -> artifact command ({link}, {artifact} filled in); empty: none
    size: tuple[str, ...]  # Berkeley-format size command ({link} filled in)
    i2c: dict[str, Any]
    pwm_pins: tuple[str, ...]
    pwm_frequency_hz: int
    uart_port: str
    uart_baud: int
    uart_rx_buffer: int
    uart_tx_buffer: int
    flash_methods: tuple[FlashMethod, ...]
    i2c_buses: tuple[I2cBus, ...] = ()
    base_flash_bytes: int = 0  # measured firmware of a two-limb robot with tiny tables (0: not estimated)
    base_ram_bytes: int = 0
    stack_bytes: int = 0  # RAM kept free for the stack and interrupts beside static RAM (measured peak + margin)
    budget: TickBudget | None = None  # None: no measurement (host-sim: virtual time)
    transport: str = "uart"  # [link] transport: the host link on the UART or on CAN
    can: CanConfig | None = None  # [can]: the CAN controller's pins, bit rate, node (can_config.py)

    @property
    def pwm_channels(self) -> tuple[str, ...]:
        return self.pwm_pins

    def objcopy_command(self) -> list[str]:
        return [_fill(p, link=self.link, artifact=self.artifact) for p in self.objcopy]

    def size_command(self) -> list[str]:
        return [_fill(p, link=self.link, artifact=self.artifact) for p in self.size]

    def tools(self) -> list[str]:
        """Every program the build runs (compiler, conversion, size)."""
        return [self.cc] + [cmd[0] for cmd in (self.objcopy, self.size) if cmd]

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
    return _board_from_dict(path, _read_doc(path))


def _read_doc(path: Path, seen: tuple[Path, ...] = ()) -> dict:
    """The board file's tables; ``[board] extends = "NAME"`` takes every table of board NAME
    and lays this file's over it (tables key by key, lists and values replaced)."""
    odd = not_a_regular_file(path)
    if odd:
        raise BoardError(f"{path}: cannot read the board file: {odd}")
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise BoardError(f"{path}: no such board file") from None
    except UnicodeDecodeError as e:
        line = e.object[: e.start].count(b"\n") + 1
        raise BoardError(f"{path}: expected UTF-8 text, got byte 0x{e.object[e.start]:02x} on line {line}") from None
    except OSError as e:  # a directory, no permission...
        raise BoardError(f"{path}: cannot read the board file: {e.strerror or e}") from None
    except tomllib.TOMLDecodeError as e:
        raise BoardError(f"{path}: not valid TOML: {e}") from None
    parent = doc.get("board", {}).get("extends") if isinstance(doc.get("board"), dict) else None
    if parent is None:
        return doc
    base = boards_dir() / f"{parent}.toml"
    if not isinstance(parent, str) or not base.exists():
        raise BoardError(f"{path}: board.extends: expected the name of a board file in {boards_dir()}, got {parent!r}")
    if base.resolve() in seen or base.resolve() == path.resolve():
        raise BoardError(f"{path}: board.extends: {parent!r} extends itself")
    merged = _merge(_read_doc(base, (*seen, path.resolve())), doc)
    merged["board"].pop("extends", None)
    return merged


def _merge(base: dict, top: dict) -> dict:
    out = dict(base)
    for k, v in top.items():
        out[k] = _merge(base[k], v) if isinstance(v, dict) and isinstance(base.get(k), dict) else v
    return out


def _need(path: Path, doc: dict, table: str, key: str, kind: type | tuple[type, ...]) -> Any:
    t = doc.get(table)
    if not isinstance(t, dict) or key not in t:
        raise BoardError(f"{path}: {table}.{key}: missing")
    v = t[key]
    if not isinstance(v, kind) or isinstance(v, bool):
        raise BoardError(f"{path}: {table}.{key}: expected {getattr(kind, '__name__', kind)}, got {v!r}")
    return v


def _whole(path: Path, doc: dict, table: str, key: str, default: int | None = None) -> int:
    """A whole number in its ``RANGES`` entry; required when there is no default."""
    lo, hi, what = RANGES[table, key]
    v = _need(path, doc, table, key, int) if default is None else doc.get(table, {}).get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise BoardError(f"{path}: {table}.{key}: expected {what} in {lo:_}..{hi:_}, got {v!r}")
    return v


def _strings(path: Path, doc: dict, table: str, key: str, default: list | None = None) -> tuple[str, ...]:
    t = doc.get(table, {})
    v = t.get(key, default)
    if v is None or not isinstance(v, list) or not all(isinstance(s, str) for s in v):
        raise BoardError(f"{path}: {table}.{key}: expected a list of strings, got {v!r}")
    return tuple(v)


def _fill(part: str, **values: str) -> str:
    for k, v in values.items():
        part = part.replace("{" + k + "}", v)
    return part


def _buffer(path: Path, doc: dict, key: str, default: int, family: str) -> int:
    """A UART ring's size, within what the family's HAL takes: past an 8-bit MCU's 128 bytes
    the board file was taken (flash --dry-run printed its command, exit 0) and only the
    compiler refused it, at hal_avr.c's #error."""
    top = load_family(family).max_ring_bytes
    v = doc.get("uart", {}).get(key, default)
    if not is_ring_size(v, top):
        on = (f" (the most the {family} family's HAL takes: its family.toml's uart.max_ring_bytes)"
              if top < MAX_RING_BYTES else "")
        raise BoardError(f"{path}: uart.{key}: expected a power of two from 16 to {top} bytes{on}, got {v!r}")
    return v


def _baud(path: Path, doc: dict, family: str) -> int:
    """``uart.baud``, which the family's HAL can make from ``board.clock_hz`` (``Family.baud_problem``):
    a board file of an 8 MHz ATmega328P at 115200 loaded, built, and its UART ran at 111,111
    (-3.5 %): every frame garbled."""
    baud = _whole(path, doc, "uart", "baud")
    clock = _whole(path, doc, "board", "clock_hz")
    problem = load_family(family).baud_problem(clock, baud) if clock else None  # clock_hz 0: virtual time
    if problem:
        raise BoardError(f"{path}: uart.baud: {baud} {problem}")
    return baud


def _file_name(path: Path, doc: dict, key: str) -> str:
    """``build.link`` or ``build.artifact``: a file the Makefile makes in the project
    directory. An empty one was taken: the artifact then named the directory itself, which
    flash --dry-run printed as the file to write (exit 0) and the build never made."""
    v = _need(path, doc, "build", key, str)
    if not v.strip() or v != v.strip() or "/" in v or "\\" in v or v in (".", ".."):
        raise BoardError(f"{path}: build.{key}: expected a file name in the project directory (no folder, "
                         f"no spaces at its ends), e.g. \"firmware.elf\", got {v!r}")
    return v


def _program(path: Path, where: str, name: str) -> str:
    """A program a build step runs, found on PATH: an empty name was looked for as itself
    ("proleg: error:  not found, needed for board ...")."""
    if not name.strip() or name != name.strip():
        raise BoardError(f"{path}: {where}: expected the name of a program (no spaces at its ends), got {name!r}")
    return name


def _build_steps(path: Path, doc: dict) -> dict[str, Any]:
    b = doc.get("build")
    if not isinstance(b, dict):
        raise BoardError(f"{path}: build: missing (the [build] table: main_loop, link, artifact, size)")
    main_loop = b.get("main_loop")
    if not isinstance(main_loop, bool):
        raise BoardError(f"{path}: build.main_loop: expected true or false, got {main_loop!r}")
    link = _file_name(path, doc, "link")
    artifact = _file_name(path, doc, "artifact")
    objcopy = _strings(path, doc, "build", "objcopy", [])
    size = _strings(path, doc, "build", "size")
    if not size:
        raise BoardError(f"{path}: build.size: expected a command, e.g. [\"size\", \"-B\", \"{{link}}\"]")
    for key, command in (("objcopy", objcopy), ("size", size)):
        if command:
            _program(path, f"build.{key}[0]", command[0])
    if artifact != link and not objcopy:
        raise BoardError(f"{path}: build.objcopy: missing, needed to make artifact {artifact!r} from {link!r}")
    if artifact == link and objcopy:
        raise BoardError(f"{path}: build.objcopy: given, but build.artifact is the link output {link!r}")
    return dict(main_loop=main_loop, link=link, artifact=artifact, objcopy=objcopy, size=size)


#: The keys each table of a board file takes ([can] checks its own: can_config; [[flash]] is a list).
TABLE_KEYS = {
    "board": {"name", "description", "family", "mcu", "clock_hz", "flash_bytes", "ram_bytes", "base_flash_bytes",
              "base_ram_bytes", "stack_bytes"},
    "toolchain": {"cc", "cflags", "ldflags", "packages"},
    "build": {"artifact", "link", "main_loop", "objcopy", "size"},
    "i2c": {"bus", "hz", "sda", "scl", "imu_addresses", "mux_addresses"},
    "pwm": {"frequency_hz", "pins"},
    "uart": {"baud", "port", "rx_buffer", "tx_buffer"},
    "budget": {"enforce", "measured", "tick_us_base", "tick_us_per_limb"},
    "link": {"transport"},
}


def _board_from_dict(path: Path, doc: dict) -> Board:
    known = {"board", "toolchain", "build", "i2c", "pwm", "uart", "flash", "budget", "link", "can"}
    unknown = sorted(set(doc) - known)
    if unknown:
        raise BoardError(f"{path}: unknown table {unknown[0]!r} (expected: {', '.join(sorted(known))})")
    for table, keys in TABLE_KEYS.items():
        if table in doc and not isinstance(doc[table], dict):
            raise BoardError(f"{path}: {table}: expected a table, got {doc[table]!r}")
        _known_keys(path, table, doc.get(table, {}), keys)
    family = _need(path, doc, "board", "family", str)
    if family not in available_families():
        raise BoardError(
            f"{path}: board.family: expected one of {', '.join(available_families())} "
            f"(a folder with a family.toml under {hal_root()}), got {family!r}"
        )
    buses = i2c_buses(path, doc.get("i2c", {}))
    i2c = {k: v for k, v in doc.get("i2c", {}).items() if k != "bus"} | {
        "bus": buses[0].name,
        "imu_addresses": list(buses[0].addresses),
        "hz": _whole(path, doc, "i2c", "hz", DEFAULT_I2C_HZ),
    }
    name = _need(path, doc, "board", "name", str)
    if not BOARD_NAME_RE.fullmatch(name):
        raise BoardError(f"{path}: board.name: expected {NAME_ALPHABET}, 1 to 15 characters "
                         f"(INFO carries 15), got {name!r}")
    description = doc["board"].get("description", "")
    if not isinstance(description, str):
        raise BoardError(f"{path}: board.description: expected a string, got {description!r}")
    return Board(
        name=name,
        path=path,
        description=description,
        family=family,
        mcu=_need(path, doc, "board", "mcu", str),
        clock_hz=_whole(path, doc, "board", "clock_hz"),
        flash_bytes=_whole(path, doc, "board", "flash_bytes"),
        ram_bytes=_whole(path, doc, "board", "ram_bytes"),
        cc=_program(path, "toolchain.cc", _need(path, doc, "toolchain", "cc", str)),
        cflags=_strings(path, doc, "toolchain", "cflags", []),
        ldflags=_strings(path, doc, "toolchain", "ldflags", []),
        packages=_strings(path, doc, "toolchain", "packages", []),
        **_build_steps(path, doc),
        i2c=i2c,
        pwm_pins=_pwm_pins(path, doc),
        pwm_frequency_hz=_whole(path, doc, "pwm", "frequency_hz"),
        uart_port=_need(path, doc, "uart", "port", str),
        uart_baud=_baud(path, doc, family),
        uart_rx_buffer=_buffer(path, doc, "rx_buffer", DEFAULT_UART_RX_BUFFER, family),
        uart_tx_buffer=_buffer(path, doc, "tx_buffer", DEFAULT_UART_TX_BUFFER, family),
        flash_methods=_flash_methods(path, doc),
        i2c_buses=buses,
        base_flash_bytes=_whole(path, doc, "board", "base_flash_bytes", 0),
        base_ram_bytes=_whole(path, doc, "board", "base_ram_bytes", 0),
        stack_bytes=_whole(path, doc, "board", "stack_bytes", 0),
        budget=_budget(path, doc),
        **_link(path, doc, family),
    )


def _known_keys(path: Path, where: str, table: dict, keys: set[str]) -> None:
    """Refuse a key the table does not take: a misspelt key would silently take its default."""
    if stray := sorted(set(table) - keys):
        near = difflib.get_close_matches(stray[0], sorted(keys), n=1)
        hint = f"did you mean {near[0]!r}?" if near else f"expected one of: {', '.join(sorted(keys))}"
        raise BoardError(f"{path}: {where}.{stray[0]}: unknown key ({hint})")


def _pwm_pins(path: Path, doc: dict) -> tuple[str, ...]:
    pins = _strings(path, doc, "pwm", "pins")
    twice = next((p for i, p in enumerate(pins) if p in pins[:i]), None)
    if twice is not None:
        raise BoardError(f"{path}: pwm.pins: expected each pin once (one channel per pin), got {twice!r} twice")
    return pins


def _flash_methods(path: Path, doc: dict) -> tuple[FlashMethod, ...]:
    flash = doc.get("flash", [])
    if not isinstance(flash, list) or not all(isinstance(f, dict) for f in flash):
        raise BoardError(f"{path}: flash: expected [[flash]] tables, got {flash!r}")
    methods = []
    for i, f in enumerate(flash):
        where = f"flash[{i}]"
        _known_keys(path, where, f, FLASH_KEYS)
        table = {where: f}
        tool = _need(path, table, where, "tool", str)
        cmd = _strings(path, table, where, "command")
        if not cmd:
            raise BoardError(f"{path}: {where}.command: expected a command, got []")
        methods.append(FlashMethod(tool, cmd, _strings(path, table, where, "packages", [])))
    return tuple(methods)


def _link(path: Path, doc: dict, family: str) -> dict[str, Any]:
    transport = link_transport(path, doc)
    can = can_config(path, doc, family)
    if transport == "can" and can is None:
        raise BoardError(f"{path}: link.transport = \"can\" needs a [can] table (rx, tx, bitrate, clock_hz)")
    return {"transport": transport, "can": can}


def _addresses(path: Path, where: str, v: Any, allowed: range) -> tuple[int, ...]:
    if not isinstance(v, list) or not all(isinstance(a, int) and not isinstance(a, bool) and a in allowed for a in v):
        raise BoardError(f"{path}: {where}: expected a list of 7-bit addresses in 0x{allowed.start:02x}..0x{allowed.stop - 1:02x}, got {v!r}")
    if len(set(v)) != len(v):
        raise BoardError(f"{path}: {where}: an address is listed twice")
    return tuple(v)


def i2c_buses(path: Path, i2c: dict) -> tuple[I2cBus, ...]:
    """The board's I2C buses: ``[[i2c.bus]]`` tables (name, sda, scl, imu_addresses,
    mux_addresses), or the single bus of a board file that gives ``[i2c] bus = "NAME"``."""
    tables = i2c.get("bus", "I2C")
    if isinstance(tables, str):  # one bus, described in [i2c] itself
        tables = [{"name": tables, **{k: i2c[k] for k in ("sda", "scl", "imu_addresses", "mux_addresses") if k in i2c}}]
    if not isinstance(tables, list) or not tables or not all(isinstance(t, dict) for t in tables):
        raise BoardError(f"{path}: i2c.bus: expected [[i2c.bus]] tables (name, sda, scl, imu_addresses, mux_addresses)")
    if len(tables) > MAX_I2C_BUSES:
        raise BoardError(f"{path}: i2c.bus: at most {MAX_I2C_BUSES} buses, got {len(tables)}")
    out: list[I2cBus] = []
    for i, t in enumerate(tables):
        where = f"i2c.bus[{i + 1}]"
        unknown = sorted(set(t) - {"name", "sda", "scl", "imu_addresses", "mux_addresses"})
        if unknown:
            raise BoardError(f"{path}: {where}: unknown key {unknown[0]!r} (expected name, sda, scl, imu_addresses, mux_addresses)")
        name = t.get("name")
        if not isinstance(name, str) or not name:
            raise BoardError(f"{path}: {where}.name: expected a string, got {name!r}")
        if any(b.name == name for b in out):
            raise BoardError(f"{path}: {where}.name: {name!r} names another bus too")
        pins = {k: t.get(k, "") for k in ("sda", "scl")}
        for k, v in pins.items():
            if not isinstance(v, str):
                raise BoardError(f"{path}: {where}.{k}: expected a pin name, got {v!r}")
        addrs = _addresses(path, f"{where}.imu_addresses", t.get("imu_addresses", list(DEFAULT_IMU_ADDRESSES)), range(0x08, 0x70))
        if not addrs:
            raise BoardError(f"{path}: {where}.imu_addresses: expected at least one address")
        muxes = _addresses(path, f"{where}.mux_addresses", t.get("mux_addresses", []), MUX_RANGE)
        out.append(I2cBus(i, name, pins["sda"], pins["scl"], addrs, muxes))
    return tuple(out)


def _budget(path: Path, doc: dict) -> TickBudget | None:
    if "budget" not in doc:
        return None
    values = []
    for key in ("tick_us_base", "tick_us_per_limb"):
        v = _need(path, doc, "budget", key, (int, float))
        if not v >= 0:
            raise BoardError(f"{path}: budget.{key}: expected µs ≥ 0, got {v!r}")
        values.append(float(v))
    if values[0] + values[1] <= 0:
        raise BoardError(f"{path}: budget: tick_us_base + tick_us_per_limb must be above 0 µs")
    measured = _need(path, doc, "budget", "measured", str)
    enforce = doc["budget"].get("enforce", True)
    if not isinstance(enforce, bool):
        raise BoardError(f"{path}: budget.enforce: expected true or false, got {enforce!r}")
    return TickBudget(values[0], values[1], measured, enforce)


def pwm_channel_error(robot: Any, actuator: Any, board_name: str, pins: Sequence[str]) -> str:
    """The one message for an actuator on a PWM channel the board does not have. Channels are
    shown as the robot file writes them (``channel = N``, the board's [pwm] pins in order),
    with the pin each one is; an actuator without a ``channel`` key is said to be on its
    default channel, its position (the file has no ``channel = N`` to quote)."""
    have = ", ".join(f"channel = {i} ({p})" for i, p in enumerate(pins)) or "none"
    if getattr(actuator, "channel_given", True):
        on = f"is on channel = {actuator.channel}"
    else:  # the default: say so, the file has no such line
        k = actuator.channel + 1
        nth = f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"
        on = (f"(the {nth} [[actuator]], no channel key) is on channel {actuator.channel} by default, its "
              "position")
    too_many = ""
    n = len(getattr(robot, "actuators", ()))
    if n > len(pins):  # no renumbering fits: say so, not only which channel is out of range
        too_many = (f"; {robot.name} has {n} actuators and board {board_name} drives at most {len(pins)}: share "
                    f"coils between limbs (several [[limb]]s naming one [[actuator]]) or build for a board with "
                    f"more PWM channels")
    return (f"{robot.where}: actuator {actuator.name!r} {on}, but board {board_name} has {len(pins)} PWM channels: "
            f"{have}{too_many}")
