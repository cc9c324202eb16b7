"""How a message is laid out: the field types, ``Field``, ``MessageSpec`` and the limb/channel
ceilings the protocol is sized for.

Part of the protocol definition (``definition.py`` re-exports every name here and holds the
message table built from these classes).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum, IntFlag
from typing import Literal

#: Limits the protocol is sized for (a build may use fewer).
LIMB_CEILING = 8
CHANNEL_CEILING = 8

ScalarType = Literal["u8", "u16", "u32", "i16", "i32", "char"]

#: (size in bytes, struct format char, minimum, maximum)
TYPES: dict[str, tuple[int, str, int, int]] = {
    "u8": (1, "B", 0, 0xFF),
    "u16": (2, "H", 0, 0xFFFF),
    "u32": (4, "I", 0, 0xFFFFFFFF),
    "i16": (2, "h", -0x8000, 0x7FFF),
    "i32": (4, "i", -0x80000000, 0x7FFFFFFF),
    "char": (1, "s", 0, 0x7F),
}


@dataclass(frozen=True)
class Field:
    """One payload field. ``length``: fixed text size; ``max_count``: variable array."""

    name: str
    type: ScalarType
    doc: str = ""
    length: int | None = None
    max_count: int | Literal["limbs", "channels"] | None = None
    enum: type[IntEnum] | type[IntFlag] | None = None

    @property
    def size(self) -> int:
        return TYPES[self.type][0]

    @property
    def is_array(self) -> bool:
        return self.max_count is not None

    def resolved_max(self, max_limbs: int, max_channels: int) -> int:
        """Array capacity for a build with these limits (0 for non-arrays)."""
        if self.max_count is None:
            return 0
        if self.max_count == "limbs":
            return max_limbs
        if self.max_count == "channels":
            return max_channels
        return int(self.max_count)

    def max_wire_size(self, max_limbs: int, max_channels: int) -> int:
        if self.length is not None:
            return self.length
        if self.max_count is not None:
            return 1 + self.size * self.resolved_max(max_limbs, max_channels)
        return self.size


@dataclass(frozen=True)
class MessageSpec:
    """One message: ``direction`` is ``"h2r"`` (host→robot command) or ``"r2h"``."""

    id: int
    name: str
    direction: Literal["h2r", "r2h"]
    fields: tuple[Field, ...]
    doc: str
    #: commands only: the message that answers it when accepted (NACK may always answer)
    reply: str | None = None

    def max_frame(self, max_limbs: int = LIMB_CEILING, max_channels: int = CHANNEL_CEILING) -> int:
        """Largest frame before COBS: id + payload + crc."""
        return 1 + sum(f.max_wire_size(max_limbs, max_channels) for f in self.fields) + 2
