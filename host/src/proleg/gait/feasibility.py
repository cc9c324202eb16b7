"""Can the robot's hardware run a gait, and how does it get there from rest?

The optimiser sees only the transition table; the robot file also says which actuator
drives which limb and how long a coil may stay on. An SMA coil raises its limb(s) when hot
and lets them fall when it cools, so:

* **Shared actuators** — limbs driven by one actuator rise and fall together: a step that
  raises one of them while lowering another cannot be made (error ``shared-actuator``).
* **Opposing steps** — a step that raises a limb on one actuator while lowering a limb on
  another needs a heating and a cooling crossing to coincide; the controller synchronises
  them as well as it can, but the robot may pass through an intermediate state (warning
  ``opposing``; ``proleg.states.opposing_steps``).
* **Hold time vs on-time** — a coil is on in every state where a limb it drives is raised
  (level > 0). Run cyclically, a gait keeps a coil on for the longest cyclic run of such
  states; each state lasts at least ``control.hold_ms`` (the firmware holds a reached
  state that long before it advances), or the duration of the transition out of it when
  the table has durations. Longer than ``safety.max_on_ms`` is an error (``on-time``); a
  coil on in every state of the gait never cools down (error ``never-cools``).
* **Entry** — the firmware starts from rest (every limb at level 0, state 0) and must reach
  the gait over allowed transitions that the hardware can make (``entry_path``); no such
  path is an error (``no-entry``).

Messages name limbs, actuators and states by name and label; steps count from 1 (step 1
is the gait's first transition), as everywhere in proleg's messages.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..errors import GaitError
from ..states import limb_levels
from ..transitions import TransitionTable

if TYPE_CHECKING:  # the robot layer sits above the gait engine; only its shape is used
    from ..robot import Robot

REST = 0  # every limb at level 0


@dataclass(frozen=True)
class Problem:
    """One reason a gait cannot run (``severity == "error"``) or may misbehave ("warning")."""

    kind: str       # shared-actuator | opposing | on-time | never-cools | no-entry
    severity: str   # error | warning
    message: str


@dataclass(frozen=True)
class EntryPath:
    """From rest into a gait: ``states`` runs from the rest state to ``states[-1]``, which is
    the gait's state at position ``gait_step`` (0 = the gait's first state); the gait is then
    run from there. ``states == (rest,)`` when the gait passes through rest."""

    states: tuple[int, ...]
    gait_step: int

    @property
    def transitions(self) -> int:
        return len(self.states) - 1


def _open(states: Sequence[int]) -> list[int]:
    s = [int(x) for x in states]
    return s[:-1] if len(s) > 1 and s[0] == s[-1] else s


def _name(robot: "Robot", states: Sequence[int]) -> str:
    return " ".join(robot.transitions.label(s) for s in states)


def step_problems(robot: "Robot", a: int, b: int) -> list[tuple[str, str, str]]:
    """(kind, severity, what) for one step a -> b: shared actuators moving limbs apart
    (error) and opposing crossings across actuators (warning)."""
    la, lb = limb_levels(a, robot.levels), limb_levels(b, robot.levels)
    moves = {limb.name: (y > x) - (y < x) for limb, x, y in zip(robot.limbs, la, lb)}
    out = []
    for act in robot.actuators:
        driven = [limb.name for limb in robot.limbs if limb.actuator == act.name]
        up = [n for n in driven if moves[n] > 0]
        down = [n for n in driven if moves[n] < 0]
        if up and down:
            out.append((
                "shared-actuator", "error",
                f"limbs {', '.join(map(repr, up))} and {', '.join(map(repr, down))} share actuator {act.name!r} "
                f"but would move in opposite directions",
            ))
    if not out and any(v > 0 for v in moves.values()) and any(v < 0 for v in moves.values()):
        rising = [n for n, v in moves.items() if v > 0]
        falling = [n for n, v in moves.items() if v < 0]
        out.append((
            "opposing", "warning",
            f"raises {', '.join(map(repr, rising))} while lowering {', '.join(map(repr, falling))} "
            f"(a heating and a cooling crossing must coincide)",
        ))
    return out


def _on_states(robot: "Robot", cycle: list[int], actuator: str) -> list[bool]:
    idx = [i for i, limb in enumerate(robot.limbs) if limb.actuator == actuator]
    return [any(limb_levels(s, robot.levels)[i] > 0 for i in idx) for s in cycle]


def _state_times_ms(robot: "Robot", cycle: list[int]) -> list[float]:
    """How long each state of the cycle lasts, at least: hold_ms, or the transition's duration."""
    table = robot.transitions
    hold = float(robot.control.hold_ms)
    if table.duration is None:
        return [hold] * len(cycle)
    keys = {(int(a), int(b)): float(d) for a, b, d in zip(table.src, table.dst, table.duration)}
    return [max(hold, 1000.0 * keys.get((a, b), 0.0)) for a, b in zip(cycle, cycle[1:] + cycle[:1])]


def on_time_problems(robot: "Robot", cycle: list[int]) -> list[Problem]:
    """The longest continuous on-time of each coil, run cyclically, against max_on_ms."""
    out = []
    times = _state_times_ms(robot, cycle)
    gait = _name(robot, cycle + cycle[:1])
    for act in robot.actuators:
        on = _on_states(robot, cycle, act.name)
        if all(on):
            out.append(Problem(
                "never-cools", "error",
                f"gait {gait}: actuator {act.name!r} is on in every state (a limb it drives is raised "
                f"throughout), so it never cools down",
            ))
            continue
        longest, run, where = 0.0, 0.0, None
        start = on.index(False) + 1  # walk the cycle from just after an off state
        for k in range(len(cycle)):
            i = (start + k) % len(cycle)
            run = run + times[i] if on[i] else 0.0
            if run > longest:
                longest, where = run, i
        if longest > robot.safety.max_on_ms:
            out.append(Problem(
                "on-time", "error",
                f"gait {gait}: actuator {act.name!r} stays on for at least {longest:g} ms up to state "
                f"{robot.transitions.label(cycle[where])}, above safety.max_on_ms = {robot.safety.max_on_ms}",
            ))
    return out


def gait_problems(robot: "Robot", states: Sequence[int]) -> list[Problem]:
    """Every problem running ``states`` (a closed or open cycle of state indices) on ``robot``."""
    cycle = _open(states)
    gait = _name(robot, cycle + cycle[:1])
    out = []
    for k, (a, b) in enumerate(zip(cycle, cycle[1:] + cycle[:1]), start=1):
        for kind, severity, what in step_problems(robot, a, b):
            label = f"{robot.transitions.label(a)} -> {robot.transitions.label(b)}"
            out.append(Problem(kind, severity, f"gait {gait}: step {k} ({label}) {what}"))
    out += on_time_problems(robot, cycle)
    try:
        entry_path(robot, cycle)
    except GaitError as e:
        out.append(Problem("no-entry", "error", str(e)))
    return out


def check_gait(robot: "Robot", states: Sequence[int]) -> None:
    """Raise GaitError with the first error ``gait_problems`` finds (warnings pass)."""
    for p in gait_problems(robot, states):
        if p.severity == "error":
            raise GaitError(p.message)


def entry_path(robot: "Robot", states: Sequence[int], rest: int = REST) -> EntryPath:
    """The shortest walk from ``rest`` into the gait over allowed transitions that the
    hardware can make (no shared actuator moving its limbs apart); ties go to the gait state
    that comes first in the gait, then to the lowest states. GaitError when there is none."""
    cycle = _open(states)
    if rest in cycle:
        return EntryPath((rest,), cycle.index(rest))
    table: TransitionTable = robot.transitions
    targets = {s: i for i, s in reversed(list(enumerate(cycle)))}
    parent = {rest: rest}
    queue = deque([rest])
    while queue:
        layer = sorted(queue)
        queue.clear()
        reached = [s for s in layer if s in targets]
        if reached:
            end = min(reached, key=lambda s: targets[s])
            path = [end]
            while path[-1] != rest:
                path.append(parent[path[-1]])
            return EntryPath(tuple(reversed(path)), targets[end])
        for a in layer:
            lo, hi = table.src.searchsorted(a), table.src.searchsorted(a, side="right")
            for b in sorted(int(x) for x in table.dst[lo:hi]):
                if b not in parent and not any(sev == "error" for _, sev, _ in step_problems(robot, a, b)):
                    parent[b] = a
                    queue.append(b)
    raise GaitError(
        f"gait {_name(robot, cycle + cycle[:1])}: no allowed path from the rest state "
        f"{table.label(rest)} into the gait (every limb at level 0 first)"
    )
