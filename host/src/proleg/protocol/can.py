"""How protocol messages travel on a classic CAN bus (8-byte frames, 11-bit identifiers).

Identifier layout — several robots (nodes) can share one bus::

    arbitration_id = base + (slot << 4) + node        base default 0x100, node 0..15

    slot  name              direction    content
    0     CMD               host→robot   segmented frame (any command)
    1     REPLY             robot→host   segmented frame (INFO, ACK, NACK, STATS, EVENT)
    2     TELEMETRY_A       robot→host   seq u16 | time_ms u32 | measured u16
    3     TELEMETRY_B       robot→host   target u16 | gait u8 | direction u8 | step u8 |
                                         flags u16 | psi_count u4 | duty_count u4
    4     TELEMETRY_PSI_0   robot→host   psi[0..3] i16 (0.01°)
    5     TELEMETRY_PSI_1   robot→host   psi[4..7] i16
    6     TELEMETRY_DUTY_0  robot→host   duty[0..3] u16 (permyriad)
    7     TELEMETRY_DUTY_1  robot→host   duty[4..7] u16
    8     EVENT             robot→host   time_ms u32 | kind u8 | code u8 | detail u16

All little-endian (Intel). TELEMETRY uses fixed signal layouts (``proleg dbc`` writes a DBC
describing them, so any CAN tool can plot a robot); a frame is sent only when it carries a
used element (2 limbs, 2 channels → A, B, PSI_0, DUTY_0). The receiver assembles one TELEMETRY
from A, B and then the PSI/DUTY frames B announces; a new A drops an unfinished one.

Segmented frames carry the protocol's unframed bytes ``msg_id | payload | crc16`` (the CRC
stays, end to end), always 8 bytes: byte 0 = segment index (bits 0–3) | (data bytes − 1) << 4
(bits 4–6) | 0x80 on the last segment; bytes 1..7 = the next up to 7 bytes, zero-padded.
A segment out of order drops the message being assembled. EVENT (exactly 8 payload bytes)
travels in its own fixed frame (slot 8) so a CAN tool decodes events and faults with the DBC;
the CRC is left out there as for TELEMETRY (CAN's own CRC covers the frame).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from cobs import cobs

from ..errors import LinkError, UsageError
from .codec import FrameDecoder, Message, encode
from .definition import BY_NAME, CHANNEL_CEILING, LIMB_CEILING

DEFAULT_BASE = 0x100
MAX_NODE = 15
SLOT_CMD = 0
SLOT_REPLY = 1
SLOT_EVENT = 8
N_SLOTS = 9
SEGMENT_DATA = 7
LAST_SEGMENT = 0x80


@dataclass(frozen=True)
class Signal:
    """One signal of a fixed CAN frame: ``field`` of TELEMETRY (``index`` into an array)."""

    name: str
    field: str
    index: int | None
    start_bit: int  # Intel (little-endian) start bit
    length: int  # bits
    signed: bool
    scale: float = 1.0
    unit: str = ""


@dataclass(frozen=True)
class FixedFrame:
    slot: int
    name: str
    signals: tuple[Signal, ...]
    #: the frame is sent when this many array elements are in use (0 = always): (field, first index)
    needs: tuple[str, int] | None = None


def _array_frame(slot: int, name: str, field: str, first: int, signed: bool, scale: float, unit: str) -> FixedFrame:
    sigs = tuple(Signal(f"{field}_{first + k}", field, first + k, 16 * k, 16, signed, scale, unit) for k in range(4))
    return FixedFrame(slot, name, sigs, (field, first))


TELEMETRY_FRAMES: tuple[FixedFrame, ...] = (
    FixedFrame(2, "TELEMETRY_A", (
        Signal("seq", "seq", None, 0, 16, False),
        Signal("time_ms", "time_ms", None, 16, 32, False, 1.0, "ms"),
        Signal("measured", "measured", None, 48, 16, False),
    )),
    FixedFrame(3, "TELEMETRY_B", (
        Signal("target", "target", None, 0, 16, False),
        Signal("gait", "gait", None, 16, 8, False),
        Signal("direction", "direction", None, 24, 8, False),
        Signal("step", "step", None, 32, 8, False),
        Signal("flags", "flags", None, 40, 16, False),
        Signal("psi_count", "psi_count", None, 56, 4, False),
        Signal("duty_count", "duty_count", None, 60, 4, False),
    )),
    _array_frame(4, "TELEMETRY_PSI_0", "psi", 0, True, 0.01, "deg"),
    _array_frame(5, "TELEMETRY_PSI_1", "psi", 4, True, 0.01, "deg"),
    _array_frame(6, "TELEMETRY_DUTY_0", "duty", 0, False, 0.01, "%"),
    _array_frame(7, "TELEMETRY_DUTY_1", "duty", 4, False, 0.01, "%"),
)
EVENT_FRAME = FixedFrame(SLOT_EVENT, "EVENT", (
    Signal("time_ms", "time_ms", None, 0, 32, False, 1.0, "ms"),
    Signal("kind", "kind", None, 32, 8, False),
    Signal("code", "code", None, 40, 8, False),
    Signal("detail", "detail", None, 48, 16, False),
))
_BY_SLOT = {f.slot: f for f in TELEMETRY_FRAMES}
_TELEMETRY_SCALARS = ("seq", "time_ms", "measured", "target", "gait", "direction", "step", "flags")
_TELEMETRY_ID = BY_NAME["TELEMETRY"].id


def _check_layout() -> None:
    """The fixed layout must cover TELEMETRY as the protocol defines it."""
    spec = BY_NAME["TELEMETRY"]
    names = [f.name for f in spec.fields]
    if names != [*_TELEMETRY_SCALARS, "psi", "duty"]:
        raise RuntimeError(f"TELEMETRY fields changed ({names}); update proleg.protocol.can")
    if LIMB_CEILING > 8 or CHANNEL_CEILING > 8:
        raise RuntimeError("CAN telemetry layout carries at most 8 limbs and 8 channels")


_check_layout()


@dataclass(frozen=True)
class CanIds:
    """The identifier scheme of one robot on the bus."""

    node: int = 0
    base: int = DEFAULT_BASE

    def __post_init__(self) -> None:
        if not 0 <= self.node <= MAX_NODE:
            raise UsageError(f"CAN node id {self.node} outside 0..{MAX_NODE}")
        if not 0 <= self.base or self.base + ((N_SLOTS - 1) << 4) + MAX_NODE > 0x7FF:
            raise UsageError(f"CAN base id {self.base:#x} leaves no room for 11-bit ids (base ≤ 0x770)")

    def id(self, slot: int) -> int:
        return self.base + (slot << 4) + self.node

    def slot(self, arbitration_id: int) -> int | None:
        """The slot of a frame addressed to/from this node, else None."""
        off = arbitration_id - self.base
        if off < 0 or off >= N_SLOTS << 4 or (off & 0x0F) != self.node:
            return None
        return off >> 4


# --------------------------------------------------------------------------- message → frames
def _put(buf: bytearray, sig: Signal, value: int) -> None:
    mask = (1 << sig.length) - 1
    word = int.from_bytes(buf, "little")
    word |= (value & mask) << sig.start_bit
    buf[:] = word.to_bytes(8, "little")


def _get(data: bytes, sig: Signal) -> int:
    v = (int.from_bytes(data.ljust(8, b"\0"), "little") >> sig.start_bit) & ((1 << sig.length) - 1)
    if sig.signed and v & (1 << (sig.length - 1)):
        v -= 1 << sig.length
    return v


def telemetry_frames(msg: Message, ids: CanIds) -> list[tuple[int, bytes]]:
    """The fixed frames of one TELEMETRY message."""
    values: dict[str, int] = {k: int(msg[k]) for k in _TELEMETRY_SCALARS}
    psi = tuple(msg["psi"])
    duty = tuple(msg["duty"])
    values["psi_count"] = len(psi)
    values["duty_count"] = len(duty)
    arrays = {"psi": psi, "duty": duty}
    out: list[tuple[int, bytes]] = []
    for frame in TELEMETRY_FRAMES:
        if frame.needs is not None and len(arrays[frame.needs[0]]) <= frame.needs[1]:
            continue
        buf = bytearray(8)
        for sig in frame.signals:
            if sig.index is None:
                v = values[sig.field]
            else:
                arr = arrays[sig.field]
                v = int(arr[sig.index]) if sig.index < len(arr) else 0
            _put(buf, sig, v)
        out.append((ids.id(frame.slot), bytes(buf)))
    return out


def segment_frames(raw: bytes, arbitration_id: int) -> list[tuple[int, bytes]]:
    """``raw`` (msg_id | payload | crc, 1..64 bytes) cut into 8-byte segments."""
    chunks = [raw[i:i + SEGMENT_DATA] for i in range(0, len(raw), SEGMENT_DATA)]
    if not chunks or len(chunks) > 16:
        raise LinkError(f"cannot segment a {len(raw)}-byte frame onto CAN")
    out = []
    for k, c in enumerate(chunks):
        head = k | ((len(c) - 1) << 4) | (LAST_SEGMENT if k == len(chunks) - 1 else 0)
        out.append((arbitration_id, bytes([head]) + c.ljust(SEGMENT_DATA, b"\0")))
    return out


def message_frames(msg: Message, ids: CanIds, *, from_host: bool) -> list[tuple[int, bytes]]:
    """The CAN frames that carry one message."""
    if not from_host and msg.name == "TELEMETRY":
        return telemetry_frames(msg, ids)
    if not from_host and msg.name == "EVENT":
        buf = bytearray(8)
        for sig in EVENT_FRAME.signals:
            _put(buf, sig, int(msg[sig.field]))
        return [(ids.id(SLOT_EVENT), bytes(buf))]
    wire = encode(msg)
    raw = cobs.decode(wire[:-1])
    return segment_frames(raw, ids.id(SLOT_CMD if from_host else SLOT_REPLY))


class WireToCan:
    """Wire bytes (COBS frames, possibly split anywhere) → CAN frames."""

    def __init__(self, ids: CanIds, *, from_host: bool, max_limbs: int = LIMB_CEILING,
                 max_channels: int = CHANNEL_CEILING):
        self.ids = ids
        self.from_host = from_host
        self.decoder = FrameDecoder(max_limbs=max_limbs, max_channels=max_channels)

    def feed(self, data: bytes) -> list[tuple[int, bytes]]:
        out: list[tuple[int, bytes]] = []
        for msg in self.decoder.feed(data):
            out.extend(message_frames(msg, self.ids, from_host=self.from_host))
        return out


# --------------------------------------------------------------------------- frames → wire bytes
class CanToWire:
    """CAN frames of one node and direction → wire bytes (COBS frames) the codec decodes.

    ``dropped`` counts messages lost in assembly (a missing or out-of-order frame).
    """

    def __init__(self, ids: CanIds, *, from_host: bool):
        self.ids = ids
        self.seg_slot = SLOT_CMD if from_host else SLOT_REPLY
        self.accept_telemetry = not from_host
        self.dropped = 0
        self._seg = bytearray()
        self._seg_next = 0
        self._tel: dict[str, int] | None = None
        self._psi: list[int] = []
        self._duty: list[int] = []
        self._missing: list[int] = []

    def feed(self, arbitration_id: int, data: bytes) -> bytes:
        """Wire bytes completed by this frame (``b""`` for most frames)."""
        slot = self.ids.slot(arbitration_id)
        if slot is None:
            return b""
        if slot == self.seg_slot:
            return self._segment(bytes(data))
        if self.accept_telemetry and slot == SLOT_EVENT:
            return encode(Message("EVENT", {s.field: _get(bytes(data), s) for s in EVENT_FRAME.signals}))
        if self.accept_telemetry and slot in _BY_SLOT:
            return self._telemetry(slot, bytes(data))
        return b""

    def _segment(self, data: bytes) -> bytes:
        if not data:
            return b""
        index, size, last = data[0] & 0x0F, ((data[0] >> 4) & 0x07) + 1, bool(data[0] & LAST_SEGMENT)
        if index == 0:
            if self._seg_next:
                self.dropped += 1
            self._seg = bytearray()
        elif index != self._seg_next:
            if self._seg_next:
                self.dropped += 1
            self._seg_next = 0
            return b""
        self._seg += data[1:1 + size]
        self._seg_next = index + 1
        if not last:
            return b""
        raw, self._seg, self._seg_next = bytes(self._seg), bytearray(), 0
        return cobs.encode(raw) + b"\0"

    def _telemetry(self, slot: int, data: bytes) -> bytes:
        frame = _BY_SLOT[slot]
        if slot == 2:
            if self._tel is not None:
                self.dropped += 1
            self._tel = {s.field: _get(data, s) for s in frame.signals}
            self._missing = [3]
            return b""
        if self._tel is None or not self._missing or self._missing[0] != slot:
            if self._tel is not None:
                self.dropped += 1
            self._tel = None
            return b""
        self._missing.pop(0)
        if slot == 3:
            self._tel.update({s.field: _get(data, s) for s in frame.signals})
            n_psi, n_duty = self._tel["psi_count"], self._tel["duty_count"]
            if n_psi > LIMB_CEILING or n_duty > CHANNEL_CEILING:
                self.dropped += 1
                self._tel = None
                return b""
            self._psi, self._duty = [], []
            self._missing = [4 + k for k in range((n_psi + 3) // 4)] + [6 + k for k in range((n_duty + 3) // 4)]
        else:
            target = self._psi if frame.signals[0].field == "psi" else self._duty
            target.extend(_get(data, s) for s in frame.signals)
        if self._missing:
            return b""
        tel, self._tel = self._tel, None
        fields = {k: tel[k] for k in _TELEMETRY_SCALARS}
        fields["psi"] = tuple(self._psi[: tel["psi_count"]])
        fields["duty"] = tuple(self._duty[: tel["duty_count"]])
        return encode(Message("TELEMETRY", fields))


def iter_slots() -> Iterator[tuple[int, str]]:
    """(slot, frame name) of every frame kind, for documentation and the DBC."""
    yield SLOT_CMD, "CMD"
    yield SLOT_REPLY, "REPLY"
    for f in TELEMETRY_FRAMES:
        yield f.slot, f.name
    yield SLOT_EVENT, EVENT_FRAME.name


def frames_text(frames: Iterable[tuple[int, bytes]]) -> str:
    """``"123#0102..."`` lines (can-utils' cansend notation), for debugging."""
    return "\n".join(f"{i:03X}#{d.hex().upper()}" for i, d in frames)


