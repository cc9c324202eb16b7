"""The values the gait engine returns: one gait, and the answer to an optimisation."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: Two values tie when they differ by at most this fraction of the scale of the table
#: (``reward_scale`` for ``total`` and ``rate``, ``speed_scale`` for ``speed``). A walk
#: "moves" in +x only when J exceeds the same tolerance.
RELATIVE_TOLERANCE = 1e-9


def reward_scale(w: np.ndarray, bound: int | None) -> float:
    """The scale of a gait's J that ties and "moves at all" are judged against, for rewards
    ``w`` signed for the direction (−reward for −x) and walks of at most ``bound``
    transitions: the largest |w|, but no more than ``bound`` × the largest positive w. A walk
    with J > 0 has no step below −(bound − 1) × that, so a larger |w| (a penalty of −1e9 in
    a matrix of ±1) is in no walk that is compared, and made every J within 1 a tie: gaits
    worse by 1 were listed as optimal, and rate answered "no gait"."""
    if not len(w):
        return 0.0
    top = float(np.abs(w).max())
    positive = float(np.max(w))
    if positive <= 0 or bound is None:
        return top
    return min(top, bound * positive)


def speed_scale(reward: np.ndarray, duration: np.ndarray, bound: int | None = None) -> float:
    """The scale of a gait's speed (reward per second) that ties and "moves at all" are
    judged against: ``reward_scale`` per the median duration. Not the largest |w/t| of
    one transition: one very short transition made every cycle's speed look like rounding
    noise, and the speed objective answered "no gait" (durations 1 s and one of 1 ns)."""
    if not len(reward):
        return 0.0
    return reward_scale(np.asarray(reward, dtype=np.float64), bound) / float(np.median(duration))

#: At most this many tied gaits are listed; beyond it ``GaitResult.truncated`` is True.
MAX_TIES = 10_000
#: ...and at most this many states in all (ties of a large flat table can be very long).
MAX_LISTED_STATES = 1_000_000


@dataclass(frozen=True)
class Gait:
    """A closed walk s0 -> s1 -> ... -> sN = s0 over allowed transitions.

    ``states`` is rotated to its canonical start: among the rotations that start at the
    walk's lowest state index, the lexicographically smallest. ``reward``, ``transitions``,
    ``rate`` and ``duration`` are those of one pass. ``repeats`` is how many passes the
    answer to a ``total`` question counts (k = ⌊N / transitions⌋: the walk repeated k times
    is the closed walk of at most N transitions it stands for; the firmware runs the gait
    cyclically, so it runs that walk); 1 for every other gait.
    """

    states: tuple[int, ...]
    reward: float
    transitions: int
    rate: float
    duration: float | None = None
    repeats: int = 1

    @property
    def total(self) -> float:
        """J of the walk this gait stands for: ``reward × repeats``."""
        return self.reward * self.repeats

    @property
    def speed(self) -> float | None:
        """J per second, when the table has durations."""
        return None if self.duration is None else self.reward / self.duration


@dataclass(frozen=True)
class GaitResult:
    """Every optimal gait for one objective and direction.

    ``value`` is the optimum (J, J per transition or J per second; negative for -x), or
    None when no gait moves in ``direction``; for ``total`` it is the best J of a closed walk
    of at most ``max_transitions`` transitions, repeated walks included (``Gait.total``).
    ``gaits`` holds every tie in rank order — gait 0 is the one the firmware runs by
    default: best rate (J per transition, in ``direction``) first, then fewest transitions,
    then by states (rates within the tie tolerance count as equal) — unless more than ``MAX_TIES`` exist (or they hold more than ``MAX_LISTED_STATES`` states):
    then the first ones found and ``truncated=True``.
    ``max_transitions`` is the bound actually used (the default for ``total`` included).
    ``below_zero`` (planar objectives only): no gait scores above zero, and ``value`` and
    ``gaits`` are the best ones anyway (the least costly, in a cost-minimising reading).
    """

    direction: str
    objective: str
    max_transitions: int | None
    value: float | None
    gaits: tuple[Gait, ...]
    truncated: bool = False
    below_zero: bool = False
