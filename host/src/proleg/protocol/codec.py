"""Python codec of the link protocol, driven by ``definition.MESSAGES``.

Frame: ``COBS(msg_id | payload | crc16-le) 0x00`` (see ``definition`` and ARCHITECTURE.md).

- ``encode(msg) -> bytes``: one complete wire frame; raises ``ProtocolError`` on a message
  that does not fit the definition (unknown name, missing/extra field, value out of range,
  array too long, text too long or not ASCII).
- ``FrameDecoder.feed(data) -> list[Message]``: streaming decoder. Never raises on input
  bytes; every broken frame increments exactly one counter (``framing_errors``,
  ``crc_errors``, ``unknown_ids``, ``bad_length``, ``bad_value``) in the same order of checks
  as the C runtime, and resynchronises on the next 0x00, so valid frames around garbage
  still decode.
- ``pack``/``unpack``: the layer below framing (msg_id + payload, no CRC, no COBS).

Each message is compiled once into ``struct.Struct`` segments (fixed runs of scalars/text,
and counted arrays), so decoding is a few C calls per frame.
"""

from __future__ import annotations

import struct
from binascii import crc_hqx
from dataclasses import dataclass
from typing import Any, Union

from cobs import cobs as _cobs

from proleg.errors import ProtocolError
from proleg.protocol.definition import (
    BY_NAME,
    CHANNEL_CEILING,
    LIMB_CEILING,
    MAX_ENCODED_FRAME,
    MAX_FRAME,
    MESSAGES,
    TYPES,
    MessageSpec,
)

Value = Union[int, str, tuple[int, ...]]

_cobs_encode = _cobs.encode
_cobs_decode = _cobs.decode
_DecodeError = _cobs.DecodeError
_MAX_BODY = MAX_ENCODED_FRAME - 1  # encoded bytes between delimiters


@dataclass(slots=True)
class Message:
    """A decoded or to-be-encoded message: ``name`` from the definition, ``fields`` by name.

    Scalars are ints, text fields str, variable arrays tuples of ints (their count is implied
    by the length). ``msg.psi`` is ``msg.fields["psi"]``.
    """

    name: str
    fields: dict[str, Value]

    @classmethod
    def new(cls, name: str, **fields: Value) -> "Message":
        return cls(name, fields)

    @property
    def spec(self) -> MessageSpec:
        return BY_NAME[self.name]

    @property
    def id(self) -> int:
        return BY_NAME[self.name].id

    def __getitem__(self, key: str) -> Value:
        return self.fields[key]

    def __getattr__(self, key: str) -> Any:
        if key in ("name", "fields") or key.startswith("__"):
            raise AttributeError(key)
        try:
            return self.fields[key]
        except KeyError:
            raise AttributeError(f"{self.name} has no field {key!r}") from None


class _Reject(Exception):
    """Internal: a CRC-valid frame does not fit the definition; ``counter`` names why."""

    def __init__(self, counter: str, why: str) -> None:
        super().__init__(why)
        self.counter = counter


@dataclass(frozen=True, slots=True)
class _Fixed:
    struct: struct.Struct
    names: tuple[str, ...]
    text: tuple[int, ...]  # positions (in names) of text fields
    lo: tuple[int, ...]  # value ranges for encode validation (text: 0/length-1)
    hi: tuple[int, ...]


@dataclass(frozen=True, slots=True)
class _Array:
    name: str
    fmt: str  # struct format char of one element
    size: int
    max: int
    lo: int
    hi: int
    structs: tuple[struct.Struct, ...]  # structs[n] unpacks n elements


_Segment = Union[_Fixed, _Array]


def _compile(spec: MessageSpec, max_limbs: int, max_channels: int) -> tuple[_Segment, ...]:
    segments: list[_Segment] = []
    fmt, names, text, lo, hi = "<", [], [], [], []

    def flush() -> None:
        nonlocal fmt, names, text, lo, hi
        if names:
            segments.append(_Fixed(struct.Struct(fmt), tuple(names), tuple(text), tuple(lo), tuple(hi)))
        fmt, names, text, lo, hi = "<", [], [], [], []

    for f in spec.fields:
        size, char, vmin, vmax = TYPES[f.type]
        if f.length is not None:
            text.append(len(names))
            fmt += f"{f.length}s"
            lo.append(0)
            hi.append(f.length - 1)
            names.append(f.name)
        elif f.is_array:
            flush()
            n = f.resolved_max(max_limbs, max_channels)
            structs = tuple(struct.Struct(f"<{k}{char}") for k in range(n + 1))
            segments.append(_Array(f.name, char, size, n, vmin, vmax, structs))
        else:
            fmt += char
            lo.append(vmin)
            hi.append(vmax)
            names.append(f.name)
    flush()
    return tuple(segments)


class _Plan:
    """One message compiled for one build's limits."""

    __slots__ = ("spec", "name", "id", "segments", "fixed_only", "size", "names")

    def __init__(self, spec: MessageSpec, max_limbs: int, max_channels: int) -> None:
        self.spec = spec
        self.name = spec.name
        self.id = spec.id
        self.segments = _compile(spec, max_limbs, max_channels)
        self.fixed_only = all(isinstance(s, _Fixed) for s in self.segments)
        self.size = sum(s.struct.size for s in self.segments if isinstance(s, _Fixed))
        self.names = frozenset(f.name for f in spec.fields)

    def unpack(self, raw: bytes, end: int) -> Message:
        """Decode ``raw[1:end]`` (the payload); raises _Reject."""
        if self.fixed_only:
            if end - 1 != self.size:
                raise _Reject("bad_length", f"{self.name}: payload {end - 1} bytes, expected {self.size}")
            if not self.segments:
                return Message(self.name, {})
            seg = self.segments[0]
            values = seg.struct.unpack_from(raw, 1)
            if seg.text:
                values = _fix_text(values, seg.text)
            return Message(self.name, dict(zip(seg.names, values)))
        fields: dict[str, Value] = {}
        pos = 1
        for seg in self.segments:
            if isinstance(seg, _Fixed):
                size = seg.struct.size
                if end - pos < size:
                    raise _Reject("bad_length", f"{self.name}: payload too short")
                values = seg.struct.unpack_from(raw, pos)
                if seg.text:
                    values = _fix_text(values, seg.text)
                fields.update(zip(seg.names, values))
                pos += size
            else:
                if pos >= end:
                    raise _Reject("bad_length", f"{self.name}: payload too short for {seg.name} count")
                n = raw[pos]
                pos += 1
                if n > seg.max:
                    raise _Reject("bad_value", f"{self.name}.{seg.name}: count {n} > max {seg.max}")
                need = n * seg.size
                if end - pos < need:
                    raise _Reject("bad_length", f"{self.name}.{seg.name}: payload too short")
                fields[seg.name] = seg.structs[n].unpack_from(raw, pos)
                pos += need
        if pos != end:
            raise _Reject("bad_length", f"{self.name}: {end - pos} bytes after the last field")
        return Message(self.name, fields)

    def pack(self, msg: Message) -> bytes:
        fields = msg.fields
        if fields.keys() != self.names:
            missing = sorted(self.names - fields.keys())
            extra = sorted(fields.keys() - self.names)
            raise ProtocolError(f"{self.name}: missing fields {missing}, unknown fields {extra}")
        parts = [bytes((self.id,))]
        for seg in self.segments:
            if isinstance(seg, _Fixed):
                values: list[Any] = []
                for i, name in enumerate(seg.names):
                    v = fields[name]
                    if i in seg.text:
                        values.append(_text_bytes(self.name, name, v, seg.hi[i]))
                        continue
                    _check_int(self.name, name, v, seg.lo[i], seg.hi[i])
                    values.append(v)
                parts.append(seg.struct.pack(*values))
            else:
                v = fields[seg.name]
                if not isinstance(v, (tuple, list)):
                    raise ProtocolError(f"{self.name}.{seg.name}: expected a sequence of ints, got {v!r}")
                if len(v) > seg.max:
                    raise ProtocolError(f"{self.name}.{seg.name}: {len(v)} elements, at most {seg.max}")
                for x in v:
                    _check_int(self.name, seg.name, x, seg.lo, seg.hi)
                parts.append(bytes((len(v),)))
                parts.append(seg.structs[len(v)].pack(*v))
        return b"".join(parts)


def _fix_text(values: tuple[Any, ...], text: tuple[int, ...]) -> tuple[Any, ...]:
    out = list(values)
    for i in text:
        out[i] = out[i].split(b"\0", 1)[0].decode("latin-1")
    return tuple(out)


def _text_bytes(msg: str, name: str, v: Any, max_chars: int) -> bytes:
    if not isinstance(v, str):
        raise ProtocolError(f"{msg}.{name}: expected str, got {v!r}")
    try:
        b = v.encode("ascii")
    except UnicodeEncodeError:
        raise ProtocolError(f"{msg}.{name}: {v!r} is not ASCII") from None
    if len(b) > max_chars or b"\0" in b:
        raise ProtocolError(f"{msg}.{name}: {v!r} longer than {max_chars} characters or contains NUL")
    return b  # struct pads with NULs


def _check_int(msg: str, name: str, v: Any, lo: int, hi: int) -> None:
    if type(v) is not int and not (isinstance(v, int) and not isinstance(v, bool)):
        raise ProtocolError(f"{msg}.{name}: expected int, got {v!r}")
    if not lo <= v <= hi:
        raise ProtocolError(f"{msg}.{name}: {v} outside {lo}..{hi}")


def _plans(max_limbs: int, max_channels: int) -> dict[int, _Plan]:
    return {m.id: _Plan(m, max_limbs, max_channels) for m in MESSAGES}


_DEFAULT_PLANS = _plans(LIMB_CEILING, CHANNEL_CEILING)
_PLANS_BY_NAME = {p.name: p for p in _DEFAULT_PLANS.values()}


# ----------------------------------------------------------------------------- public API
def pack(msg: Message) -> bytes:
    """msg_id + payload of ``msg`` (no CRC, no COBS); raises ProtocolError if invalid."""
    plan = _PLANS_BY_NAME.get(msg.name)
    if plan is None:
        raise ProtocolError(f"unknown message name {msg.name!r}")
    return plan.pack(msg)


def unpack(raw: bytes, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING) -> Message:
    """Decode msg_id + payload (no CRC); raises ProtocolError naming what is wrong."""
    plans = _DEFAULT_PLANS if (max_limbs, max_channels) == (LIMB_CEILING, CHANNEL_CEILING) else _plans(max_limbs, max_channels)
    if not raw or raw[0] not in plans:
        raise ProtocolError(f"unknown message id {raw[0] if raw else None!r}")
    try:
        return plans[raw[0]].unpack(bytes(raw), len(raw))
    except _Reject as e:
        raise ProtocolError(str(e)) from None


def encode(msg: Message) -> bytes:
    """The complete wire frame of ``msg``: COBS(id | payload | crc16-le) + 0x00."""
    raw = pack(msg)
    if len(raw) + 2 > MAX_FRAME:  # cannot happen within the ceilings; kept as a guard
        raise ProtocolError(f"{msg.name}: frame of {len(raw) + 2} bytes > {MAX_FRAME}")
    crc = crc_hqx(raw, 0xFFFF)
    return _cobs_encode(raw + bytes((crc & 0xFF, crc >> 8))) + b"\0"


def decode_frame(frame: bytes, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING) -> Message:
    """Decode exactly one wire frame (trailing 0x00 optional); raises ProtocolError."""
    dec = FrameDecoder(max_limbs, max_channels)
    body = frame[:-1] if frame.endswith(b"\0") else frame
    if b"\0" in body:
        raise ProtocolError("more than one frame")
    msgs = dec.feed(bytes(body) + b"\0")
    if not msgs:
        raise ProtocolError(f"invalid frame: {dec.last_error or 'empty'}")
    return msgs[0]


COUNTERS = ("frames_ok", "crc_errors", "framing_errors", "unknown_ids", "bad_length", "bad_value")


class FrameDecoder:
    """Streaming decoder: ``feed(bytes) -> list[Message]`` with error counters.

    ``max_limbs``/``max_channels`` bound the ψ/duty arrays like the firmware build does
    (default: the protocol ceilings). The decoder starts inside a frame, like the C receiver:
    bytes before the first 0x00 are judged (and usually counted) as a frame.
    """

    __slots__ = ("_plans", "_partial", "_overflow", *COUNTERS, "last_error")

    def __init__(self, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING) -> None:
        self._plans = (
            _DEFAULT_PLANS
            if (max_limbs, max_channels) == (LIMB_CEILING, CHANNEL_CEILING)
            else _plans(max_limbs, max_channels)
        )
        self._partial = b""
        self._overflow = False
        self.frames_ok = 0
        self.crc_errors = 0
        self.framing_errors = 0
        self.unknown_ids = 0
        self.bad_length = 0
        self.bad_value = 0
        self.last_error = ""  # why the last broken frame was counted

    def counters(self) -> dict[str, int]:
        return {name: getattr(self, name) for name in COUNTERS}

    def feed(self, data: bytes) -> list[Message]:
        """Decode every frame completed by ``data``; keeps the unfinished tail."""
        if self._partial:
            data = self._partial + data
        chunks = data.split(b"\0")
        tail = chunks.pop()
        out: list[Message] = []
        if self._overflow and chunks:
            # the first completed chunk ends an over-long frame whose start was dropped
            chunks[0] = b"\xff" * (_MAX_BODY + 1)
            self._overflow = False
        if len(tail) > _MAX_BODY:
            self._overflow = True
            tail = b""
        self._partial = tail
        plans = self._plans
        append = out.append
        for chunk in chunks:
            n = len(chunk)
            if n == 0:
                continue
            if n > _MAX_BODY:
                self.framing_errors += 1
                self.last_error = "frame too long"
                continue
            try:
                raw = _cobs_decode(chunk)
            except _DecodeError:
                self.framing_errors += 1
                self.last_error = "bad COBS"
                continue
            end = len(raw) - 2
            if end < 1 or end + 2 > MAX_FRAME:
                self.framing_errors += 1
                self.last_error = "frame too short" if end < 1 else "frame too long"
                continue
            if crc_hqx(raw[:end], 0xFFFF) != raw[end] | (raw[end + 1] << 8):
                self.crc_errors += 1
                self.last_error = "bad CRC"
                continue
            plan = plans.get(raw[0])
            if plan is None:
                self.unknown_ids += 1
                self.last_error = f"unknown id 0x{raw[0]:02X}"
                continue
            try:
                append(plan.unpack(raw, end))
            except _Reject as e:
                if e.counter == "bad_value":
                    self.bad_value += 1
                else:
                    self.bad_length += 1
                self.last_error = str(e)
                continue
            self.frames_ok += 1
        return out
