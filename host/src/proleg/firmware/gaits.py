"""Which gaits the firmware carries, and the selection that chose them.

``firmware_gaits`` returns the optimal gaits of both directions, every tie (at most
MAX_FIRMWARE_GAITS per direction, the best-ranked), as a
``FirmwareGaits`` mapping (``{"+x": (Gait, ...), "-x": (...)}``) that also names its
``GaitSelection`` (objective, directions, max_transitions, rank), so the rendered gait
table and proleg-build.json can say which inputs chose them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..robot import Robot

#: The rank of tied optimal gaits in the table: gait 0 is the one START runs by default.
RANK = "fewest opposing steps first, then search order"
DIRECTIONS = ("+x", "-x")
#: Tied optimal gaits the firmware carries per direction at most (the best-ranked ones).
MAX_FIRMWARE_GAITS = 32
#: The objective "total" enumerates every walk up to max_transitions; the gait engine
#: wants it given above this many states.
TOTAL_DEFAULT_MAX_STATES = 16


def default_max_transitions(robot: Robot, objective: str) -> int | None:
    """max_transitions when none is given: None (the engine's own default) up to 16 states;
    for the total objective on larger robots, one pass of every limb up through its levels
    and down again, 2 * sum(levels - 1) transitions (a whole-body wave)."""
    if objective != "total" or robot.n_states <= TOTAL_DEFAULT_MAX_STATES:
        return None
    return 2 * sum(k - 1 for k in robot.levels)


@dataclass(frozen=True)
class GaitSelection:
    objective: str
    max_transitions: int | None  # None = unbounded
    directions: tuple[str, ...] = DIRECTIONS
    rank: str = RANK

    def describe(self) -> str:
        """One line for generated headers."""
        mt = "unbounded" if self.max_transitions is None else str(self.max_transitions)
        return (
            f"objective {self.objective}, max_transitions {mt}, directions {' '.join(self.directions)}, "
            f"every optimal tie ranked {self.rank}"
        )

    def as_json(self) -> dict[str, Any]:
        return {
            "objective": self.objective,
            "max_transitions": self.max_transitions,
            "directions": list(self.directions),
            "rank": self.rank,
        }


class FirmwareGaits(dict):
    """``{direction: (Gait, ...)}`` plus the ``selection`` that produced it."""

    def __init__(self, gaits: dict, selection: GaitSelection):
        super().__init__(gaits)
        self.selection = selection


def firmware_gaits(robot: Robot, objective: str = "total", max_transitions: int | None = None) -> FirmwareGaits:
    """The optimal gaits the firmware carries, all ties, for +x and -x (possibly none).

    Ties whose steps each move limbs one way only come first (stable otherwise), so that
    gait 0, the one START and ``proleg sim`` run by default, is the easiest to make
    physically (``proleg.states.opposing_steps``)."""
    from ..gait import optimal_gaits
    from ..states import opposing_steps

    def ordered(gaits):
        return tuple(sorted(gaits, key=lambda g: len(opposing_steps(g.states, robot.levels))))

    if max_transitions is None:
        max_transitions = default_max_transitions(robot, objective)
    gaits = {
        d: ordered(optimal_gaits(robot.transitions, objective, d, max_transitions).gaits)[:MAX_FIRMWARE_GAITS]
        for d in DIRECTIONS
    }
    return FirmwareGaits(gaits, GaitSelection(objective, max_transitions))


#: Feasibility problems that mean the hardware cannot make the gait at all.
CANNOT_MAKE = ("shared-actuator", "no-entry")


def gait_warnings(robot: Robot, gaits: dict) -> list[str]:
    """What the hardware may not do in the firmware's gaits (proleg.gait.feasibility):
    one line per problem, for ``proleg build`` to print. BuildError when gait 0 of a
    direction (the one START runs by default) is one the hardware cannot make: a shared
    actuator moving its limbs apart, or no way in from rest over allowed transitions.
    A coil on longer than safety.max_on_ms (on-time, never-cools) stays a warning: the
    firmware's hold is bang-bang on psi and sma.c enforces the on-time limit and the
    cool-down (the paper's one-actuator R1 walks 10 11 10 with its coil held)."""
    from ..errors import BuildError
    from ..gait.feasibility import gait_problems

    out = []
    for d, gs in gaits.items():
        for i, g in enumerate(gs):
            problems = gait_problems(robot, g.states)
            errors = [p for p in problems if p.severity == "error" and p.kind in CANNOT_MAKE]
            if i == 0 and errors:
                raise BuildError(
                    f"robot {robot.name}: gait 0 of {d}, the one START runs, cannot run on this robot: "
                    f"{errors[0].message} (choose another objective or --max-transitions, or fix the robot file)"
                )
            out += [f"gait {i} of {d}: {p.severity}: {p.message}" for p in problems]
    return out


#: Steps a fallback gait may have at most (core/limbmap.c copies it into the loaded gait).
MAX_FALLBACK_STEPS = 16


def firmware_fallbacks(robot: Robot) -> dict[tuple[int, str], Any]:
    """Per (lost actuator index, direction): the fallback the firmware switches to by itself
    (proleg.limbloss.fallback), when it has a gait of at most MAX_FALLBACK_STEPS steps.
    Empty when ``[control] fallback = false`` or the robot has a single actuator."""
    from ..limbloss import fallback

    if not getattr(robot.control, "fallback", True) or len(robot.actuators) < 2:
        return {}
    out = {}
    for a in range(len(robot.actuators)):
        for d in DIRECTIONS:
            fb = fallback(robot, a, d)
            if fb.states is not None and len(fb.states) - 1 <= MAX_FALLBACK_STEPS:
                out[(a, d)] = fb
    return out


def fallback_lines(robot: Robot) -> list[str]:
    """What ``proleg build`` says about the fallbacks the firmware carries (or why none)."""
    if not getattr(robot.control, "fallback", True):
        return ["fallback gaits: off ([control] fallback = false)"]
    fbs = firmware_fallbacks(robot)
    if not fbs:
        return ["fallback gaits: none (one actuator only, or no single-actuator loss leaves a gait that moves it)"]
    out = []
    for (a, d), fb in sorted(fbs.items()):
        walk = " ".join(fb.table.label(s) for s in fb.states)
        amap = ", ".join(f"{limb.name}→{robot.actuators[x].name}" for limb, x in zip(robot.limbs, fb.actuator_map))
        out.append(f"fallback without {robot.actuators[a].name} ({d}): {walk} ({fb.mode}: {amap})")
    return out
