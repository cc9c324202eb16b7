"""What ``RobotClient`` hands on from the link: each decoded message with its time of receipt
(``Received``), and the host-side counters of what it received (``LinkStats``).

``proleg.link.client`` re-exports both names.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

from ..protocol.codec import Message


@dataclass
class LinkStats:
    """Host-side counters of one client."""

    frames_ok: int = 0
    crc_errors: int = 0
    framing_errors: int = 0
    unknown_ids: int = 0
    bad_length: int = 0
    bad_value: int = 0
    telemetry: int = 0
    lost: int = 0  # TELEMETRY frames missing from the sequence numbers
    seq_restarts: int = 0
    reconnects: int = 0
    nacks: int = 0
    timeouts: int = 0  # commands that got no reply (after their retries)
    retries: int = 0  # commands sent again after a try got no reply
    lost_acks: int = 0  # STARTs whose ACK was lost: sent again, refused, and TELEMETRY runs their gait

    @property
    def corrupt(self) -> int:
        return self.crc_errors + self.framing_errors + self.unknown_ids + self.bad_length + self.bad_value

    def as_dict(self) -> dict[str, int]:
        return {**asdict(self), "corrupt": self.corrupt}


@dataclass(slots=True)
class Received:
    """One decoded message with the host's time of receipt (link clock) and whatever ground
    truth the link knew then (the simulated robot's displacement...)."""

    message: Message
    time: float
    truth: dict[str, float] = field(default_factory=dict)
