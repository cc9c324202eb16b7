"""The link protocol: one definition (``definition``), the Python codec (``codec``) and the
C tables rendered from it (``render``). See docs/ARCHITECTURE.md "Link protocol"."""

from proleg.protocol.codec import COUNTERS, FrameDecoder, Message, decode_frame, encode, pack, unpack
from proleg.protocol.definition import (
    BY_ID,
    BY_NAME,
    MESSAGES,
    PROTOCOL_VERSION,
    ClearWhat,
    Direction,
    ErrorCode,
    EventKind,
    FaultCode,
    Flag,
    ParamId,
    StopReason,
)
from proleg.protocol.render import render_c

__all__ = [
    "BY_ID",
    "BY_NAME",
    "COUNTERS",
    "MESSAGES",
    "PROTOCOL_VERSION",
    "ClearWhat",
    "Direction",
    "ErrorCode",
    "EventKind",
    "FaultCode",
    "Flag",
    "FrameDecoder",
    "Message",
    "ParamId",
    "StopReason",
    "decode_frame",
    "encode",
    "pack",
    "render_c",
    "unpack",
]
