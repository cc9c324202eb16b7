"""What a robot can still do when one actuator is lost, and its best gait then.

Two ways to go on without actuator ``a`` (both are computed, the better one is used):

* **dead** — the limb→actuator map stays as compiled; the limbs ``a`` drove can no longer
  rise by themselves: every state with such a limb above level 0 can be neither reached nor
  held, so every transition into or out of one is forbidden.
* **remap** — each limb ``a`` drove is given to the actuator of its nearest other limb
  (fewest limbs apart, the lower index on a tie) that can lift it: on the physical plant's
  body (``body.coil_reach_deg``, from ``[plant]`` length_mm and overlap_mm) that coil
  alone, at full stroke, bends the limb past its first level's entry edge (ψ* +
  hysteresis/2), and the limb may rise only to the levels the coil reaches. A limb no other
  coil can lift stays on ``a``, i.e. dead; when none can be lifted there is no remap (on
  R1's 80 mm body a coil lifts the other end to 23.5°, past 21°; on the three- and
  four-limb examples a neighbour's coil lifts a limb 8–17°, short of it: a remap there would
  heat a healthy coil to its on-time limit and then blame it). That actuator now raises its
  own limbs and the foreign one(s). One coil bends the body from its own end: it crosses its
  own limb's ψ* first and the foreign limb's only when it contracts further (R1: α ≈ 0.33
  and 0.74, docs/plant.md). So a foreign limb can be above level 0 only while every own limb
  of the coil is too, at least at the level the contraction that lifts the foreign limb bends
  it to (``own_levels_under``: a multi-level own limb, its top level in practice), and a step may change a foreign limb's level only if no other limb of
  that coil changes in the same step (one coil cannot make the two cross together). For R1
  without ``sma-right`` this gives exactly the paper's one-actuator matrix
  (robots/paper-r1-one-actuator.toml): 00↔10, 10↔11. Then the body has its say: a coil
  contracted far enough to hold a foreign limb up bends its own limb, and the body, further
  than its own limbs alone need; states where that lifts another limb past its band, and
  steps where it keeps one from coming down, go too (``robot_body.coupled_states`` and
  ``blocked_descents`` with the remapped drive).

Rewards are the robot's own (they depend on the friction states, not on which coil made
them). Gaits are ranked by rate (reward per transition, simple cycles), as in ``replan``.
The firmware carries these fallbacks (gait_table.c, core/limbmap.c) and the host replans
with them (proleg.learn.replan); both must agree, so both call ``fallback`` here.
"""

from __future__ import annotations

import numbers
from collections.abc import Container, Iterable
from dataclasses import dataclass

import numpy as np

from .body import coil_reach_deg
from .robot_body import body_of
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


def _unreachable(robot, t: TransitionTable) -> np.ndarray:
    """Per state of ``t``: one the intact robot cannot reach on the simulated body
    (``Robot.unreachable``, every raised limb's coil at full stroke). With a coil lost or its
    limbs on other coils no raised limb gets more help, so a fallback cannot reach it either
    (a limb moved onto a coil that happens to reach it further is given up with it)."""
    bad = np.zeros(t.n_states, dtype=bool)
    bad[list(getattr(robot, "unreachable", {}))] = True
    return bad


def dead_table(robot, lost: int | Iterable[int]) -> TransitionTable:
    """The robot's table without the transitions that need actuator ``lost`` (module doc; or
    any of several actuators: a host that lost one after another), nor those into or out of a
    state the robot cannot reach (``_unreachable``), nor those the body cannot make with the
    compiled map (``Robot.unholdable``, ``Robot.blocked``): the dead mode keeps that map, so what the intact body cannot
    hold or end it cannot either."""
    t = robot.transitions
    amap = compiled_map(robot)
    gone = {int(lost)} if isinstance(lost, numbers.Integral) else {int(x) for x in lost}
    driven = [i for i, a in enumerate(amap) if a in gone]
    up = np.array([any(limb_levels(s, t.levels)[i] > 0 for i in driven) for s in range(t.n_states)], dtype=bool)
    up |= _unreachable(robot, t)
    # the load warnings the gait check turns into errors: a three-limb robot without its back
    # coil fell back on 000 -> 010 -> 011 -> 001, in 010 and 011 the back pad lifted past its edge
    # by the middle one: the fallback the firmware switches to would have ended in STATE_TIMEOUT
    held = _clear_of(t, getattr(robot, "unholdable", {}), getattr(robot, "blocked", {}))
    return t.restricted(~(up[t.src] | up[t.dst]) & held)


def _clear_of(t: TransitionTable, states: Container[int], steps: Container[tuple[int, int]]) -> np.ndarray:
    """Per transition of ``t``: neither into nor out of one of ``states``, nor one of ``steps``
    (the body's states it cannot hold and steps it cannot end, ``robot_body``)."""
    return np.array([int(a) not in states and int(b) not in states and (int(a), int(b)) not in steps
                     for a, b in zip(t.src, t.dst)], dtype=bool)


def foreign_top_level(robot, limb: int, actuator: int) -> int:
    """The highest level coil ``actuator`` alone, at full stroke, lifts ``limb`` to on the
    physical plant's body (0: not past its first entry edge, ψ* + hysteresis/2)."""
    reach = coil_reach_deg(body_of(list(compiled_map(robot)), len(robot.actuators), robot.plant), actuator)[limb]
    lb = robot.limbs[limb]
    return sum(1 for star in lb.psi_star_deg if star + lb.hysteresis_deg / 2.0 <= reach)


def own_levels_under(robot, limb: int, actuator: int, own: tuple[int, ...]) -> dict[int, dict[int, int]]:
    """For a foreign ``limb`` lifted by coil ``actuator``: per level j ≥ 1 of it, the lowest
    level each own limb of that coil reads while the coil is contracted enough for level j,
    ``{j: {own limb: level}}`` (at least 1). The contraction is the fraction of the coil's
    full-stroke reach at ``limb`` its entry edge needs (ψ* + hysteresis/2; the body bends in
    proportion to it), and an own limb reads level k + 1 as long as that contraction keeps it
    at or above ψ*(k) − hysteresis/2, the edge it would have to fall below: a three-level own
    limb cannot come down to level 1 while the coil holds a far limb up (on R1's 80 mm body
    that contraction bends the own end to ≈ 52°)."""
    reach = coil_reach_deg(body_of(list(own), len(robot.actuators), robot.plant), actuator)
    lf = robot.limbs[limb]
    out: dict[int, dict[int, int]] = {}
    for j, star in enumerate(lf.psi_star_deg, start=1):
        c = min(1.0, (star + lf.hysteresis_deg / 2.0) / reach[limb]) if reach[limb] > 0 else 1.0
        out[j] = {}
        for m in (i for i, a in enumerate(own) if a == actuator):
            lm = robot.limbs[m]
            k = sum(1 for sm in lm.psi_star_deg if sm - lm.hysteresis_deg / 2.0 <= c * reach[m])
            out[j][m] = max(1, k)
    return out


def remap(robot, lost: int) -> tuple[int, ...] | None:
    """The map that gives each limb of ``lost`` to the actuator of its nearest other limb
    that can lift it (module doc); a limb none can lift stays on ``lost`` (dead). None: no
    limb of ``lost`` can be lifted by another coil."""
    amap = compiled_map(robot)
    others = [i for i, a in enumerate(amap) if a != lost]
    out = list(amap)
    for i, a in enumerate(amap):
        if a != lost:
            continue
        for j in sorted(others, key=lambda k: (abs(k - i), k)):
            if foreign_top_level(robot, i, amap[j]) > 0:
                out[i] = amap[j]
                break
    return None if out == list(amap) else tuple(out)


def remapped_table(robot, new_map: tuple[int, ...], lost: int | None = None, *, body: bool = True) -> TransitionTable:
    """What the robot can do with ``new_map`` after losing actuator ``lost`` (module doc:
    foreign limbs follow own limbs, up to the levels their new coil lifts them to; a limb
    ``new_map`` leaves on ``lost``, which no other coil lifts, stays down), and, with ``body``,
    what the physical plant's body then lets it hold and finish (``_body_allows``)."""
    t = robot.transitions
    own = compiled_map(robot)
    groups = []  # per coil that gained limbs: (own limbs, foreign limbs, all its limbs)
    tops = {}    # foreign limb -> the highest level its new coil lifts it to
    for a in sorted(set(new_map) - {lost}):
        mine = [i for i, b in enumerate(own) if b == a]
        foreign = [i for i, b in enumerate(new_map) if b == a and own[i] != a]
        if foreign:
            groups.append((mine, foreign, mine + foreign))
            tops.update({f: foreign_top_level(robot, f, a) for f in foreign})
    down = [i for i, b in enumerate(new_map) if b == lost]  # no coil lifts these
    lv = [limb_levels(s, t.levels) for s in range(t.n_states)]
    needs = {f: own_levels_under(robot, f, new_map[f], own) for _, foreign, _ in groups for f in foreign}

    def coil_ok(s: int, mine: list[int], foreign: list[int]) -> bool:
        up = [f for f in foreign if lv[s][f] > 0]
        return all(lv[s][m] >= max(needs[f][lv[s][f]][m] for f in up) for m in mine) if up else True

    ok_state = np.array([all(coil_ok(s, mine, foreign) for mine, foreign, _ in groups)
                         and all(lv[s][f] <= top for f, top in tops.items())
                         and not any(lv[s][i] > 0 for i in down) for s in range(t.n_states)], dtype=bool)
    ok_state &= ~_unreachable(robot, t)
    keep = ok_state[t.src] & ok_state[t.dst]
    for e in range(len(t.src)):
        if not keep[e]:
            continue
        a, b = lv[int(t.src[e])], lv[int(t.dst[e])]
        for _, foreign, every in groups:
            changed = [i for i in every if a[i] != b[i]]
            if any(i in foreign for i in changed) and len(changed) > 1:
                keep[e] = False
    if groups and body:
        keep &= _body_allows(robot, t.restricted(keep), new_map, t)
    return t.restricted(keep)


def _body_allows(robot, table: TransitionTable, new_map: tuple[int, ...], full: TransitionTable) -> np.ndarray:
    """Per transition of ``full``: whether the physical plant's body lets the remapped robot
    make it. A coil that lifts a foreign limb contracts far enough to bend its own limb, and
    the body, far past where it holds them alone: inchworm-3 on a 160 mm body without its
    head coil held the head up with the middle coil, which bent the middle to 60° and kept the
    tail up, so 111 -> 011 never finished, the middle coil ran into its on-time limit and the
    fault blamed the tail (``robot_body.coupled_states`` and ``blocked_descents`` with the
    remapped drive)."""
    from .robot_body import body_coupling

    coupled, blocked = body_coupling(robot, table, list(new_map))
    return _clear_of(full, coupled, blocked)


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
        t = remapped_table(robot, new, lost)
        states, rate = best_gait(t, direction)
        if states is not None and (best.states is None or sign * rate > sign * best.rate * (1 + 1e-9)):
            best = Fallback(name, lost, "remap", new, t, states, rate)
    return best
