"""The way from rest into a gait: the walk the firmware follows before the gait's first step.

Contract. ``entry_walk(table, cycle, rest, can_step, unheld, blocked)`` returns the
``EntryPath`` from ``rest`` into ``cycle`` (an open cycle of state indices):

* ``(rest,)`` at the gait step of ``rest`` when the gait passes through it;
* else the shortest walk over the table's transitions that ``can_step`` lets through (the
  steps the hardware can make) and that keeps out of the states in ``unheld`` (the body
  cannot hold them; a gait state's own trouble is the gait's, so gait states are never
  avoided) and the steps in ``blocked`` (the body cannot end them), however much longer
  than the shortest walk through them;
* failing that, the shortest walk over the steps ``can_step`` lets through, whatever it
  goes through (the caller says what is wrong with it: ``feasibility.gait_problems``);
* ties go to the gait state that comes first in the gait, then to the lowest states (each
  state is reached from the lowest state one step nearer to rest);
* ``GaitError`` naming the gait and the rest state when there is no walk at all.

Every state of the walk before its last is outside the gait. The search is breadth-first,
one layer (states at one distance from rest) at a time. The robot-level entry point is
``feasibility.entry_path``, which supplies ``can_step``, ``unheld`` and ``blocked`` from the
robot (``step_problems``, ``Robot.unholdable``, ``Robot.blocked``).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Container
from dataclasses import dataclass

from ..errors import GaitError
from ..transitions import TransitionTable

REST = 0  # every limb at level 0


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


def entry_walk(table: TransitionTable, cycle: list[int], rest: int, can_step: Callable[[int, int], bool],
               unheld: Container[int] = (), blocked: Container[tuple[int, int]] = ()) -> EntryPath:
    """The entry path from ``rest`` into ``cycle`` (see the module's contract)."""
    if rest in cycle:
        return EntryPath((rest,), cycle.index(rest))

    def holdable(a: int, b: int) -> bool:  # a gait state's own trouble is the gait's problem
        return (b not in unheld or b in cycle) and (a, b) not in blocked

    try:
        return _shortest_walk(table, cycle, rest, lambda a, b: holdable(a, b) and can_step(a, b))
    except GaitError:
        return _shortest_walk(table, cycle, rest, can_step)


def _shortest_walk(table: TransitionTable, cycle: list[int], rest: int, ok: Callable[[int, int], bool]) -> EntryPath:
    """``entry_walk``'s breadth-first search over the steps ``ok`` lets through."""
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
                if b not in parent and ok(a, b):
                    parent[b] = a
                    queue.append(b)
    raise GaitError(
        f"gait {' '.join(table.label(s) for s in cycle + cycle[:1])}: no allowed path from the rest state "
        f"{table.label(rest)} into the gait (every limb at level 0 first)"
    )
