"""A board's CAN link: the ``[link]`` and ``[can]`` tables of a board file, and the bit
timing the firmware's CAN controller is given.

``[link] transport`` is ``"uart"`` (the default: the host link on the board's UART) or
``"can"`` (the host link on the board's CAN controller, framed as ``proleg.protocol.can``
lays messages out). A CAN board file has a ``[can]`` table::

    [can]
    rx = "PA11"              # the controller's pins; the HAL family's family.toml lists the pairs it can route
    tx = "PA12"
    bitrate = 500000         # bit/s on the bus
    clock_hz = 36000000      # the controller's clock (STM32F1: PCLK1, the APB1 bus)
    sample_point = 0.875     # where in the bit the controller samples (CiA 301's recommendation)
    node = 0                 # this robot's node id, 0..15 (proleg.protocol.can.CanIds)
    base_id = 0x100          # the first identifier of the scheme
    tx_frames = 32           # the firmware's transmit queue, frames (a power of two, 8..128)

Bit timing (RM0008 §24.7.7, "Bit timing", Figure 232): a bit is ``1 + TS1 + TS2`` time
quanta of ``BRP × (1 / clock)`` each — the synchronisation segment is one quantum, bit
segment 1 (propagation + phase 1) ``TS1`` quanta (1..16), bit segment 2 ``TS2`` quanta
(1..8; at least 2 here, see TS2_RANGE); the sample point is at the end of segment 1; ``BRP`` is 1..1024; the
resynchronisation jump width ``SJW`` is 1..4 quanta and at most ``TS2``. ``CAN_BTR`` holds
each minus one: BRP in bits 9:0, TS1 in 19:16, TS2 in 22:20, SJW in 25:24 (RM0008 §24.9.2).
``bit_timing`` picks the exact division with the sample point nearest the one asked for
(more quanta per bit on a tie: finer resynchronisation), and refuses a bit rate the clock
cannot divide to exactly.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import BoardError

TRANSPORTS = ("uart", "can")
#: RM0008 §24.9.2 CAN_BTR field ranges (values, not the register's minus-one encoding)
BRP_RANGE = range(1, 1025)
TS1_RANGE = range(1, 17)
TS2_RANGE = range(2, 9)  # the register allows 1; phase segment 2 must cover the information
#                          processing time, 2 quanta (ISO 11898-1 §11.3.1.2, "IPT ≤ 2 tq")
SJW_MAX = 4
#: A bit of at least 8 quanta (1 + TS1 + TS2 ≥ 8) leaves room to place the sample point;
#: at most 25 (1 + 16 + 8).
MIN_QUANTA, MAX_QUANTA = 8, 25
#: The identifier scheme's limits (proleg.protocol.can): 9 slots of 16 nodes above base.
MAX_NODE = 15
MAX_BASE = 0x7FF - (8 << 4) - MAX_NODE


@dataclass(frozen=True)
class BitTiming:
    clock_hz: int
    brp: int  # prescaler: a quantum is brp clock periods
    ts1: int  # quanta
    ts2: int
    sjw: int

    @property
    def quanta(self) -> int:
        return 1 + self.ts1 + self.ts2

    @property
    def bitrate(self) -> float:
        return self.clock_hz / (self.brp * self.quanta)

    @property
    def sample_point(self) -> float:
        return (1 + self.ts1) / self.quanta

    @property
    def btr(self) -> int:
        """The CAN_BTR value (normal mode: LBKM = SILM = 0)."""
        return (self.brp - 1) | (self.ts1 - 1) << 16 | (self.ts2 - 1) << 20 | (self.sjw - 1) << 24

    def describe(self) -> str:
        return (f"{self.bitrate:.0f} bit/s from {self.clock_hz} Hz: BRP {self.brp}, {self.quanta} quanta "
                f"(1 + TS1 {self.ts1} + TS2 {self.ts2}), SJW {self.sjw}, sample point {100 * self.sample_point:.1f} %")


def bit_timing(clock_hz: int, bitrate: int, sample_point: float = 0.875) -> BitTiming:
    """The CAN bit timing for ``bitrate`` from a controller clock of ``clock_hz``; ``ValueError``
    when no BRP / TS1 / TS2 divides the clock to exactly that bit rate."""
    if clock_hz <= 0 or bitrate <= 0:
        raise ValueError(f"clock {clock_hz} Hz and bit rate {bitrate} bit/s must be positive")
    best: tuple[float, int, BitTiming] | None = None
    for quanta in range(MIN_QUANTA, MAX_QUANTA + 1):
        if clock_hz % (bitrate * quanta):
            continue
        brp = clock_hz // (bitrate * quanta)
        if brp not in BRP_RANGE:
            continue
        for ts2 in TS2_RANGE:
            ts1 = quanta - 1 - ts2
            if ts1 not in TS1_RANGE:
                continue
            t = BitTiming(clock_hz, brp, ts1, ts2, min(SJW_MAX, ts2))
            key = (abs(t.sample_point - sample_point), -quanta, t)
            if best is None or key[:2] < best[:2]:
                best = key
    if best is None:
        reachable = [r for r in STANDARD_RATES if _exact(clock_hz, r)]
        hint = f" (standard rates it can: {', '.join(str(r) for r in reachable)})" if reachable else ""
        raise ValueError(f"{bitrate} bit/s is not reachable exactly from a {clock_hz} Hz CAN clock with "
                         f"{MIN_QUANTA}..{MAX_QUANTA} quanta per bit{hint}")
    return best[2]


STANDARD_RATES = (1_000_000, 800_000, 500_000, 250_000, 125_000, 100_000, 50_000, 20_000, 10_000)


def _exact(clock_hz: int, bitrate: int) -> bool:
    return any(clock_hz % (bitrate * q) == 0 and clock_hz // (bitrate * q) in BRP_RANGE
               for q in range(MIN_QUANTA, MAX_QUANTA + 1))


@dataclass(frozen=True)
class CanConfig:
    """A board's ``[can]`` table, checked."""

    rx: str
    tx: str
    bitrate: int
    clock_hz: int
    sample_point: float
    node: int
    base_id: int
    tx_frames: int
    timing: BitTiming
    remap: int  # the HAL family's routing of the (rx, tx) pair (STM32F1: AFIO_MAPR CAN_REMAP)

    @property
    def pins(self) -> str:
        return f"{self.rx}/{self.tx}"


_KEYS = {"rx", "tx", "bitrate", "clock_hz", "sample_point", "node", "base_id", "tx_frames"}


def _int(path: Path, t: dict, key: str, default: Any, lo: int, hi: int) -> int:
    v = t.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
        raise BoardError(f"{path}: can.{key}: expected a whole number in {lo}..{hi}, got {v!r}")
    return v


def family_can_pins(family: str) -> dict[str, int]:
    """``"RX/TX"`` (upper case) -> routing value, from the family's ``[can] pins`` table
    (``"any"`` for a family that takes any names: then {} and every pair routes as 0)."""
    from .families import hal_root

    spec = hal_root() / family / "family.toml"
    doc = tomllib.loads(spec.read_text(encoding="utf-8")) if spec.is_file() else {}
    pins = doc.get("can", {}).get("pins")
    if pins == "any":
        return {}
    if not isinstance(pins, dict) or not pins:
        raise BoardError(f"HAL family {family!r} has no CAN controller ({spec}: no [can] pins table)")
    return {str(k).upper(): int(v) for k, v in pins.items()}


def link_transport(path: Path, doc: dict) -> str:
    link = doc.get("link", {})
    if not isinstance(link, dict):
        raise BoardError(f"{path}: link: expected a table")
    unknown = sorted(set(link) - {"transport"})
    if unknown:
        raise BoardError(f"{path}: link: unknown key {unknown[0]!r} (expected transport)")
    transport = link.get("transport", "uart")
    if transport not in TRANSPORTS:
        raise BoardError(f"{path}: link.transport: expected one of {', '.join(TRANSPORTS)}, got {transport!r}")
    return transport


def can_config(path: Path, doc: dict, family: str) -> CanConfig | None:
    """The checked ``[can]`` table (None when the board file has none); ``BoardError`` naming
    the file and key for anything wrong, an unreachable bit rate included."""
    t = doc.get("can")
    if t is None:
        return None
    if not isinstance(t, dict):
        raise BoardError(f"{path}: can: expected a table")
    unknown = sorted(set(t) - _KEYS)
    if unknown:
        raise BoardError(f"{path}: can: unknown key {unknown[0]!r} (expected {', '.join(sorted(_KEYS))})")
    rx, tx = t.get("rx"), t.get("tx")
    if not isinstance(rx, str) or not isinstance(tx, str) or not rx or not tx:
        raise BoardError(f"{path}: can.rx / can.tx: expected pin names, got {rx!r} / {tx!r}")
    routes = family_can_pins(family)
    pair = f"{rx}/{tx}".upper()
    if routes and pair not in routes:
        raise BoardError(f"{path}: can.rx / can.tx: {rx}/{tx} is not a pin pair the {family} HAL routes the CAN "
                         f"controller to (expected one of: {', '.join(sorted(routes))})")
    bitrate = _int(path, t, "bitrate", None, 10_000, 1_000_000)
    clock = _int(path, t, "clock_hz", None, 1, 1_000_000_000)
    sp = t.get("sample_point", 0.875)
    if isinstance(sp, bool) or not isinstance(sp, (int, float)) or not 0.5 <= sp <= 0.95:
        raise BoardError(f"{path}: can.sample_point: expected a fraction of the bit in 0.5..0.95, got {sp!r}")
    try:
        timing = bit_timing(clock, bitrate, float(sp))
    except ValueError as e:
        raise BoardError(f"{path}: can.bitrate: {e}") from None
    frames = _int(path, t, "tx_frames", 32, 8, 128)
    if frames & (frames - 1):
        raise BoardError(f"{path}: can.tx_frames: expected a power of two, got {frames}")
    return CanConfig(rx=rx, tx=tx, bitrate=bitrate, clock_hz=clock, sample_point=float(sp),
                     node=_int(path, t, "node", 0, 0, MAX_NODE), base_id=_int(path, t, "base_id", 0x100, 0, MAX_BASE),
                     tx_frames=frames, timing=timing, remap=routes.get(pair, 0))


#: Bits a classic data frame with 8 data bytes and an 11-bit identifier occupies on the bus
#: at most: 111 bits of frame (SOF, arbitration, control, data, CRC, ACK, EOF), up to 24 stuff
#: bits (one per four bits of the 98 stuffed ones), 3 of interframe space (ISO 11898-1).
FRAME_BITS = 111 + 24 + 3


def telemetry_frames(limbs: int, actuators: int) -> int:
    """CAN frames of one TELEMETRY message (proleg.protocol.can: A, B, ψ and duty frames)."""
    return 2 + (limbs + 3) // 4 + (actuators + 3) // 4
