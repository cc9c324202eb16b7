"""Level calibration over the link: CALIBRATE_LEVEL, GET_LEVEL, CLEAR_LEVEL (docs/calibration.md).

``calibrate_level(client)`` asks the robot to record each IMU's rest tilt (the robot at rest on
flat ground, coils cold), waits for its ``EVENT LEVEL_DONE`` and reads back what is stored.
The firmware does the measuring and the storing (core/level.c); this module only asks and
reports.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import LinkError
from ..protocol.definition import EventKind, LevelResult, LevelStatus
from .client import RobotClient

#: sampling takes 64 ticks (0.64 s at 100 Hz), a flash or EEPROM write well under a second
DONE_WITHIN_S = 5.0

_RESULT_TEXT = {
    LevelResult.STORED: "stored",
    LevelResult.TOO_TILTED: "refused: tilted more than 20° at rest (not on flat ground, not at rest, or the IMU mounted crooked)",
    LevelResult.IMU: "refused: the IMU is bad or gave no samples",
    LevelResult.INTERRUPTED: "refused: a gait started or a fault latched while sampling",
    LevelResult.WRITE_FAILED: "refused: the non-volatile write did not verify",
}


@dataclass(frozen=True)
class LevelReading:
    """What GET_LEVEL answered: the record's status and each limb's offset (0.01°)."""

    status: LevelStatus
    offsets_cdeg: tuple[int, ...]
    ground_cdeg: tuple[int, ...] = ()

    @property
    def offsets_deg(self) -> tuple[float, ...]:
        return tuple(o / 100.0 for o in self.offsets_cdeg)

    @property
    def ground_deg(self) -> tuple[float, ...]:
        return tuple(o / 100.0 for o in self.ground_cdeg)


@dataclass(frozen=True)
class LevelOutcome:
    """The end of a calibration: the result, the limbs it concerns (bit per limb) and what
    the robot has stored now."""

    result: LevelResult
    limbs_mask: int
    reading: LevelReading

    @property
    def ok(self) -> bool:
        return self.result == LevelResult.STORED

    def limb_text(self, limb: int) -> str:
        """The outcome for one limb (0-based ``limb``) in words."""
        if self.ok:
            return "stored"
        if self.result in (LevelResult.TOO_TILTED, LevelResult.IMU) and not self.limbs_mask >> limb & 1:
            return "not stored (another limb was refused)"
        return _RESULT_TEXT.get(self.result, f"refused: result {int(self.result)}")

    def refusal_text(self, names: Sequence[str]) -> str:
        """Why a calibration was refused, in words, naming the limbs it concerns (``names``:
        the limbs' names, first limb first): "limb 'left': tilted more than 20° at rest (…)"."""
        limbs = [n for i, n in enumerate(names) if self.limbs_mask >> i & 1]
        why = _RESULT_TEXT.get(self.result, f"refused: result {int(self.result)}").removeprefix("refused: ")
        if not limbs:
            return why
        return f"{'limb' if len(limbs) == 1 else 'limbs'} {', '.join(repr(n) for n in limbs)}: {why}"


def get_level(client: RobotClient, timeout: float | None = None) -> LevelReading:
    reply = client.request("GET_LEVEL", timeout=timeout)
    try:
        status = LevelStatus(reply.status)
    except ValueError:
        raise LinkError(f"{client.link.description}: GET_LEVEL answered an unknown status {reply.status}") from None
    return LevelReading(status, tuple(reply.offset), tuple(reply.ground))


def clear_level(client: RobotClient) -> LevelReading:
    """Erase the stored calibration; returns what the robot reports after."""
    client.request("CLEAR_LEVEL")
    deadline = client.link.clock() + DONE_WITHIN_S
    while True:
        reading = get_level(client)
        if reading.status != LevelStatus.CALIBRATING or client.link.clock() >= deadline:
            return reading
        client.recv(0.05)


def calibrate_level(client: RobotClient, *, ground: bool = False, within_s: float = DONE_WITHIN_S) -> LevelOutcome:
    """CALIBRATE_LEVEL, then wait for EVENT LEVEL_DONE; ``CommandRefused`` when the robot
    refuses at once (NOT_ALLOWED: a gait runs, an IMU is bad, a fault is latched).
    ``ground``: level on the ground the robot stands on now (a slope), in the robot's RAM
    only, on top of the stored flat calibration."""
    ask_level_calibration(client, ground=ground)
    return level_outcome(client, within_s)


def ask_level_calibration(client: RobotClient, *, ground: bool = False) -> None:
    """CALIBRATE_LEVEL: from here the board samples and stores (or applies) on its own, whether
    or not anyone waits for its end."""
    client.request("CALIBRATE_LEVEL", ground=int(ground))


def level_outcome(client: RobotClient, within_s: float = DONE_WITHIN_S) -> LevelOutcome:
    """Wait for the EVENT LEVEL_DONE of the calibration asked for, and read back what is stored."""
    deadline = client.link.clock() + within_s
    while True:
        msg = client.recv(max(0.0, deadline - client.link.clock()))
        if msg is not None and msg.name == "EVENT" and msg.kind == EventKind.LEVEL_DONE:
            try:
                result = LevelResult(msg.code)
            except ValueError:
                raise LinkError(f"{client.link.description}: level calibration ended with unknown result {msg.code}") from None
            return LevelOutcome(result, int(msg.detail), get_level(client))
        if msg is None and client.link.clock() >= deadline:
            raise LinkError(f"{client.link.description}: no end of the level calibration within {within_s:g} s")
