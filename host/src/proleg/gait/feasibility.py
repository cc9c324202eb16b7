"""Can the robot's hardware run a gait, and how does it get there from rest?

The optimiser sees only the transition table; the robot file also says which actuator
drives which limb and how long a coil may stay on. An SMA coil raises its limb(s) when hot
and lets them fall when it cools, so:

* **Shared actuators** — limbs driven by one actuator rise and fall together: a step that
  raises one of them while lowering another cannot be made (error ``shared-actuator``), and
  neither can a step that raises or lowers only some of them into a state the coil cannot
  hold — it lifts one of its limbs while holding another up (``Robot.coil_lifts``, from the
  body model that warns about it when the file is loaded: one coil on two limbs lifts its
  near limb first, so paper-r1-one-actuator makes 00 -> 10 -> 11 but never 01).
* **Unreachable states** — a step into a state in which some raised limb cannot get to its
  level on the simulated body, even with every raised limb's coil at full stroke (a limb
  named on another limb's coil, which sits at that limb: ``Robot.unreachable``): error
  ``unreachable``.
* **States the body cannot hold** — a step into a state in which a limb rests or is lifted by
  its raised neighbours past its level's upper edge on the simulated body (``Robot.unholdable``,
  the load check's "cannot be held" lines): it reads as another state, and the firmware's step
  ends in STATE_TIMEOUT (error ``unholdable``, not refused by the build: the body is a model).
  On two limbs, a limb held up inside the band above its level (it reads its level but never
  settles: the firmware's rule for that is built for three or more limbs) is one too.
* **Steps that cannot end** — a step that lowers a limb the raised limbs of the state it goes
  to keep above its level's lower edge (``Robot.blocked``, the load check's "cannot come down"
  lines): it keeps reading the level above and the step ends in STATE_TIMEOUT (error
  ``blocked``, like ``unholdable`` not refused by the build).
* **Opposing steps** — a step that raises a limb on one actuator while lowering a limb on
  another needs a heating and a cooling crossing to coincide; the controller synchronises
  them as well as it can, but the robot may pass through an intermediate state (warning
  ``opposing``; ``proleg.states.opposing_steps``).
* **Hold time vs on-time** — the firmware keeps an on-time *debt* per coil
  (``gait.coil_debt``, docs/safety.md): a coil adds on-time while it raises one of its
  limbs (for the transition's duration, or ``DEFAULT_DRIVE_S``); holding a raised limb,
  lowering one and the ``control.hold_ms`` the firmware holds each reached state pay it
  back at ``max_on_ms`` / ``min_cooldown_ms``. Run cyclically from cool coils, a debt that
  passes ``safety.max_on_ms`` is cut by the firmware (error ``on-time``); a coil that drives
  up more debt per cycle than the cycle pays back is cut sooner or later (error
  ``never-cools``). Holding a limb up for the whole gait is fine (docs/safety.md: the
  one-coil gait 10 -> 11 -> 10).
* **Step time vs state timeout** — the firmware latches ``STATE_TIMEOUT`` when a step's
  target is demanded ``safety.state_timeout_ms`` without being reached (docs/safety.md): a
  step the robot file says takes that long or longer (``durations_s``, a CSV's ``duration_s``
  or ``default_duration_s``), the entry path's from rest included, is cut (error ``timeout``).
  Without durations nothing is assumed.
* **Entry** — the firmware starts from rest (every limb at level 0, state 0) and must reach
  the gait over allowed transitions that the hardware can make (``entry_path``); no such
  path is an error (``no-entry``).

Messages name limbs, actuators and states by name and label; steps count from 1 (step 1
is the gait's first transition), as everywhere in proleg's messages.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..errors import GaitError
from ..robot_body import unsettled
from .coil_debt import EPS_S, Step, coil_budget, cycle_debt
from .entry import REST, EntryPath, entry_walk
from ..states import limb_levels

if TYPE_CHECKING:  # the robot layer sits above the gait engine; only its shape is used
    from ..robot import Robot

DEFAULT_DRIVE_S = 1.0  # a transition's drive time when the table has no durations: R1 takes 0.7–1.2 s


@dataclass(frozen=True)
class Problem:
    """One reason a gait cannot run (``severity == "error"``) or may misbehave ("warning")."""

    kind: str       # shared-actuator | unreachable | unholdable | blocked | opposing | on-time | never-cools | timeout | no-entry
    severity: str   # error | warning
    message: str


def _open(states: Sequence[int]) -> list[int]:
    s = [int(x) for x in states]
    return s[:-1] if len(s) > 1 and s[0] == s[-1] else s


def _name(robot: "Robot", states: Sequence[int]) -> str:
    return " ".join(robot.transitions.label(s) for s in states)


def _per_step(robot: "Robot", what: str) -> dict:
    """A cache of one per-step answer on ``robot`` (keyed (a, b)): the answers depend only on
    the robot, which is frozen, and a robot with thousands of tied gaits (an 8-limb one has
    10,000) asks the same few hundred steps again and again."""
    caches = robot.__dict__.get("_feasibility_cache")
    if caches is None:
        caches = {}
        object.__setattr__(robot, "_feasibility_cache", caches)
    return caches.setdefault(what, {})


def step_problems(robot: "Robot", a: int, b: int) -> list[tuple[str, str, str]]:
    """(kind, severity, what) for one step a -> b: shared actuators moving limbs apart
    (error) and opposing crossings across actuators (warning)."""
    cache = _per_step(robot, "problems")
    if (a, b) not in cache:
        cache[(a, b)] = tuple(_step_problems(robot, a, b))
    return list(cache[(a, b)])


def _step_problems(robot: "Robot", a: int, b: int) -> list[tuple[str, str, str]]:
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
        elif (up or down) and len(up or down) < len(driven) and (why := _coil_cannot_hold(robot, act.name, b)):
            moved = ", ".join(map(repr, up or down))
            still = ", ".join(repr(n) for n in driven if moves[n] == 0)
            out.append((
                "shared-actuator", "error",
                f"{'raises' if up else 'lowers'} {moved} but not {still}, which share actuator {act.name!r}: {why}",
            ))
    if a != b and b in getattr(robot, "unreachable", {}):
        out.append(("unreachable", "error", f"goes to state {robot.transitions.label(b)}, {CANNOT_REACH}: "
                                            f"{_short_of(robot, b)} (the warning when the robot file is loaded)"))
    if not out and any(v > 0 for v in moves.values()) and any(v < 0 for v in moves.values()):
        rising = [n for n, v in moves.items() if v > 0]
        falling = [n for n, v in moves.items() if v < 0]
        out.append((
            "opposing", "warning",
            f"raises {', '.join(map(repr, rising))} while lowering {', '.join(map(repr, falling))} "
            f"(a heating and a cooling crossing must coincide)",
        ))
    return out


CANNOT_REACH = "which the robot cannot reach on the simulated body (every raised limb's coil at full stroke)"


def _short_of(robot: "Robot", state: int) -> str:
    """Why ``state`` cannot be reached (``Robot.unreachable``)."""
    return "; ".join(f"{robot.limbs[i].name!r} needs ψ ≥ {need:.1f}° and gets at most {got:.1f}°"
                     for i, got, need in robot.unreachable[state])


def _unreachable_problem(robot: "Robot", gait: str, unreached: list[tuple[int, int]]) -> Problem:
    """One ``unreachable`` error for the steps of a gait into states it cannot reach: the first
    three named, with the reason for the first."""
    label = robot.transitions.label
    named = ", ".join(f"{label(b)} (step {k})" for k, b in unreached[:3])
    more = f" and {len(unreached) - 3} more" if len(unreached) > 3 else ""
    first = unreached[0][1]
    return Problem("unreachable", "error", f"gait {gait}: goes to state{'s' if len(unreached) > 1 else ''} "
                                           f"{named}{more}, {CANNOT_REACH}: in {label(first)} "
                                           f"{_short_of(robot, first)} (the warning when the robot file is loaded)")


def _body_problem(robot: "Robot", gait: str, kind: str, places: list[str], why: str,
                  entry: Sequence[int] = ()) -> Problem:
    """One ``unholdable`` or ``blocked`` error for a gait's steps into states the body cannot
    hold (``Robot.unholdable``; ``places`` names the states) or steps it cannot end
    (``Robot.blocked``, ``robot_body.blocked_descents``; ``places`` names the steps), the first
    three named, with ``why`` the first cannot be (``unholdable_why``, ``blocked_why``). With
    ``entry``, the places are on the gait's entry path from rest, which goes through them
    because every way in does (``entry_path`` keeps out of them where it can).

    A planar robot's library gait through such a state (011 111 101 …, the middle pad lifted to
    12.5° past its 11° edge in 101), nano-3x6 (three 6-level limbs) and R1 with hysteresis 16°
    through such steps were built without a word and ended in STATE_TIMEOUT; so did a gait whose
    own steps are clean but whose entry is not: the firmware follows that path, and it stopped
    before the gait began."""
    more = f" and {len(places) - 3} more" if len(places) > 3 else ""
    s = "s" if len(places) > 1 else ""
    what = (f"goes to state{s} {', '.join(places[:3])}{more}, which the simulated body cannot hold"
            if kind == "unholdable" else
            f"makes the step{s} {', '.join(places[:3])}{more}, which the simulated body cannot end")
    if entry:
        what = f"its entry from rest ({_name(robot, entry)}) {what}, and there is no other way in"
    return Problem(kind, "error", f"gait {gait}: {what}: {why}")


def unholdable_why(robot: "Robot", state: int) -> str:
    """Why the body cannot hold ``state`` (one of ``Robot.unholdable``): ``in 101 'mid' (level 0)
    sits at …, so it reads as another state and the step ends in STATE_TIMEOUT``."""
    levels = limb_levels(state, robot.levels)
    held = robot.unholdable[state]
    why = "; ".join(_unheld_why(robot.limbs[i], levels[i], psi) for i, psi in held)
    reads = ("it never settles" if all(unsettled(robot.limbs[i], levels[i], psi) for i, psi in held)
             else "it reads as another state")
    return (f"in {robot.transitions.label(state)} {why} (the warning when the robot file is loaded), so {reads} "
            "and the step ends in STATE_TIMEOUT")


def _unheld_why(limb: Any, level: int, psi: float) -> str:
    """Why ``limb`` on ``level`` at ψ cannot be held: past the band above its level, or (two
    limbs: ``robot_body.unsettled``) inside it, where it never settles."""
    lo, hi = (limb.psi_star_deg[level] - limb.hysteresis_deg / 2, limb.psi_star_deg[level] + limb.hysteresis_deg / 2)
    if unsettled(limb, level, psi):
        return (f"{limb.name!r} (level {level}) is held up to {psi:.1f}°, inside the band above its level "
                f"({lo:.1f}..{hi:.1f}°)")
    return f"{limb.name!r} (level {level}) sits at {psi:.1f}°, past its level-{level + 1} edge {hi:.1f}°"


def blocked_why(robot: "Robot", a: int, b: int) -> str:
    """Why the body cannot end the step ``a`` -> ``b`` (one of ``Robot.blocked``): ``in 01 the
    raised limbs hold …, so it keeps reading level 1 and the step ends in STATE_TIMEOUT``."""
    i, _, psi = robot.blocked[(a, b)]
    limb, k = robot.limbs[i], limb_levels(b, robot.levels)[i]
    return (f"in {robot.transitions.label(b)} the raised limbs hold {limb.name!r} at {psi:.1f}°, above its level-{k} "
            f"edge {limb.psi_star_deg[k] - limb.hysteresis_deg / 2:.1f}° (the warning when the robot file is loaded), "
            f"so it keeps reading level {k + 1} and the step ends in STATE_TIMEOUT")


def _coil_cannot_hold(robot: "Robot", actuator: str, state: int) -> str | None:
    """Why ``actuator`` cannot hold ``state`` (``Robot.coil_lifts``), or None."""
    for act, lifted, raised in getattr(robot, "coil_lifts", {}).get(state, ()):
        if act == actuator:
            up = ", ".join(repr(robot.limbs[j].name) for j in raised)
            return (f"holding {up} up, it lifts {robot.limbs[lifted].name!r} too on the simulated body, so state "
                    f"{robot.transitions.label(state)} cannot be held (the warning when the robot file is loaded; "
                    f"mark the transitions into it \"x\")")
    return None


def _rising_coils(robot: "Robot", a: int, b: int) -> tuple[bool, ...]:
    """Which actuators drive during a -> b: those raising one of their limbs."""
    cache = _per_step(robot, "rising")
    if (a, b) not in cache:
        la, lb = limb_levels(a, robot.levels), limb_levels(b, robot.levels)
        cache[(a, b)] = tuple(
            any(y > x for limb, x, y in zip(robot.limbs, la, lb) if limb.actuator == act.name)
            for act in robot.actuators
        )
    return cache[(a, b)]


def coil_steps(robot: "Robot", cycle: Sequence[int]) -> list[Step]:
    """The gait's steps as the coils see them: a -> b drives the raising coils for the
    transition's duration (``DEFAULT_DRIVE_S`` when the table has none), then the firmware
    holds b for ``control.hold_ms`` before it advances."""
    cycle = _open(cycle)
    table = robot.transitions
    durations = {}
    if table.duration is not None:
        durations = {(int(a), int(b)): float(d) for a, b, d in zip(table.src, table.dst, table.duration)}
    hold = robot.control.hold_ms / 1000.0
    return [
        Step(_rising_coils(robot, a, b), durations.get((a, b), DEFAULT_DRIVE_S), hold)
        for a, b in zip(cycle, cycle[1:] + cycle[:1])
    ]


def on_time_problems(robot: "Robot", cycle: list[int]) -> list[Problem]:
    """Each coil's on-time debt, run cyclically, against the firmware's budget."""
    out = []
    gait = _name(robot, cycle + cycle[:1])
    budget = coil_budget(robot.safety.max_on_ms, robot.safety.min_cooldown_ms, robot.control.tick_hz)
    steps = coil_steps(robot, cycle)
    for act, debt in zip(robot.actuators, cycle_debt(steps, budget.payback)):
        if debt.growth_s > 0:
            out.append(Problem(
                "never-cools", "error",
                f"gait {gait}: actuator {act.name!r} gains {1000 * debt.growth_s:.0f} ms of on-time debt every cycle "
                f"(it drives longer than holding and lowering pay back at max_on_ms / min_cooldown_ms), "
                f"so the firmware cuts it (SMA_ON_LIMIT) after a few cycles",
            ))
        elif debt.peak_s > budget.max_on_s + EPS_S:
            label = robot.transitions.label(cycle[(debt.at_step + 1) % len(cycle)])
            out.append(Problem(
                "on-time", "error",
                f"gait {gait}: actuator {act.name!r} carries {1000 * debt.peak_s:.0f} ms of on-time debt on reaching "
                f"state {label}, above safety.max_on_ms = {robot.safety.max_on_ms}: the firmware cuts it (SMA_ON_LIMIT)",
            ))
    return out


def timeout_problems(robot: "Robot", cycle: list[int], from_rest: bool = True) -> list[Problem]:
    """Each step the robot file's durations say takes ``safety.state_timeout_ms`` or longer, the
    steps of the entry path from rest included (the sequencer times them alike: seq.c): the
    firmware stops it with STATE_TIMEOUT. R1 with ``default_duration_s = 0.9`` and
    ``state_timeout_ms = 500`` built without a word and faulted 0.6 s after START; gait 10 11 01
    of an R1 whose 00 -> 10 takes 9 s (against 8 s) was let through, its entry being that step."""
    table = robot.transitions
    if table.duration is None:
        return []
    durations = {(int(a), int(b)): float(d) for a, b, d in zip(table.src, table.dst, table.duration)}
    timeout_ms = robot.safety.state_timeout_ms
    steps = [(f"step {k} ({table.label(a)} -> {table.label(b)})", a, b)
             for k, (a, b) in enumerate(zip(cycle, cycle[1:] + cycle[:1]), start=1)]
    try:
        entry = entry_path(robot, cycle).states if from_rest else ()
    except GaitError:
        entry = ()  # no-entry's problem
    steps += [(f"its entry from rest's step {table.label(a)} -> {table.label(b)}", a, b)
              for a, b in zip(entry, entry[1:])]
    long = [(durations[(a, b)], i, what) for i, (what, a, b) in enumerate(steps)
            if 1000.0 * durations.get((a, b), 0.0) >= timeout_ms]
    if not long:
        return []
    d, _, what = min(long, key=lambda x: (-x[0], x[1]))  # the longest step, the first of equals
    more = f" (and {len(long) - 1} more of its steps)" if len(long) > 1 else ""
    return [Problem(
        "timeout", "error",
        f"gait {_name(robot, cycle + cycle[:1])}: {what} takes {d:g} s (the robot file's durations){more}, not "
        f"under safety.state_timeout_ms = {timeout_ms}: the firmware stops it (STATE_TIMEOUT); raise "
        f"state_timeout_ms or check the durations",
    )]


def gait_problems(robot: "Robot", states: Sequence[int], from_rest: bool = True) -> list[Problem]:
    """Every problem running ``states`` (a closed or open cycle of state indices) on ``robot``;
    with ``from_rest`` False, none of its entry path from rest (a gait loaded by ``load-gait``
    has none: the firmware starts it where the robot stands)."""
    cycle = _open(states)
    gait = _name(robot, cycle + cycle[:1])
    out = []
    unreached = []  # (step, state): one problem for them all (an 8-limb gait may enter dozens)
    for k, (a, b) in enumerate(zip(cycle, cycle[1:] + cycle[:1]), start=1):
        for kind, severity, what in step_problems(robot, a, b):
            if kind == "unreachable":
                unreached.append((k, b))
                continue
            label = f"{robot.transitions.label(a)} -> {robot.transitions.label(b)}"
            out.append(Problem(kind, severity, f"gait {gait}: step {k} ({label}) {what}"))
    if unreached:  # first: a state no drive reaches says the most
        out.insert(0, _unreachable_problem(robot, gait, unreached))
    unheld = [(k, b) for k, (a, b) in enumerate(zip(cycle, cycle[1:] + cycle[:1]), start=1)
              if b in getattr(robot, "unholdable", {}) and b not in {s for _, s in unreached}]
    label = robot.transitions.label
    if unheld:
        out.append(_body_problem(robot, gait, "unholdable", [f"{label(b)} (step {k})" for k, b in unheld],
                                 unholdable_why(robot, unheld[0][1])))
    skip = {s for _, s in unreached} | {s for _, s in unheld}
    stuck = [(k, a, b) for k, (a, b) in enumerate(zip(cycle, cycle[1:] + cycle[:1]), start=1)
             if (a, b) in getattr(robot, "blocked", {}) and b not in skip]
    if stuck:
        out.append(_body_problem(robot, gait, "blocked", [f"{label(a)} -> {label(b)} (step {k})" for k, a, b in stuck],
                                 blocked_why(robot, *stuck[0][1:])))
    out += on_time_problems(robot, cycle)
    out += timeout_problems(robot, cycle, from_rest)
    if not from_rest:
        return out
    try:
        entry = entry_path(robot, cycle).states
    except GaitError as e:
        out.append(Problem("no-entry", "error", str(e)))
        return out
    return out + _entry_body_problems(robot, gait, cycle, entry)


def _entry_body_problems(robot: "Robot", gait: str, cycle: list[int], entry: Sequence[int]) -> list[Problem]:
    """The ``unholdable`` and ``blocked`` errors of a gait's entry path from rest, where every
    way in goes through a state the body cannot hold or a step it cannot end (``entry_path``
    keeps out of them where it can): the firmware follows that path, and it ends in
    STATE_TIMEOUT before the gait begins, though the gait's own steps are clean."""
    label = robot.transitions.label
    steps = list(zip(entry, entry[1:]))
    out = []
    unheld = [b for _, b in steps if b in getattr(robot, "unholdable", {}) and b not in cycle]
    if unheld:
        out.append(_body_problem(robot, gait, "unholdable", [label(b) for b in unheld],
                                 unholdable_why(robot, unheld[0]), entry))
    stuck = [(a, b) for a, b in steps if (a, b) in getattr(robot, "blocked", {}) and b not in unheld]
    if stuck:
        out.append(_body_problem(robot, gait, "blocked", [f"{label(a)} -> {label(b)}" for a, b in stuck],
                                 blocked_why(robot, *stuck[0]), entry))
    return out


def check_gait(robot: "Robot", states: Sequence[int]) -> None:
    """Raise GaitError with the first error ``gait_problems`` finds (warnings pass)."""
    for p in gait_problems(robot, states):
        if p.severity == "error":
            raise GaitError(p.message)


def entry_path(robot: "Robot", states: Sequence[int], rest: int = REST) -> EntryPath:
    """The shortest walk from ``rest`` into the gait over allowed transitions that the
    hardware can make (no shared actuator moving its limbs apart); ties go to the gait state
    that comes first in the gait, then to the lowest states. GaitError when there is none.

    A walk that keeps out of the states the body cannot hold (``Robot.unholdable``) and the
    steps it cannot end (``Robot.blocked``) is taken where there is one, however much longer:
    the shortest walk went through them (a three-limb robot's -x gait entered by 000 -> 010 ->
    020 -> 120, its back pad lifted past its edge in 010 and 020, when 000 -> 100 -> 110 -> 120
    was there), and the firmware, which follows this path, stopped in STATE_TIMEOUT before the
    gait began. Where every walk goes through one, ``gait_problems`` says so. The search
    itself: ``gait.entry``."""
    return entry_walk(robot.transitions, _open(states), rest, lambda a, b: _hardware_can(robot, a, b),
                      getattr(robot, "unholdable", {}), getattr(robot, "blocked", {}))


def _hardware_can(robot: "Robot", a: int, b: int) -> bool:
    """The hardware can make a -> b (step_problems finds no error)."""
    return not any(sev == "error" for _, sev, _ in step_problems(robot, a, b))


def _can_step(robot: "Robot", a: int, b: int) -> bool:
    """a -> b is allowed in the robot file and the hardware can make it (step_problems)."""
    return robot.transitions.lookup(a, b) is not None and _hardware_can(robot, a, b)


def loaded_start(robot: "Robot", states: Sequence[int], standing: int) -> list[int]:
    """``states`` (a gait to LOAD_GAIT) in the order that starts it well from ``standing``.

    The firmware starts a loaded gait at the step whose state the robot stands in, else at
    its first step, straight from where the robot stands: a loaded gait has no entry path.
    So the gait is unchanged when it visits ``standing``; else it is rotated to begin at its
    first state the robot can step into (allowed in the robot file, and a step the hardware
    can make) - the same cycle, from another phase. GaitError when it can step into none."""
    cycle = _open(states)
    if standing in cycle:
        return cycle
    for k, s in enumerate(cycle):
        if _can_step(robot, standing, s):
            return cycle[k:] + cycle[:k]
    table = robot.transitions
    raise GaitError(
        f"gait {_name(robot, cycle + cycle[:1])}: the robot stands in {table.label(standing)}, which the gait does "
        f"not visit, and no step from there into one of its states is allowed (the firmware would step straight "
        f"into {table.label(cycle[0])}); move the robot into one of its states first (proleg console)"
    )


def rest_start_warning(robot: "Robot", states: Sequence[int]) -> str | None:
    """A line for a gait loaded as ``states`` whose first step, started from rest, is one the
    robot cannot make (``loaded_start``): None when it visits the rest state or can step into
    its first state from there."""
    cycle = _open(states)
    if REST in cycle or _can_step(robot, REST, cycle[0]):
        return None
    table = robot.transitions
    try:
        better = loaded_start(robot, cycle, REST)
        fix = f"start it from one of its states, or load it from {table.label(better[0])}: " + " ".join(
            table.label(x) for x in better + better[:1])
    except GaitError:
        fix = "start it from one of its states"
    return (f"started from rest ({table.label(REST)}) this gait steps straight into {table.label(cycle[0])}, "
            f"{'forbidden in the robot file' if table.lookup(REST, cycle[0]) is None else 'a step the hardware cannot make'} "
            f"(a loaded gait has no entry path); {fix}")
