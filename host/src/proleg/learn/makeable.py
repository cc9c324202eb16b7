"""The allowed transitions learning leaves out, and the words that say so.

Three kinds for learning (``KINDS``; a fourth, ``not_made``, for a matrix measured on the simulated
body), each with the reason per transition (``Left``):

* ``impossible``: transitions the robot's hardware cannot make at all. A step that moves limbs
  of one shared coil apart, or raises some of them into a state the coil cannot hold
  (``shared-actuator``), a step into a state in which a raised limb cannot reach its level on
  the simulated body even with every coil at full stroke (``unreachable``;
  ``proleg.gait.feasibility.step_problems``, the errors the build refuses a gait 0 for), and
  any transition out of such a state (the robot is never in it). Never asked for.
* ``unholdable``: transitions into or out of a state the body model says the robot cannot
  hold (``Robot.unholdable``: a limb lifted by its raised neighbours past its level's edge, so
  it reads as another state), and steps it says the body cannot end (``Robot.blocked``): the
  gait check's ``unholdable`` and ``blocked`` errors, "expect a fault". Asked for one, the
  firmware heats a coil to the state timeout. Not asked for by default; the body is a model,
  so ``try_unholdable`` (``proleg learn --try-unholdable``) asks for them all the same.
* ``faulted``: transitions the robot faulted on while making them in an earlier run of the
  same trial log (``measure.Failure``; ``runner.Explorer`` records them, and leaves one out
  for the rest of its own run as soon as it faulted). ``retry_faulted`` asks for them again.

``Explorer`` plans its tours over ``makeable_robot`` (the table without them), the start
line and the report name them (``skipped_lines``, ``report_lines``), the report's table tags
their rows (``KINDS[kind].tag``), and the learned robot file marks them ``"x"``
(``file_comments``), all worded here. A transition the robot did make after all, measured
in the log (an older run, another option), keeps its measurement.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import numpy as np

from ..robot import Robot
from ..transitions import TransitionTable
from .measure import Failure


@dataclass(frozen=True)
class Left:
    """Why learning does not ask for a transition: ``kind`` (a key of ``KINDS``) and ``why``."""

    kind: str
    why: str


@dataclass(frozen=True)
class Words:
    start: str    # the start line's "K of them …"
    report: str   # the report's line under the table
    tag: str      # the report table's row
    comment: str  # the learned file's comment: "forbidden ("x") now: …"
    again: str = ""  # the option that asks for them (said in the start line and the report)


KINDS = {
    "impossible": Words(
        "impossible on this hardware, not asked for", "impossible on this hardware, not asked for",
        "impossible here",
        "the hardware cannot make them (a state a raised limb cannot reach, or a shared coil moving its limbs "
        "apart: the warnings when the robot file is loaded), so they were not asked for"),
    "unholdable": Words(
        "into or out of states the body cannot hold, not asked for",
        "into or out of states the body cannot hold, not asked for", "cannot hold",
        "the body model says the robot cannot hold the state they go to or come from, or cannot end them (the "
        "warnings when the robot file is loaded: a coil heated to the state timeout), so they were not asked for "
        "(proleg learn --try-unholdable asks for them)",
        "--try-unholdable asks for them"),
    "faulted": Words(
        "faulted on the robot before, not asked for again", "faulted on the robot, not asked for again",
        "faulted",
        "the robot faulted making them (the fault is in the trial log and the learn report), so they were not "
        "asked for again (proleg learn --retry-faulted asks for them)",
        "--retry-faulted asks for them again"),
    # proleg sim --measure-matrix --out of an unmeasured file (learnt: the simulated body's)
    "not_made": Words(
        "not made on the simulated body", "not made on the simulated body", "not made",
        "the idealised drive did not make them on the simulated body (proleg sim --measure-matrix: their start "
        "or end state was not reached), and an unmeasured matrix has no value of theirs to keep"),
}


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


def unholdable(robot: Robot) -> dict[int, str]:
    """Edge index → why the body model says the robot cannot hold the state the transition goes
    to or comes from (``Robot.unholdable``), or cannot end it (``Robot.blocked``)."""
    from ..gait.feasibility import blocked_why, unholdable_why

    t = robot.transitions
    held, blocked = getattr(robot, "unholdable", {}), getattr(robot, "blocked", {})
    out: dict[int, str] = {}
    for e, (a, b) in enumerate(zip(t.src.tolist(), t.dst.tolist())):
        if b in held:
            out[e] = f"goes to state {t.label(b)}, which the simulated body cannot hold: {unholdable_why(robot, b)}"
        elif a in held:
            out[e] = f"it leaves state {t.label(a)}, which the simulated body cannot hold (the robot is never in it)"
        elif (a, b) in blocked:
            out[e] = f"the simulated body cannot end it: {blocked_why(robot, a, b)}"
    return out


def faulted(table: TransitionTable, failures: Iterable[Failure]) -> dict[int, str]:
    """Edge index → the first fault recorded while making that transition (``failures``; a
    pair the table does not allow is ignored)."""
    out: dict[int, str] = {}
    for f in failures:
        try:
            e = table.lookup(table.index(f.src), table.index(f.dst))
        except (ValueError, KeyError):
            continue
        if e is not None and e not in out:
            out[e] = f.fault + (f" at firmware time {f.t_fault:g} s" if f.t_fault is not None else "")
    return out


def not_asked(robot: Robot, *, try_unholdable: bool = False, failures: Iterable[Failure] = (),
              retry_faulted: bool = False) -> dict[int, Left]:
    """Edge index → why learning leaves that transition out (the first kind of ``KINDS`` that
    applies): ``impossible`` always, ``unholdable`` unless ``try_unholdable``, ``faulted`` (from
    ``failures``, a log's) unless ``retry_faulted``."""
    out = {e: Left("impossible", why) for e, why in impossible(robot).items()}
    if not try_unholdable:
        out.update({e: Left("unholdable", why) for e, why in unholdable(robot).items() if e not in out})
    if not retry_faulted:
        out.update({e: Left("faulted", why) for e, why in faulted(robot.transitions, failures).items()
                    if e not in out})
    return out


def _kept(table: TransitionTable, drop) -> np.ndarray:
    """A mask over ``table``'s edges: False at the indices in ``drop``."""
    keep = np.ones(table.n_transitions, dtype=bool)
    keep[list(drop)] = False
    return keep


def without_edges(table: TransitionTable, drop) -> TransitionTable:
    """``table`` without the edges (indices) in ``drop``."""
    return table.restricted(_kept(table, drop))


def makeable_robot(robot: Robot, drop=None) -> Robot:
    """``robot`` without the transitions in ``drop`` (edge indices; default: those its
    hardware cannot make), or ``robot`` itself when there are none."""
    drop = impossible(robot) if drop is None else drop
    if not drop:
        return robot
    keep = _kept(robot.transitions, drop)
    n_trials = None if robot.n_trials is None else np.asarray(robot.n_trials)[keep]
    return replace(robot, transitions=robot.transitions.restricted(keep), n_trials=n_trials)


def _by_kind(drop: dict[int, Left]) -> list[tuple[str, list[int]]]:
    return [(kind, sorted(e for e, left in drop.items() if left.kind == kind)) for kind in KINDS
            if any(left.kind == kind for left in drop.values())]


def _names(table: TransitionTable, edges: list[int], shown: int, more: str = "") -> str:
    labels = [f"{table.label(int(table.src[e]))}->{table.label(int(table.dst[e]))}" for e in edges]
    return ", ".join(labels[:shown]) + (f", … ({len(labels) - shown} more{more})" if len(labels) > shown else "")


def _first(table: TransitionTable, drop: dict[int, Left], edges: list[int]) -> str:
    e = edges[0]
    return f"{table.label(int(table.src[e]))}->{table.label(int(table.dst[e]))}: {drop[e].why}"


def skipped_lines(robot: Robot, drop: dict[int, Left], shown: int = 5) -> list[str]:
    """One ``K of them impossible on this hardware, not asked for (a->b, …; a->b: why)`` per
    kind in ``drop``, for the messages."""
    t = robot.transitions
    out = []
    for kind, edges in _by_kind(drop):
        w = KINDS[kind]
        again = f"; {w.again}" if w.again else ""
        out.append(f"{len(edges)} of them {w.start} ({_names(t, edges, shown)}; {_first(t, drop, edges)}{again})")
    return out


def report_lines(table: TransitionTable, drop: dict[int, Left], shown: int = 10) -> list[str]:
    """The report's lines under its table, one per kind in ``drop``: ``impossible on this
    hardware, not asked for (marked "x" in the learned file): K of N: a->b, …; a->b: why``."""
    out = []
    for kind, edges in _by_kind(drop):
        w = KINDS[kind]
        again = f"; {w.again}" if w.again else ""
        out.append(f"{w.report} (marked \"x\" in the learned file): {len(edges)} of {table.n_transitions}: "
                   f"{_names(table, edges, shown)}; {_first(table, drop, edges)}{again}")
    return out


def file_comments(table: TransitionTable, drop: dict[int, Left]) -> list[str]:
    """The learned file's comment lines naming the transitions written "x", one per kind."""
    return [f"# forbidden (\"x\") now: {KINDS[kind].comment}: {_names(table, edges, len(edges))}"
            for kind, edges in _by_kind(drop)]
