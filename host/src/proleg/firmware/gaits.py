"""Which gaits the firmware carries, and the selection that chose them.

``firmware_gaits`` returns the optimal gaits of both directions, every tie, as a
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

    gaits = {d: ordered(optimal_gaits(robot.transitions, objective, d, max_transitions).gaits) for d in DIRECTIONS}
    return FirmwareGaits(gaits, GaitSelection(objective, max_transitions))
