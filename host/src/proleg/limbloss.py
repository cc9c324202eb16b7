"""What a robot can still do when one actuator is lost, and its best gait then.

Two ways to go on without actuator ``a`` (both are computed, the better one is used):

* **dead** — the limb→actuator map stays as compiled; the limbs ``a`` drove can no longer
  rise by themselves: every state with such a limb above level 0 can be neither reached nor
  held, so every transition into or out of one is forbidden.
* **remap** — each limb ``a`` drove is given to the actuator of its nearest other limb
  (fewest limbs apart, the lower index on a tie); that actuator now raises its own limbs and
  the foreign one(s). One coil bends the body from its own end: it crosses its own limb's ψ*
  first and the foreign limb's only when it contracts further (R1: α ≈ 0.33 and 0.74,
  docs/plant.md). So a foreign limb can be above level 0 only while every own limb of the
  coil is too, and a step may change a foreign limb's level only if no other limb of that
  coil changes in the same step (one coil cannot make the two cross together). For R1
  without ``sma-right`` this gives exactly the paper's one-actuator matrix
  (robots/paper-r1-one-actuator.toml): 00↔10, 10↔11.

Rewards are the robot's own (they depend on the friction states, not on which coil made
them). Gaits are ranked by rate (reward per transition, simple cycles), as in ``replan``.
The firmware carries these fallbacks (gait_table.c, core/limbmap.c) and the host replans
with them (proleg.learn.replan); both must agree, so both call ``fallback`` here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .states import limb_levels
from .transitions import TransitionTable


@dataclass(frozen=True)
class Fallback:
    actuator: str                     # the lost actuator
    lost: int                         # its index in robot.actuators
    mode: str                         # "dead" | "remap"
    actuator_map: tuple[int, ...]     # actuator index per limb to run with
    table: TransitionTable            # what the robot can still do with that map
    states: tuple[int, ...] | None    # best closed walk (first state repeated last), None: none
    rate: float                       # its reward per transition (0 when none)

    def describe(self, robot) -> str:
        if self.states is None:
            return f"without {self.actuator}: no gait moves {robot.name} this way"
        labels = "→".join(self.table.label(s) for s in self.states)
        names = ", ".join(f"{limb.name}→{robot.actuators[a].name}"
                          for limb, a in zip(robot.limbs, self.actuator_map))
        return f"without {self.actuator}: gait {labels} (rate {self.rate:+.3g} per transition), map {names}"


def compiled_map(robot) -> tuple[int, ...]:
    """The robot file's limb→actuator map as actuator indices."""
    index = {a.name: i for i, a in enumerate(robot.actuators)}
    return tuple(index[limb.actuator] for limb in robot.limbs)


def _restrict(t: TransitionTable, keep: np.ndarray) -> TransitionTable:
    planar = None
    if t.planar is not None:
        planar = type(t.planar)(**{k: np.asarray(v)[keep] for k, v in t.planar.given().items()})
    return TransitionTable(t.levels, t.src[keep], t.dst[keep], t.reward[keep],
                           None if t.duration is None else t.duration[keep], planar)


def dead_table(robot, lost: int) -> TransitionTable:
    """The robot's table without the transitions that need actuator ``lost`` (module doc)."""
    t = robot.transitions
    amap = compiled_map(robot)
    driven = [i for i, a in enumerate(amap) if a == lost]
    up = np.array([any(limb_levels(s, t.levels)[i] > 0 for i in driven) for s in range(t.n_states)], dtype=bool)
    return _restrict(t, ~(up[t.src] | up[t.dst]))


def remap(robot, lost: int) -> tuple[int, ...] | None:
    """The map that gives each limb of ``lost`` to its nearest other limb's actuator (None:
    no other actuator drives any limb)."""
    amap = compiled_map(robot)
    others = [i for i, a in enumerate(amap) if a != lost]
    if not others:
        return None
    out = list(amap)
    for i, a in enumerate(amap):
        if a == lost:
            j = min(others, key=lambda k: (abs(k - i), k))
            out[i] = amap[j]
    return tuple(out)


def remapped_table(robot, new_map: tuple[int, ...]) -> TransitionTable:
    """What the robot can do with ``new_map`` (module doc: foreign limbs follow own limbs)."""
    t = robot.transitions
    own = compiled_map(robot)
    groups = []  # per coil that gained limbs: (own limbs, foreign limbs, all its limbs)
    for a in sorted(set(new_map)):
        mine = [i for i, b in enumerate(own) if b == a]
        foreign = [i for i, b in enumerate(new_map) if b == a and own[i] != a]
        if foreign:
            groups.append((mine, foreign, mine + foreign))
    lv = [limb_levels(s, t.levels) for s in range(t.n_states)]
    ok_state = np.array([all(not any(lv[s][f] > 0 for f in foreign) or all(lv[s][m] > 0 for m in mine)
                             for mine, foreign, _ in groups) for s in range(t.n_states)], dtype=bool)
    keep = ok_state[t.src] & ok_state[t.dst]
    for e in range(len(t.src)):
        if not keep[e]:
            continue
        a, b = lv[int(t.src[e])], lv[int(t.dst[e])]
        for _, foreign, every in groups:
            changed = [i for i in every if a[i] != b[i]]
            if any(i in foreign for i in changed) and len(changed) > 1:
                keep[e] = False
    return _restrict(t, keep)


def best_gait(table: TransitionTable, direction: str) -> tuple[tuple[int, ...] | None, float]:
    """Best simple cycle by rate in ``direction`` (closed walk, rate), or (None, 0.0)."""
    from .errors import GaitError
    from .gait import optimal_gaits

    sign = 1.0 if direction == "+x" else -1.0
    if not table.n_transitions:
        return None, 0.0
    try:
        res = optimal_gaits(table, "rate", direction)
    except GaitError:
        return None, 0.0
    if not res.gaits or res.value is None or sign * float(res.value) <= 0:
        return None, 0.0
    g = res.gaits[0]
    states = tuple(int(s) for s in g.states)
    if states[0] != states[-1]:
        states += (states[0],)
    return states, float(res.value)


def fallback(robot, lost: int | str, direction: str = "+x") -> Fallback:
    """The better of "dead" and "remap" without actuator ``lost`` (index or name)."""
    if isinstance(lost, str):
        names = [a.name for a in robot.actuators]
        if lost not in names:
            raise ValueError(f"robot {robot.name} has no actuator {lost!r} (it has {', '.join(names)})")
        lost = names.index(lost)
    name = robot.actuators[lost].name
    if direction not in ("+x", "-x"):
        raise ValueError(f"fallback: direction {direction!r}: expected +x or -x")
    sign = 1.0 if direction == "+x" else -1.0
    amap = compiled_map(robot)
    t = dead_table(robot, lost)
    states, rate = best_gait(t, direction)
    best = Fallback(name, lost, "dead", amap, t, states, rate)
    new = remap(robot, lost)
    if new is not None:
        t = remapped_table(robot, new)
        states, rate = best_gait(t, direction)
        if states is not None and (best.states is None or sign * rate > sign * best.rate * (1 + 1e-9)):
            best = Fallback(name, lost, "remap", new, t, states, rate)
    return best
