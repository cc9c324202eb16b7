"""How steep a grade a robot's gait climbs on the physical plant: the number the robot file's
``[control] max_climb_deg`` wants (docs/calibration.md, "Too steep to climb").

``steepest_climb`` walks the gait with the idealised drive (true ψ, the firmware's duties, within
its safety envelope: ``drive.walk_within_envelope``) up ever steeper ground, by
bisection, and returns the steepest grade on which it still climbs: moves up the slope at
least ``drive.BARELY_MOVES`` (5 %) of its speed on the flat. Less is the knife edge between
climbing and sliding back, where a stick or a slip decides and 0.01° of shape changes the
answer (inchworm-3 made +0.008 mm a cycle, 3 % of its flat speed, from 4.25° to 5.5°, and
slid back at 5.75°: that is no grade it climbs). Bisection assumes a gait that does not climb a
grade does not climb any steeper one (true of every example robot measured half a degree at a
time, docs/calibration.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from ...robot_climb import MIN_CLIMB_DEG, ClimbLimit
from .drive import BARELY_MOVES, walk_within_envelope

#: The plant's steepest ground (conditions.py: incline_deg in −12..12).
TOP_DEG = 12.0
#: The bisection stops at this width (°).
RESOLUTION_DEG = 0.25
#: The grid a suggested max_climb_deg is rounded down to (at least robot_climb.MIN_CLIMB_DEG, the smallest it takes).
SUGGEST_STEP_DEG = 0.5


def climb_mm(robot: Any, states: Sequence[int], direction: str, grade_deg: float,
             conditions: Sequence[str] = ()) -> float | None:
    """How far up a grade of ``grade_deg`` (the ground rising in ``direction``) the idealised
    drive moves the robot a cycle walking ``states`` (mm, negative sliding back); None where a
    state is not reached or the envelope latches a fault."""
    from ..closed_loop import make_plant

    sign = 1 if direction == "+x" else -1
    plant = make_plant(robot, "physical", [*conditions, f"incline_deg={sign * grade_deg:g}"])
    mm = walk_within_envelope(robot, states, plant).mm_per_cycle
    return None if mm is None else sign * mm


def walks_up(robot: Any, states: Sequence[int], direction: str, grade_deg: float,
             conditions: Sequence[str] = (), *, floor_mm: float = 0.0) -> bool:
    """Does the idealised drive move the robot up a grade of ``grade_deg`` walking ``states``
    in ``direction``, by more than ``floor_mm`` a cycle?"""
    mm = climb_mm(robot, states, direction, grade_deg, conditions)
    return mm is not None and mm > floor_mm


def steepest_climb(robot: Any, states: Sequence[int], direction: str, conditions: Sequence[str] = (), *,
                   resolution_deg: float = RESOLUTION_DEG, top_deg: float = TOP_DEG) -> float | None:
    """The steepest grade (°, a multiple of ``resolution_deg``) the gait still climbs; None if
    it does not move ``direction`` even on the flat; ``top_deg`` if it climbs that too."""
    steps = top_deg / resolution_deg
    if abs(steps - round(steps)) > 1e-9:
        raise ValueError(f"top_deg {top_deg} is not a whole number of {resolution_deg}° steps")
    flat = climb_mm(robot, states, direction, 0.0, conditions)
    if flat is None or flat <= 0:
        return None
    floor = BARELY_MOVES * flat
    if walks_up(robot, states, direction, top_deg, conditions, floor_mm=floor):
        return top_deg
    lo, hi = 0, round(steps)  # in steps: climbs lo, not hi
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if walks_up(robot, states, direction, mid * resolution_deg, conditions, floor_mm=floor):
            lo = mid
        else:
            hi = mid
    return lo * resolution_deg


def suggested_limits(climbs: dict[str, Sequence[float | None]]) -> ClimbLimit | None:
    """``max_climb_deg`` (a ``robot_climb.ClimbLimit``) for each direction's gaits' steepest climbs
    (gait 0 first): per direction one limit per gait where they differ (each ``suggested_limit``
    of its own climb; a gait that does not move that way gets the smallest the firmware takes),
    else one number. A direction none of whose gaits moves takes the other's smallest (it has
    nothing to walk). None if no gait moves at all."""
    per: dict[str, tuple[float, ...] | None] = {}
    for d in ("+x", "-x"):
        got = climbs.get(d, ())
        per[d] = (tuple(suggested_limit([c]) or MIN_CLIMB_DEG for c in got)
                  if suggested_limit(got) is not None else None)
    if per["+x"] is None and per["-x"] is None:
        return None
    return ClimbLimit.of(per["+x"] if per["+x"] is not None else min(per["-x"]),
                         per["-x"] if per["-x"] is not None else min(per["+x"]))


def suggested_limit(climbs: Sequence[float | None]) -> float | None:
    """``max_climb_deg`` for these directions' steepest climbs: the smallest, rounded down to
    half a degree, at least the smallest the firmware takes (0.5°); None if no gait moves."""
    known = [c for c in climbs if c is not None]
    if not known:
        return None
    return max(MIN_CLIMB_DEG, math.floor(min(known) / SUGGEST_STEP_DEG) * SUGGEST_STEP_DEG)


def slope_warnings(robot: Any, plant: Any) -> list[str]:
    """A line when the run's ground (``incline_deg``) is steeper than the contacts' static
    friction holds the body on (``PhysicalPlant.standing_grip``): at rest, or in a state with every
    contact on its least grippy pad. A real robot slides downhill there without a coil heated;
    the plant moves the body only while its shape changes, so it stood still: R1 on 12° at
    ``friction=0.2`` (its soft pads' μ_s 0.2 < tan 12°) stopped with STATE_TIMEOUT and stayed
    put for the rest of the run, and nothing said that no robot would."""
    incline = plant.conditions.get("incline_deg")
    rest, weakest = plant.standing_grip()
    grade = math.tan(math.radians(abs(incline)))
    if grade <= weakest:
        return []
    fr = plant.conditions.get("friction")
    if grade > rest:
        where, mu = "at rest", rest
    else:
        where, mu = "with every contact on its least grippy pad", weakest
    return [f"{robot.path}: incline_deg {incline:g}° is steeper than the contacts' static friction holds the body on "
            f"{where} ({math.floor(100 * math.degrees(math.atan(mu))) / 100:g}° at friction {fr:g}): a real robot slides downhill there "
            f"with no coil heated; the physical plant (quasi-static) moves the body only while its shape changes, "
            f"so on this slope it stands where a robot slides, and its displacement is too far uphill"]
