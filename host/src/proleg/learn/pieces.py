"""Pieces of a tour the robot can run between rests, within its thermal limits.

A piece is a state path ``p0 → … → pk``; consecutive pieces chain (each starts where the
last ended). A piece is *loadable* when the firmware's LOAD_GAIT accepts it as a closed
walk: at most ``MAX_GAIT_STEPS`` states and, unless ``pk == p0``, the closing transition
``pk → p0`` allowed (the firmware checks every step of the walk, including the closing one).
The host runs a loadable piece with LOAD_GAIT + START and stops when ``pk`` is reached; a
piece that is not loadable is run as plain state targets one transition at a time (a
two-state gait ``[a, b]`` needs ``b → a``; see ``learn.runner``).

Thermal limits (``PieceLimits``): at most ``max_transitions`` per piece, no coil on for
longer than ``max_coil_on_s`` in a row (a coil is on while its limb is raised or being
raised, held too: the firmware's SMA_ON_LIMIT counts continuous on-time), and at most
``max_on_s`` of estimated drive time (the transition durations of the robot file, or
``default_duration_s``), then a rest of ``rest_s`` for the coils to cool. ``limits_for``
derives them from the robot's ``[safety]``: one piece may drive for as long as every coil
could stay on in one go (``max_on_ms`` × actuators, since a transition drives about one
coil at a time), and the rest lasts as long as the drive time times (1/max_duty − 1), at
least ``min_cooldown_ms``, so the mean duty over piece + rest stays below ``max_duty``.
These are conservative defaults, not a thermal model; the firmware's own envelope
(SMA_ON_LIMIT, cool-down) still applies underneath.
"""

from __future__ import annotations

from dataclasses import dataclass

from .. import states as _states
from ..protocol.definition import MAX_GAIT_STEPS
from ..transitions import TransitionTable

DEFAULT_DURATION_S = 1.0  # a guess for robots without durations: R1 takes 0.7–1.2 s per transition
COIL_MARGIN = 0.8  # plan coil runs to 80 % of max_on_ms: durations are estimates


@dataclass(frozen=True)
class PieceLimits:
    max_transitions: int = MAX_GAIT_STEPS - 1
    max_on_s: float = float("inf")
    rest_s: float = 0.0
    default_duration_s: float = DEFAULT_DURATION_S
    # coil per limb (index into the robot's actuators), and the longest run of transitions
    # one coil may stay on for (a raised limb is held by its coil): the firmware forces a
    # coil that was on for max_on_ms in a row into cool-down (SMA_ON_LIMIT)
    coil_of_limb: tuple[int, ...] | None = None
    max_coil_on_s: float = float("inf")


@dataclass(frozen=True)
class Piece:
    states: tuple[int, ...]
    loadable: bool
    rest_after_s: float
    est_time_s: float

    @property
    def transitions(self) -> list[tuple[int, int]]:
        return list(zip(self.states, self.states[1:]))

    def gait(self) -> tuple[int, ...]:
        """The LOAD_GAIT payload: the walk without a repeated start state."""
        s = self.states
        return s[:-1] if len(s) > 1 and s[-1] == s[0] else s


def limits_for(robot, max_transitions: int | None = None) -> PieceLimits:
    """Piece limits from a loaded robot's ``[safety]`` (see the module docstring)."""
    s = robot.safety
    on = s.max_on_ms / 1000.0 * len(robot.actuators)
    k = MAX_GAIT_STEPS - 1 if max_transitions is None else min(max_transitions, MAX_GAIT_STEPS - 1)
    rest = max(s.min_cooldown_ms / 1000.0, on * (1.0 / s.max_duty - 1.0))
    names = [a.name for a in robot.actuators]
    coils = tuple(names.index(limb.actuator) for limb in robot.limbs)
    return PieceLimits(max_transitions=k, max_on_s=on, rest_s=rest, coil_of_limb=coils,
                       max_coil_on_s=COIL_MARGIN * s.max_on_ms / 1000.0)


def _duration(table: TransitionTable, a: int, b: int, default: float) -> float:
    if table.duration is None:
        return default
    e = table.lookup(a, b)
    return default if e is None else float(table.duration[e])


def _loadable(table: TransitionTable, states: list[int]) -> bool:
    closed = states[-1] == states[0]
    n = len(states) - 1 if closed else len(states)
    if n < 2 or n > MAX_GAIT_STEPS:
        return False
    return closed or table.lookup(states[-1], states[0]) is not None


def _coils_on(table: TransitionTable, state: int, limits: PieceLimits) -> list[bool]:
    """Which coils are on while the robot heads for / holds ``state`` (a limb above level 0)."""
    if limits.coil_of_limb is None:
        return []
    up = _states.limb_levels(state, table.levels)
    on = [False] * (max(limits.coil_of_limb) + 1)
    for lvl, c in zip(up, limits.coil_of_limb):
        on[c] = on[c] or lvl > 0
    return on


def _coil_runs(table: TransitionTable, state: int, limits: PieceLimits) -> list[float]:
    """Coil on-times at a piece's start: it starts after a rest, so every coil is cool."""
    return [0.0] * len(_coils_on(table, state, limits))


def split(table: TransitionTable, walk: tuple[int, ...] | list[int], limits: PieceLimits = PieceLimits()) -> list[Piece]:
    """Cut ``walk`` into chained pieces within ``limits``; each piece is as long as the limits
    allow, shortened (never below one transition) to the longest prefix that is loadable."""
    if limits.max_transitions < 1:
        raise ValueError("a piece needs at least one transition")
    walk = list(walk)
    out: list[Piece] = []
    i = 0
    while i < len(walk) - 1:
        j, t = i, 0.0
        run = _coil_runs(table, walk[i], limits)
        while j < len(walk) - 1 and j - i < limits.max_transitions:
            d = _duration(table, walk[j], walk[j + 1], limits.default_duration_s)
            on = _coils_on(table, walk[j + 1], limits)
            after = [r + d if c else 0.0 for r, c in zip(run, on)]
            if j > i and (t + d > limits.max_on_s or max(after, default=0.0) > limits.max_coil_on_s):
                break
            t += d
            run = after
            j += 1
        end = j
        while end > i + 1 and not _loadable(table, walk[i:end + 1]):
            end -= 1
        if not _loadable(table, walk[i:end + 1]):
            end = j  # nothing shorter loads either: keep the full piece, run it step by step
        seg = walk[i:end + 1]
        est = sum(_duration(table, a, b, limits.default_duration_s) for a, b in zip(seg, seg[1:]))
        out.append(Piece(tuple(seg), _loadable(table, seg), limits.rest_s, est))
        i = end
    if out:
        last = out[-1]
        out[-1] = Piece(last.states, last.loadable, 0.0, last.est_time_s)
    return out
