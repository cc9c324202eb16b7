"""Where each limb's IMU sits on the board's I2C buses, and whether the board can host it.

A robot file may say, per limb, ``imu = { bus = "I2C1", mux = 0x70, channel = 3,
address = 0x68 }`` (every part optional); a board file lists its buses
(``[[i2c.bus]]``: name, pins, the IMU addresses a device may use, the addresses at which
a TCA9548A/PCA9548A multiplexer may sit). ``place_imus`` completes every limb's
placement or raises ``BuildError`` saying why the board cannot host the robot:

1. Limbs that name (part of) a placement get it, the rest filled in: the first bus;
   behind the bus's multiplexer when a channel or mux is named; the first channel and
   address still free.
2. Limbs that name none are placed automatically, the first plan that fits: every bus
   wired directly (addresses on the first bus, then on the second ...), then the first
   bus behind a multiplexer (eight channels, each with the bus's addresses), then the
   second too, and so on. Behind a multiplexer two IMUs share a channel when they can
   (fewer channel switches per tick).

Two IMUs conflict when the firmware can ever see both at one address: the same bus and
address, unless both sit behind the (one) multiplexer of that bus on different channels
(the firmware enables one channel at a time, core/imubus.c). One multiplexer per bus.

``i2c_tick_us`` estimates the bus time of one control tick (every IMU read once, plus
the channel switches) from the bit counts of the transfers; ``check_tick_budget``
refuses a robot whose reads do not fit in ``I2C_TICK_SHARE`` of its tick.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BuildError
from ..names import counted
from ..robot import MUX_CHANNELS, ImuSpec
from .boards import I2cBus, i2c_buses

#: Bit times of one MPU-6050 accelerometer read (write the register pointer, repeated
#: start, read 6 bytes): start + 2 address bytes + 7 data bytes (9 bits each, with ACK)
#: + stop ~ 84 (I2C-bus specification UM10204, byte = 8 bits + ACK).
BITS_PER_IMU_READ = 84
#: Bit times of one multiplexer channel select (address + control byte, TCA9548A datasheet §8.5.4).
BITS_PER_MUX_SELECT = 20
#: The share of a control tick the IMU reads may take (the rest: ψ, sequencer, safety, link).
I2C_TICK_SHARE = 0.75
#: What the firmware's tables hold at most (core/imubus.h): buses and IMUs.
MAX_IMUS = 8


@dataclass(frozen=True)
class ImuPlacement:
    limb: str
    bus: int  # index in the board's [[i2c.bus]] list (0 = hal_i2c_write_read's bus)
    bus_name: str
    mux: int | None  # multiplexer address, None = wired directly
    channel: int | None
    address: int
    automatic: bool  # placed by the build, not by the robot file

    def describe(self) -> str:
        where = f"bus {self.bus_name}"
        if self.mux is not None:
            where += f", multiplexer 0x{self.mux:02x} channel {self.channel}"
        how = " (automatic)" if self.automatic else ""
        return f"limb {self.limb}: IMU at 0x{self.address:02x} on {where}{how}"


def buses_of(board: Any) -> tuple[I2cBus, ...]:
    """A Board's buses, or those of a plain dict board description (tests, renderers)."""
    buses = getattr(board, "i2c_buses", None)
    if buses:
        return tuple(buses)
    i2c = board.get("i2c", {}) if isinstance(board, dict) else getattr(board, "i2c", {})
    name = board.get("name", "board") if isinstance(board, dict) else getattr(board, "name", "board")
    return i2c_buses(Path(str(name)), dict(i2c or {}))


def _conflicts(a: ImuPlacement, b: ImuPlacement) -> bool:
    if a.bus != b.bus or a.address != b.address:
        return False
    return not (a.mux is not None and b.mux is not None and a.channel != b.channel)


def _board_name(board: Any) -> str:
    return str(board.get("name") if isinstance(board, dict) else getattr(board, "name", "board"))


def place_imus(robot: Any, board: Any) -> tuple[ImuPlacement, ...]:
    """Every limb's IMU placement on this board (see the module docstring), or BuildError."""
    buses = buses_of(board)
    bname = _board_name(board)
    limbs = list(robot.limbs)
    if len(limbs) > MAX_IMUS:
        raise BuildError(f"{robot.where}: {len(limbs)} limbs, the firmware reads at most {MAX_IMUS} IMUs")
    taken: list[ImuPlacement] = []
    renamed = _sim_bus_names(robot, board, buses)
    for limb in limbs:
        if limb.imu is not None:
            spec = limb.imu
            if spec.bus in renamed:
                spec = dataclasses.replace(spec, bus=renamed[spec.bus])
            p = _explicit(robot, bname, buses, limb.name, spec, taken)
            taken.append(p)
    auto = [limb.name for limb in limbs if limb.imu is None]
    if auto:
        taken.extend(_automatic(robot, bname, buses, auto, taken))
    by_name = {p.limb: p for p in taken}
    return tuple(by_name[limb.name] for limb in limbs)


def _sim_bus_names(robot: Any, board: Any, buses: Sequence[I2cBus]) -> dict[str, str]:
    """On a simulated board (family ``sim``: what ``proleg sim``, ``run --sim`` and ``learn``
    build for), the bus names a robot file's ``imu`` placements give for a real board, each
    mapped to the simulated bus of the same index: ``{"I2C2": "sim1"}``. A placement wired for
    the bluepill (``bus = "I2C1"``) was refused by every simulator command ("board host-sim has
    no I2C bus 'I2C1'"). Only names that are not the simulated board's own, from the one shipped
    board that has the most of them on a bus index the simulated board has; a name it does not
    have stays, and the placement's own error names it."""
    family = board.get("board", {}).get("family") if isinstance(board, dict) else getattr(board, "family", None)
    if family != "sim":
        return {}
    own = {b.name for b in buses}
    named = {lb.imu.bus for lb in robot.limbs if lb.imu is not None and lb.imu.bus is not None} - own
    if not named:
        return {}
    from .boards import available_boards, load_board

    best: dict[str, str] = {}
    for name in available_boards():
        try:
            other = load_board(name)
        except Exception:  # a board file that does not load is not where the names come from
            continue
        if getattr(other, "family", None) == "sim":
            continue
        index = {b.name: b.index for b in buses_of(other)}
        mapped = {n: buses[index[n]].name for n in sorted(named) if n in index and index[n] < len(buses)}
        if len(mapped) > len(best):
            best = mapped
    return best


def _bus_mux(buses: Sequence[I2cBus], taken: Sequence[ImuPlacement], bus: I2cBus) -> int | None:
    used = {p.mux for p in taken if p.bus == bus.index and p.mux is not None}
    return next(iter(used)) if used else None


def _explicit(robot: Any, bname: str, buses: Sequence[I2cBus], limb: str, spec: ImuSpec,
              taken: Sequence[ImuPlacement]) -> ImuPlacement:
    where = f"{robot.where}: limb {limb}: imu"
    behind = spec.mux is not None or spec.channel is not None
    if spec.bus is not None:
        bus = next((b for b in buses if b.name == spec.bus), None)
        if bus is None:
            names = ", ".join(b.name for b in buses)
            raise BuildError(f"{where}.bus: board {bname} has no I2C bus {spec.bus!r} (it has: {names})")
    elif behind:
        bus = next((b for b in buses if b.mux_addresses), None)
        if bus is None:
            raise BuildError(f"{where}: a multiplexer channel is named, but no bus of board {bname} can carry a multiplexer")
    else:
        bus = buses[0]
    mux = None
    if behind:
        if not bus.mux_addresses:
            raise BuildError(f"{where}: bus {bus.name} of board {bname} carries no multiplexer (no mux_addresses)")
        present = _bus_mux(buses, taken, bus)
        mux = spec.mux if spec.mux is not None else (present if present is not None else bus.mux_addresses[0])
        if mux not in bus.mux_addresses:
            allowed = ", ".join(f"0x{a:02x}" for a in bus.mux_addresses)
            raise BuildError(f"{where}.mux: 0x{mux:02x} is not a multiplexer address of bus {bus.name} ({allowed})")
        if present is not None and present != mux:
            raise BuildError(f"{where}.mux: bus {bus.name} already has the multiplexer at 0x{present:02x} (one per bus)")
    if spec.address is not None and spec.address not in bus.addresses:
        allowed = ", ".join(f"0x{a:02x}" for a in bus.addresses)
        raise BuildError(f"{where}.address: 0x{spec.address:02x} is not an IMU address of bus {bus.name} ({allowed})")
    channels = [spec.channel] if spec.channel is not None else (list(range(MUX_CHANNELS)) if behind else [None])
    addresses = [spec.address] if spec.address is not None else list(bus.addresses)
    clash: ImuPlacement | None = None
    for ch in channels:
        for addr in addresses:
            p = ImuPlacement(limb, bus.index, bus.name, mux, ch, addr, False)
            other = next((q for q in taken if _conflicts(p, q)), None)
            if other is None:
                return p
            clash = clash or other
    assert clash is not None
    raise BuildError(f"{where}: no free place as given ({clash.describe()} is there already)")


def _plans(buses: Sequence[I2cBus]) -> list[tuple[bool, ...]]:
    """Which buses carry a multiplexer, in the order automatic placement tries them."""
    plans = [tuple(False for _ in buses)]
    muxed = [False] * len(buses)
    for b in buses:
        if b.mux_addresses:
            muxed[b.index] = True
            plans.append(tuple(muxed))
    return plans


def _automatic(robot: Any, bname: str, buses: Sequence[I2cBus], names: list[str],
               taken: Sequence[ImuPlacement]) -> list[ImuPlacement]:
    for plan in _plans(buses):
        chosen: list[ImuPlacement] = []
        slots = iter(_slots(buses, plan, taken))
        for name in names:
            for bus, mux, ch, addr in slots:
                p = ImuPlacement(name, bus.index, bus.name, mux, ch, addr, True)
                if not any(_conflicts(p, q) for q in [*taken, *chosen]):
                    chosen.append(p)
                    break
            else:
                break
        if len(chosen) == len(names):
            return chosen
    raise BuildError(
        f"robot {robot.name} has {counted(len(robot.limbs), 'limb')}, each with an IMU, but board {bname} can host at most "
        f"{capacity(buses)} IMUs ({_bus_summary(buses)})"
    )


def _slots(buses: Sequence[I2cBus], plan: tuple[bool, ...], taken: Sequence[ImuPlacement]):
    for bus in buses:
        if plan[bus.index]:
            mux = _bus_mux(buses, taken, bus)
            mux = mux if mux is not None else bus.mux_addresses[0]
            for ch in range(MUX_CHANNELS):
                for addr in bus.addresses:
                    yield bus, mux, ch, addr
        else:
            for addr in bus.addresses:
                yield bus, None, None, addr


def capacity(buses: Sequence[I2cBus]) -> int:
    """IMUs the buses can carry, each behind a multiplexer where one may sit."""
    return min(MAX_IMUS, sum(len(b.addresses) * (MUX_CHANNELS if b.mux_addresses else 1) for b in buses))


def _bus_summary(buses: Sequence[I2cBus]) -> str:
    parts = []
    for b in buses:
        addrs = "/".join(f"0x{a:02x}" for a in b.addresses)
        mux = "a multiplexer may extend it" if b.mux_addresses else "no multiplexer"
        parts.append(f"bus {b.name}: {addrs}, {mux}")
    return "; ".join(parts)


def mux_selects_per_tick(placements: Sequence[ImuPlacement]) -> int:
    """Channel switches in one round of reads in limb order (the round repeats every tick)."""
    current: dict[int, int | None] = {}
    for _ in range(2):  # the second round starts from the channels the first left
        switches = 0
        for p in placements:
            if p.mux is not None and current.get(p.bus) != p.channel:
                current[p.bus] = p.channel
                switches += 1
    return switches


def i2c_tick_us(placements: Sequence[ImuPlacement], i2c_hz: int) -> float:
    """Bus time of one control tick: every IMU read once, plus the channel switches."""
    bits = BITS_PER_IMU_READ * len(placements) + BITS_PER_MUX_SELECT * mux_selects_per_tick(placements)
    return bits * 1e6 / i2c_hz


def max_tick_hz(placements: Sequence[ImuPlacement], i2c_hz: int) -> int:
    """The highest whole tick rate whose I2C reads fit ``I2C_TICK_SHARE`` of its period."""
    return int(I2C_TICK_SHARE * 1e6 / i2c_tick_us(placements, i2c_hz))


def check_tick_budget(robot: Any, bname: str, placements: Sequence[ImuPlacement], i2c_hz: int) -> None:
    tick_us = 1e6 / robot.control.tick_hz
    need = i2c_tick_us(placements, i2c_hz)
    if need > I2C_TICK_SHARE * tick_us:
        most = max_tick_hz(placements, i2c_hz)
        raise BuildError(
            f"{robot.where}: reading {counted(len(placements), 'IMU')} ({counted(mux_selects_per_tick(placements), 'channel switch')}) "
            f"takes about {need:.0f} us of I2C at {i2c_hz // 1000} kHz per tick on board {bname}, more than "
            f"{I2C_TICK_SHARE:.0%} of the {tick_us:.0f} us tick: set control.tick_hz to at most {most}"
        )


def sim_imu_keys(placements: Sequence[ImuPlacement]) -> tuple[int, ...]:
    """The key the host-sim ABI (sim_imu_set_truth ...) takes for each limb's IMU: its
    address when it sits directly on bus 0, else 0x80 | limb index (hal_sim.c)."""
    return tuple(
        p.address if p.bus == 0 and p.mux is None else 0x80 | i for i, p in enumerate(placements)
    )
