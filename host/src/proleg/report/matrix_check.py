"""Does a simulated run walk the way the robot file's matrix says its gait walks?

``proleg sim`` runs a gait the gait engine chose from the matrix; the physical plant does not
read the matrix, so a matrix that does not describe the body (hand-written, learned from a
run that passed through other states, or a 3-level limb that overshoots) gives a gait that
walks the other way, or not at all. The run itself succeeded, so this is a remark beside the
report, not a failure: ``sim`` says it and points to ``--measure-matrix``.

The matrix's promise per cycle is the gait's reward for one pass (``Gait.reward``; a cycle is
step 0 to step 0). In a length unit it is a length; in ``steps`` it is a length only on the table plant
(× ``[plant] step_mm``), and on the physical plant only its sign is a promise.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..robot_transitions import UNIT_MM

#: below this much per cycle (mm) a run "does not move", whatever the matrix's units (a promise of
#: less than this in mm: below SHORT_SHARE of it)
STILL_MM = 1e-3
#: a run in a length unit that makes less than this share of the promised length per cycle
SHORT_SHARE = 0.1
#: on the table plant, which moves by the matrix itself, a mean cycle further than this share
#: of the promise (plus 3 σ of its noise) from it: the plant made other transitions than the
#: gait's (a limb passing another level on the way; `unexpected_transitions`)
TABLE_SHARE = 0.25


@dataclass(frozen=True)
class MatrixCheck:
    promised: float        # the gait's reward for one pass, in the matrix's units
    units: str
    promised_mm: float | None  # the same in mm, where the units and the plant say what a unit is
    walked_mm: float       # mean per cycle, the plant's truth
    remark: str | None     # why the run does not agree with the matrix, or None

    def as_json(self) -> dict[str, Any]:
        return {"promised_per_cycle": self.promised, "units": self.units, "promised_mm": self.promised_mm,
                "agrees": self.remark is None, "remark": self.remark}


def check(robot: Any, plant: str, promised: float, cycles_mm: list[float], steps: int = 1) -> MatrixCheck | None:
    """The run's cycles against the promise (``steps``: the gait's transitions a cycle); None
    with fewer than two cycles (too few to say)."""
    if len(cycles_mm) < 2:
        return None
    units = robot.units
    if units in UNIT_MM:
        per_mm: float | None = UNIT_MM[units]
    else:
        per_mm = robot.plant.step_mm if plant == "table" else None
    promised_mm = promised * per_mm if per_mm is not None else None
    walked = sum(cycles_mm) / len(cycles_mm)
    # a promise of under STILL_MM a cycle (step_mm = 1e-9 on the table plant) is kept by moving
    # less than that: "still" is then what "short" is, a share of the promise
    still = min(STILL_MM, SHORT_SHARE * abs(promised_mm)) if promised_mm else STILL_MM
    remark = None
    if abs(walked) < still:
        remark = "did not move"
    elif promised * walked < 0:
        remark = "walked the other way"
    elif promised_mm is not None and abs(walked) < SHORT_SHARE * abs(promised_mm):
        remark = f"walked less than {SHORT_SHARE:.0%} of it"
    elif plant == "table" and promised_mm is not None and abs(walked - promised_mm) > (
            TABLE_SHARE * abs(promised_mm) + 3.0 * _cycle_noise_mm(robot, cycles_mm, steps)):
        remark = (f"walked {walked / promised_mm:.0%} of it on the table plant, which moves by the matrix: "
                  "the plant made other transitions than the gait's")
    return MatrixCheck(promised, units, promised_mm, walked, remark)


def _cycle_noise_mm(robot: Any, cycles_mm: list[float], steps: int) -> float:
    """σ of the table plant's noise (``[plant] noise_mm`` per transition) on the mean of the
    run's cycles of ``steps`` transitions each."""
    noise = float(getattr(robot.plant, "noise_mm", 0.0) or 0.0)
    return noise * (max(steps, 1) / len(cycles_mm)) ** 0.5


def remark_text(c: MatrixCheck) -> str:
    """One line for the text report."""
    promise = f"{c.promised_mm:+.2f} mm" if c.promised_mm is not None else f"{c.promised:+g} {c.units} (its sign)"
    return (f"NOTE: the matrix promises {promise} a cycle for this gait; the robot {c.remark} "
            f"({c.walked_mm:+.3f} mm a cycle). The matrix may not describe this body: "
            f"measure it (proleg sim ROBOT --measure-matrix) or learn it (proleg learn)")
