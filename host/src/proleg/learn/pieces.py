"""Pieces of a tour the robot can run between rests, within its thermal limits.

A piece is a state path ``p0 → … → pk``; consecutive pieces chain (each starts where the
last ended). The host runs a piece as a user gait (``learn.runner``): LOAD_GAIT of the
piece closed by the shortest way back from ``pk`` to ``p0`` (the firmware accepts closed
walks only and checks every step of them), START, and STOP once ``pk`` is reached. A piece
is *loadable* when that closed walk exists and has at most ``max_gait_steps`` states;
``split`` cuts pieces to the longest loadable prefix.

Thermal limits (``PieceLimits``) follow the firmware's envelope (docs/safety.md): at most
``max_transitions`` per piece, and per coil an *on-time debt* that never passes
``max_coil_on_s``: a coil is on while it raises one of its limbs (drive duty); holding a
raised limb (at or below the hold ceiling) and lowering one are not on-time, and every
second not on pays back ``coil_payback`` seconds of debt (``max_on_ms`` /
``min_cooldown_ms``), exactly as the firmware's budget does, so a planned piece never
meets SMA_ON_LIMIT. A piece also drives for at most ``max_on_s`` of estimated time (the
transition durations of the robot file, or ``default_duration_s``), then rests ``rest_s``
for the coils to cool. ``limits_for`` derives them from the robot's ``[safety]``: one piece
may drive for as long as every coil could stay on in one go (``max_on_ms`` × actuators,
since a transition drives about one coil at a time), and the rest lasts as long as the
drive time times (1/max_duty − 1), at least ``min_cooldown_ms``, so the mean duty over
piece + rest stays below ``max_duty``. The firmware's own envelope still applies underneath.

(An earlier model counted a coil as on for as long as its limb stayed raised. Under the
debt budget that is wrong, and it made every state with three limbs up unreachable for
inchworm-3 from the rest state 000: exploration then planned the same short pieces
forever. ``learn.runner`` now also stops with a clear message when pieces stop making
progress.)
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from .. import states as _states
from ..gait.coil_debt import charge  # one model of the firmware's on-time budget (gait feasibility too)
from ..protocol.definition import MAX_GAIT_STEPS
from ..transitions import TransitionTable

DEFAULT_DURATION_S = 1.0  # a guess for robots without durations: R1 takes 0.7–1.2 s per transition
COIL_MARGIN = 0.8  # plan coil debt to 80 % of max_on_ms: durations are estimates
DEFAULT_PAYBACK = 3000 / 800  # max_on_ms / min_cooldown_ms of the default [safety]


@dataclass(frozen=True)
class PieceLimits:
    max_transitions: int = MAX_GAIT_STEPS - 1
    max_on_s: float = float("inf")
    rest_s: float = 0.0
    default_duration_s: float = DEFAULT_DURATION_S
    # coil per limb (index into the robot's actuators), the most on-time debt a coil may
    # carry (the firmware cuts a coil whose debt would pass max_on_ms: SMA_ON_LIMIT), and
    # the seconds of debt each second not on pays back (max_on_ms / min_cooldown_ms)
    coil_of_limb: tuple[int, ...] | None = None
    max_coil_on_s: float = float("inf")
    coil_payback: float = DEFAULT_PAYBACK
    max_gait_steps: int = MAX_GAIT_STEPS  # states the firmware takes in one LOAD_GAIT


@dataclass(frozen=True)
class Piece:
    states: tuple[int, ...]
    loadable: bool
    rest_after_s: float
    est_time_s: float
    closing: tuple[int, ...] = ()  # states between the last and the first that close the gait

    @property
    def transitions(self) -> list[tuple[int, int]]:
        return list(zip(self.states, self.states[1:]))

    def gait(self) -> tuple[int, ...]:
        """The LOAD_GAIT payload: the piece and its way back, without a repeated start state."""
        s = self.states
        if len(s) > 1 and s[-1] == s[0]:
            return s[:-1]
        return s + self.closing


def limits_for(robot, max_transitions: int | None = None) -> PieceLimits:
    """Piece limits from a loaded robot's ``[safety]`` (see the module docstring)."""
    s = robot.safety
    on = s.max_on_ms / 1000.0 * len(robot.actuators)
    k = MAX_GAIT_STEPS - 1 if max_transitions is None else min(max_transitions, MAX_GAIT_STEPS - 1)
    rest = max(s.min_cooldown_ms / 1000.0, on * (1.0 / s.max_duty - 1.0))
    names = [a.name for a in robot.actuators]
    coils = tuple(names.index(limb.actuator) for limb in robot.limbs)
    return PieceLimits(max_transitions=k, max_on_s=on, rest_s=rest, coil_of_limb=coils,
                       max_coil_on_s=COIL_MARGIN * s.max_on_ms / 1000.0,
                       coil_payback=s.max_on_ms / max(1, s.min_cooldown_ms))


def _duration(table: TransitionTable, a: int, b: int, default: float) -> float:
    if table.duration is None:
        return default
    e = table.lookup(a, b)
    return default if e is None else float(table.duration[e])


class _Closer:
    """Shortest ways back between states (BFS over the allowed transitions, cached)."""

    def __init__(self, table: TransitionTable):
        self.n = table.n_states
        self.succ: list[list[int]] = [[] for _ in range(self.n)]
        for a, b in zip(table.src.tolist(), table.dst.tolist()):
            self.succ[a].append(b)
        self._prev: dict[int, list[int]] = {}

    def path(self, a: int, b: int) -> tuple[int, ...] | None:
        """States strictly between ``a`` and ``b`` on a shortest path a → … → b, or None."""
        prev = self._prev.get(a)
        if prev is None:
            prev = [-2] * self.n
            prev[a] = -1
            q = deque([a])
            while q:
                v = q.popleft()
                for w in self.succ[v]:
                    if prev[w] == -2:
                        prev[w] = v
                        q.append(w)
            self._prev[a] = prev
        if a == b:
            return ()
        if prev[b] == -2:
            return None
        out = []
        v = prev[b]
        while v != a:
            out.append(v)
            v = prev[v]
        return tuple(reversed(out))


def _closing(closer: _Closer, states: list[int], max_steps: int) -> tuple[int, ...] | None:
    """The states that close ``states`` into a loadable gait, or None when it is not loadable."""
    k = len(states) - 1
    if k < 1:
        return None
    if states[-1] == states[0]:
        return () if 2 <= k <= max_steps else None
    back = closer.path(states[-1], states[0])
    if back is None or k + 1 + len(back) > max_steps:
        return None
    return back


def _rises(table: TransitionTable, a: int, b: int, limits: PieceLimits) -> list[bool]:
    """Which coils are on during a → b: those raising one of their limbs (a level going up)."""
    if limits.coil_of_limb is None:
        return []
    la, lb = _states.limb_levels(a, table.levels), _states.limb_levels(b, table.levels)
    on = [False] * (max(limits.coil_of_limb) + 1)
    for x, y, c in zip(la, lb, limits.coil_of_limb):
        on[c] = on[c] or y > x
    return on


def coil_debt(table: TransitionTable, states, limits: PieceLimits) -> list[float]:
    """Each coil's on-time debt after walking ``states`` from cool coils (a piece starts
    after a rest), by the firmware's budget (module docstring); the largest it reached is
    what ``split`` keeps below ``max_coil_on_s``: see ``peak_coil_debt``."""
    return _debts(table, list(states), limits)[0]


def peak_coil_debt(table: TransitionTable, states, limits: PieceLimits) -> float:
    """The largest on-time debt any coil reaches while walking ``states`` from cool coils."""
    return _debts(table, list(states), limits)[1]


def _debts(table: TransitionTable, states: list[int], limits: PieceLimits) -> tuple[list[float], float]:
    debt: list[float] = []
    peak = 0.0
    for a, b in zip(states, states[1:]):
        debt, p = _step_debt(table, a, b, debt, limits)
        peak = max(peak, p)
    return debt, peak


def _step_debt(table: TransitionTable, a: int, b: int, debt: list[float],
               limits: PieceLimits) -> tuple[list[float], float]:
    on = _rises(table, a, b, limits)
    if not on:
        return debt, 0.0
    d = _duration(table, a, b, limits.default_duration_s)
    debt = debt or [0.0] * len(on)
    after = charge(debt, on, d, limits.coil_payback)
    return after, max(after)


def split(table: TransitionTable, walk: tuple[int, ...] | list[int], limits: PieceLimits = PieceLimits()) -> list[Piece]:
    """Cut ``walk`` into chained pieces within ``limits``; each piece is as long as the limits
    allow, shortened (never below one transition) to the longest prefix that is loadable."""
    if limits.max_transitions < 1:
        raise ValueError("a piece needs at least one transition")
    walk = list(walk)
    closer = _Closer(table)
    out: list[Piece] = []
    i = 0
    while i < len(walk) - 1:
        j, t = i, 0.0
        debt: list[float] = []
        while j < len(walk) - 1 and j - i < limits.max_transitions:
            d = _duration(table, walk[j], walk[j + 1], limits.default_duration_s)
            after, peak = _step_debt(table, walk[j], walk[j + 1], debt, limits)
            if j > i and (t + d > limits.max_on_s or peak > limits.max_coil_on_s):
                break
            t += d
            debt = after
            j += 1
        end = j
        while end > i + 1 and _closing(closer, walk[i:end + 1], limits.max_gait_steps) is None:
            end -= 1
        closing = _closing(closer, walk[i:end + 1], limits.max_gait_steps)
        if closing is None:
            end = j  # nothing shorter loads either: keep the full piece (the runner says why)
        seg = walk[i:end + 1]
        est = sum(_duration(table, a, b, limits.default_duration_s) for a, b in zip(seg, seg[1:]))
        out.append(Piece(tuple(seg), closing is not None, limits.rest_s, est, closing or ()))
        i = end
    if out:
        last = out[-1]
        out[-1] = Piece(last.states, last.loadable, 0.0, last.est_time_s, last.closing)
    return out
