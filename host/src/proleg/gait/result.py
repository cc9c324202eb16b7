"""The values the gait engine returns: one gait, and the answer to an optimisation."""

from __future__ import annotations

from dataclasses import dataclass

#: Two values tie when they differ by at most this fraction of the scale of the table:
#: the largest |reward| (for ``total`` and ``rate``) or the largest |reward / duration|
#: (for ``speed``). A walk "moves" in +x only when J exceeds the same tolerance.
RELATIVE_TOLERANCE = 1e-9

#: At most this many tied gaits are listed; beyond it ``GaitResult.truncated`` is True.
MAX_TIES = 10_000
#: ...and at most this many states in all (ties of a large flat table can be very long).
MAX_LISTED_STATES = 1_000_000


@dataclass(frozen=True)
class Gait:
    """A closed walk s0 -> s1 -> ... -> sN = s0 over allowed transitions.

    ``states`` is rotated to its canonical start: among the rotations that start at the
    walk's lowest state index, the lexicographically smallest.
    """

    states: tuple[int, ...]
    reward: float
    transitions: int
    rate: float
    duration: float | None = None

    @property
    def speed(self) -> float | None:
        """J per second, when the table has durations."""
        return None if self.duration is None else self.reward / self.duration


@dataclass(frozen=True)
class GaitResult:
    """Every optimal gait for one objective and direction.

    ``value`` is the optimum (J, J per transition or J per second; negative for -x), or
    None when no gait moves in ``direction``. ``gaits`` holds every tie, sorted by states,
    unless more than ``MAX_TIES`` exist (or they hold more than ``MAX_LISTED_STATES`` states):
    then the first ones found and ``truncated=True``.
    ``max_transitions`` is the bound actually used (the default for ``total`` included).
    """

    direction: str
    objective: str
    max_transitions: int | None
    value: float | None
    gaits: tuple[Gait, ...]
    truncated: bool = False
