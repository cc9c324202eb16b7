"""The allowed transitions the robot's hardware cannot make, which learning leaves out.

A robot file's matrix may allow transitions that its limbs and coils cannot make: a step
that moves limbs of one shared coil apart, or raises some of them into a state the coil cannot
hold (``shared-actuator``), a step into a state in which a raised limb cannot reach its level
on the simulated body even with every coil at full stroke (``unreachable``;
``proleg.gait.feasibility.step_problems``, the errors the build refuses a gait 0 for), and any
transition out of such a state (the robot is never in it). A lab's guessed matrix often
allows them. Asked for one, the firmware heats until the state timeout (STATE_TIMEOUT on the
simulated robot, a cooked coil on a real one) and learning stopped there.

``Explorer`` plans its tours over ``makeable_robot`` (the table without them), the report names
them as not measured, and the learned robot file marks them ``"x"`` (a transition the robot
did make after all, measured in an older log, keeps its measurement).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..robot import Robot
from ..transitions import TransitionTable


def impossible(robot: Robot) -> dict[int, str]:
    """Edge index (in ``robot.transitions``) → why the hardware cannot make that transition."""
    from ..gait.feasibility import CANNOT_REACH, step_problems

    t = robot.transitions
    unreached = getattr(robot, "unreachable", {})
    out: dict[int, str] = {}
    for e, (a, b) in enumerate(zip(t.src.tolist(), t.dst.tolist())):
        if a in unreached:
            out[e] = f"it leaves state {t.label(a)}, {CANNOT_REACH}"
            continue
        errors = [what for _kind, severity, what in step_problems(robot, a, b) if severity == "error"]
        if errors:
            out[e] = errors[0]
    return out


def _kept(table: TransitionTable, drop) -> np.ndarray:
    """A mask over ``table``'s edges: False at the indices in ``drop``."""
    keep = np.ones(table.n_transitions, dtype=bool)
    keep[list(drop)] = False
    return keep


def without_edges(table: TransitionTable, drop) -> TransitionTable:
    """``table`` without the edges (indices) in ``drop``."""
    return table.restricted(_kept(table, drop))


def makeable_robot(robot: Robot) -> Robot:
    """``robot`` with only the transitions its hardware can make (``robot`` itself when it
    can make every one)."""
    drop = impossible(robot)
    if not drop:
        return robot
    keep = _kept(robot.transitions, drop)
    n_trials = None if robot.n_trials is None else np.asarray(robot.n_trials)[keep]
    return replace(robot, transitions=robot.transitions.restricted(keep), n_trials=n_trials)


def impossible_line(robot: Robot, drop: dict[int, str] | None = None, shown: int = 5) -> str | None:
    """``K of them impossible on this hardware (a->b, …; a->b: why)`` for the messages, or None."""
    drop = impossible(robot) if drop is None else drop
    if not drop:
        return None
    t = robot.transitions
    labels = [f"{t.label(int(t.src[e]))}->{t.label(int(t.dst[e]))}" for e in sorted(drop)]
    first = min(drop)
    names = ", ".join(labels[:shown]) + (f", … ({len(labels) - shown} more)" if len(labels) > shown else "")
    return (f"{len(drop)} of them impossible on this hardware, not asked for ({names}; {labels[0]}: "
            f"{drop[first]})")
